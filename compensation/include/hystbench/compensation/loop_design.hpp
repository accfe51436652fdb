#pragma once
// The feedback designed from measured frequency responses (loop shaping on every response at
// once): the controller is an integrator, with or without a proportional part (PI) and a
// low-frequency boost (feedback_controller.hpp), notch filters at the modes the responses show
// (at most two, wide enough for a mode that moves), and a second-order low-pass where the modes
// or the sensor's noise call for one. Each structure's
// integral gain is raised as far as every target holds on every response:
//   - the loop margins (loop_analysis.hpp): gain margin, phase margin, peak |S|, stability;
//   - robustness: stable, with a small margin left (variant_gain_margin_db,
//     variant_peak_sensitivity_db: the moved responses are estimates), with the responses' gain
//     changed by +/- gain_uncertainty, and each leading mode moved by +/- mode_uncertainty
//     (measured_modes.hpp);
//   - the sensor: the drive noise the feedback makes of the output's non-repeating part (each
//     response's output_noise_rms) at most output_noise_budget times that noise;
//   - a right-half-plane zero the responses cannot show (a rate law's, which acts only while
//     the stage moves: rhp_zero_hz), stable with the variants' margin on each response times
//     (1 - j f / rhp_zero_hz);
//   - an upper crossover from elsewhere, if given.
// The structure whose |S| reaches -20 dB last on its worst response is kept: the band where the
// loop takes out nine tenths of the feedforward's error; what stopped its gain from going
// higher (the first target a 10 % higher gain breaks) names what limits the bandwidth. check_loop()
// judges a given law (gains set by hand) the same way. Pure maths; allocates, about a second for
// four responses of 200 lines: not real-time.
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/feedback_controller.hpp"
#include "hystbench/compensation/loop_analysis.hpp"
#include "hystbench/compensation/measured_modes.hpp"
#include "hystbench/compensation/measured_response.hpp"

namespace hystbench::compensation {

struct LoopDesignOptions {
  double dt_s = 1e-4;  ///< the loop's period [s]
  LoopTargets targets;
  double gain_uncertainty = 0.3;              ///< stable for every gain within 1 -/+ this
  double mode_uncertainty = 0.2;              ///< and every mode moved by -/+ this
  double variant_gain_margin_db = 1.5;        ///< the margin those variants keep, at least
  double variant_peak_sensitivity_db = 12.0;  ///< their peak |S|, at most
  std::size_t max_notches = 2;                ///< at most ShapingFilter::kMaxNotches
  double output_noise_budget = 1.0;           ///< drive noise over output noise, at most
  double max_crossover_hz = 0.0;              ///< 0: none
  std::string max_crossover_reason;           ///< why, for the design's `limit`
  double rhp_zero_hz = 0.0;                   ///< 0: none
  std::string rhp_zero_reason;                ///< whose zero, for the check's words
  double output_limit = 1e300;                ///< the PID's clamp, +/- [output unit]
};

/// What a design's or a check's loop does on the responses.
struct LoopEvaluation {
  std::vector<LoopMargins> margins;     ///< on each response, in order
  bool meets_targets = false;           ///< every response meets every target
  bool robust = false;                  ///< stable on every variant of the responses
  bool quiet = false;                   ///< the drive noise within its budget
  double crossover_hz = 0.0;            ///< the lowest crossover over the responses
  double bandwidth_hz = 0.0;            ///< the lowest closed-loop bandwidth (|T|) over them
  double rejection_bandwidth_hz = 0.0;  ///< the lowest error-rejection bandwidth (|S|)
  double tenfold_rejection_hz = 0.0;    ///< the lowest frequency where |S| reaches -20 dB
  double drive_noise_rms = 0.0;         ///< the largest over them [output unit]
  double output_noise_rms = 0.0;        ///< the responses' largest output noise [output unit]
  /// The first target broken, in words ("" when none), its kind (mode, delay, sensitivity,
  /// robustness, sensor, rate_law) and frequency.
  std::string failure, failure_kind;
  double failure_hz = 0.0;
  bool ok() const noexcept { return meets_targets && robust && quiet; }
};

struct LoopDesign {
  FeedbackLaw law;
  LoopEvaluation evaluation;
  std::vector<MeasuredMode> modes;  ///< found in the responses
  std::string structure;            ///< e.g. "PI, notch at 3016 Hz, low-pass 2400 Hz"
  /// What stopped a higher gain: mode, delay, sensitivity, robustness, sensor, rate_law; and in
  /// words, with the margin it left.
  std::string limited_by, limit;
  bool found = false;  ///< false: no structure met the targets even at the lowest gain
};

/// Throws std::invalid_argument for no response, an invalid one or bad options.
LoopDesign design_loop(std::span<const MeasuredResponse> responses, const LoopDesignOptions& o);

/// The loop of `law` on the responses, judged as design_loop() judges its candidates.
LoopEvaluation check_loop(std::span<const MeasuredResponse> responses, const FeedbackLaw& law,
                          const LoopDesignOptions& o);

}  // namespace hystbench::compensation
