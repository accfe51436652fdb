#pragma once
// Amplitude dependence in records of several inputs taken at several amplitudes (a mode that
// moves as the drive grows, which no operator before linear dynamics can do):
//  - fit_amplitude_schedule(): a Hammerstein model fitted on each record alone
//    (identify_mimo_hammerstein), the records ordered by amplitude (record_amplitude() of their
//    steady state), blended by an AmplitudeScheduledMimoModel.
//  - diagnose_amplitude_dependence(): each amplitude left out in turn, the baseline is one model
//    fitted on the other records pooled (the dynamics the same at every amplitude) and the
//    extension the schedule of the other records' local models; both simulated from rest on the
//    left-out record. The cause is named where the extension lowers that error by
//    kAmplitudeNamingGain or more, on the geometric mean over the amplitudes left out. It says
//    how each entry's frequency response and each dominant mode change from the lowest
//    amplitude to the highest.
// Units: the records'. Pure maths; allocates; not real-time safe.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "hystbench/compensation/amplitude_scheduled_model.hpp"
#include "hystbench/compensation/mimo_identification.hpp"

namespace hystbench::compensation {

/// The left-out gain (baseline rms / extended rms, geometric mean) that names the cause.
inline constexpr double kAmplitudeNamingGain = 1.2;
/// The schedule's amplitude window [s]: a few hundred cycles of a mode above 1 kHz, short
/// against a drive's change of level.
inline constexpr double kScheduleWindowS = 0.25;
/// Records whose amplitudes differ by less than this (relative) are one amplitude.
inline constexpr double kDistinctAmplitude = 0.05;

/// In one record, realizations whose amplitudes are more than this apart (relative, one to the
/// next by amplitude) are taken at different amplitudes.
inline constexpr double kAmplitudeGroupGap = 0.25;

using FitProgress = std::function<void(double, const std::string&)>;

/// The steady state's amplitude of a record: record_amplitude() over the periods after the first
/// of each realization (all of them with one period), the realizations' variances averaged.
double periodic_amplitude(const PeriodicRecord& record);

/// The realizations of one record by amplitude: groups of their indices, ascending, a new group
/// where the next realization's amplitude is more than kAmplitudeGroupGap above the last one's.
/// One group where the drive kept its amplitude.
std::vector<std::vector<std::size_t>> amplitude_groups(const PeriodicRecord& record);

/// The record of some of a record's realizations.
PeriodicRecord realizations_of(const PeriodicRecord& record,
                               const std::vector<std::size_t>& realizations);

/// rms over outputs and samples of y - simulate(u), each realization simulated from rest and
/// scored after its first period (all of it with one period) [output unit].
double simulation_rms(const std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)>& simulate,
                      const PeriodicRecord& record);

struct AmplitudeFit {
  std::vector<std::size_t> order;           ///< the records' indices, by ascending amplitude
  std::vector<double> amplitudes;           ///< ascending [input unit]
  std::vector<HammersteinFitResult> local;  ///< each record's own fit, in that order
  std::optional<AmplitudeScheduledMimoModel> model;  ///< always set on return
  std::vector<double> schedule_rms;  ///< per amplitude: the schedule on its record (simulation_rms)
  /// Per amplitude: the other amplitudes' schedule on its record (simulation_rms), the
  /// interpolation's own check.
  std::vector<double> left_out_rms;
};

struct AmplitudeFitOptions {
  HammersteinFitOptions local;  ///< each record's fit (its progress is not used)
  double window_s = kScheduleWindowS;
  FitProgress progress;  ///< fraction done in [0, 1] and what is being done
};

/// Two or more records of as many inputs and outputs at one sample period. Throws
/// std::invalid_argument naming the records that do not fit (two at one amplitude included).
AmplitudeFit fit_amplitude_schedule(const std::vector<PeriodicRecord>& records,
                                    const AmplitudeFitOptions& options = {});

struct AmplitudeLeftOut {
  double amplitude = 0.0;          ///< the record left out [input unit]
  std::size_t baseline_order = 0;  ///< of the model fitted on the others pooled
  double baseline_rms = 0.0;       ///< that model on the left-out record [output unit]
  double extended_rms = 0.0;       ///< the others' schedule on it (the fit's left_out_rms)
  double gain = 0.0;               ///< baseline / extended
};

/// A dominant lightly damped mode of the highest amplitude's model, and the nearest one of each
/// amplitude's model.
struct ModeShift {
  std::vector<double> frequency_hz;  ///< per amplitude, ascending
  std::vector<double> damping;       ///< per amplitude (zeta)
  std::vector<double> peak;          ///< per amplitude: the mode's peak |G| (Frobenius norm)
  double shift_percent = 0.0;        ///< frequency at the highest amplitude over the lowest, - 1
  double peak_ratio = 0.0;           ///< peak at the highest amplitude over the lowest
};

/// How one entry of the frequency response changes from the lowest amplitude to the highest,
/// over the excited band.
struct EntryChange {
  std::size_t output = 0, input = 0;
  double change = 0.0;  ///< rms |G_high - G_low| over rms |G_high|
  double at_hz = 0.0;   ///< where |G_high - G_low| is largest
};

struct AmplitudeDiagnosis {
  std::vector<double> amplitudes;          ///< ascending [input unit]
  std::vector<AmplitudeLeftOut> left_out;  ///< one per amplitude, in that order
  double gain = 0.0;                       ///< geometric mean of the left-out gains
  bool named = false;                      ///< gain >= kAmplitudeNamingGain
  std::vector<ModeShift> modes;            ///< by the highest amplitude's peak, largest first
  std::vector<EntryChange> entries;        ///< every entry, largest change first
};

/// Needs the fit of the same records and records of one period length and count. Throws
/// std::invalid_argument when they differ.
AmplitudeDiagnosis diagnose_amplitude_dependence(const std::vector<PeriodicRecord>& records,
                                                 const AmplitudeFit& fit,
                                                 const HammersteinFitOptions& options = {},
                                                 const FitProgress& progress = {});

}  // namespace hystbench::compensation
