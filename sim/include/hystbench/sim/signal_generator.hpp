#pragma once
// Reference and excitation signals as functions of time. Every kind is
//   value(t) = offset + amplitude * shape(t),
// with shape in [-1, 1] for the periodic kinds and the given levels or samples for `steps` and
// `csv` (amplitude 1, offset 0 keep them as given). Units are the caller's (V or µm), t in s,
// t >= 0 (earlier times read as t = 0 for the kinds with a finite duration).
// make_signal_generator() allocates and throws; value() is real-time safe (no allocation,
// no exceptions; O(1), or O(log n) for steps and csv).
#include <limits>
#include <memory>
#include <string_view>
#include <vector>

namespace hystbench::sim {

enum class SignalKind {
  kSine,            ///< sin(2 pi f t + phase)
  kDecayingSine,    ///< (1 - t/T) sin(...), or |sin| when rectified (multilayer paper, eq. 12)
  kTriangle,        ///< constant-rate ramps; same phase convention as the sine (0 at t = 0, rising)
  kSawtooth,        ///< rising ramp from -1 to 1, sharp fall; 0 at phase 0
  kStep,            ///< a square wave: the sine's sign, each edge a move over rise_s
  kSteps,           ///< levels held for their hold times
  kMultiFrequency,  ///< superposed amplitude-modulated sines (rate-dependent paper: 1, 10, 19 Hz)
  kChirp,           ///< linear sweep frequency_hz -> end_frequency_hz over duration_s
  kSamples,         ///< (t, value) samples, e.g. a CSV loaded by the caller; linear interpolation
};

/// "sine", "decaying_sine", "triangle", "sawtooth", "step", "steps", "multi_frequency", "chirp",
/// "csv".
std::string_view to_string(SignalKind kind) noexcept;
/// Throws std::invalid_argument listing the valid names.
SignalKind signal_kind_from_string(std::string_view name);

struct StepLevel {
  double level = 0.0;   ///< shape value while held
  double hold_s = 1.0;  ///< > 0 [s]
};

struct TimedSample {
  double t_s = 0.0;  ///< strictly increasing across the samples [s]
  double value = 0.0;
};

inline constexpr double kInfiniteDuration = std::numeric_limits<double>::infinity();

struct SignalSpec {
  SignalKind kind = SignalKind::kSine;
  double amplitude = 1.0;  ///< peak of the shape (not peak-to-peak)
  double offset = 0.0;
  double frequency_hz = 1.0;  ///< > 0; chirp: start frequency
  double phase_rad = 0.0;     ///< sine, decaying_sine, triangle, sawtooth, step
  /// [s]; decaying_sine and chirp need it finite; periodic kinds may be infinite.
  /// steps and csv ignore it (their levels and samples define the duration).
  double duration_s = kInfiniteDuration;

  bool rectified = false;  ///< decaying_sine: |sin| (all loops share the lower turning point)
  /// step: each edge moves along a minimum-jerk curve 10 x^3 - 15 x^4 + 6 x^5 over this long
  /// [s], from its edge on (0: a jump); at most a quarter period.
  double rise_s = 0.0;
  double end_frequency_hz = 10.0;  ///< chirp: frequency at duration_s (> 0); held afterwards
  std::vector<StepLevel> steps;    ///< steps: the last level holds after the sequence
  bool repeat_steps = false;       ///< steps: loop the sequence (infinite duration)
  /// multi_frequency: component k is 0.5 (1 - cos(2 pi f_mod t + 2 pi k / K)) sin(2 pi f_k t),
  /// summed and divided by K: envelopes take turns, |shape| <= 1.
  std::vector<double> component_frequencies_hz = {1.0, 10.0, 19.0};
  double modulation_frequency_hz = 0.25;  ///< multi_frequency: f_mod (> 0)
  std::vector<TimedSample> samples;       ///< csv: held before the first and after the last
};

class SignalGenerator {
 public:
  virtual ~SignalGenerator() = default;
  /// Value at time t_s [s]. Real-time safe.
  virtual double value(double t_s) const noexcept = 0;
  /// Length of the signal [s]; kInfiniteDuration for endless periodic signals.
  virtual double duration_s() const noexcept = 0;
};

/// Validates the spec for its kind; throws std::invalid_argument naming the field.
std::unique_ptr<SignalGenerator> make_signal_generator(const SignalSpec& spec);

/// A signal given on a uniform grid: values[k] at t = k dt_s, linear in between, the ends held
/// (a user's trajectory resampled to the loop rate). duration = (n - 1) dt_s. Throws
/// std::invalid_argument for no values, a non-finite value or dt_s <= 0.
std::unique_ptr<SignalGenerator> make_uniform_signal(std::vector<double> values, double dt_s);

/// value(k dt) for k = 0 .. n-1, n = round(duration / dt): the end point is left out, so
/// consecutive signals concatenate. duration_s < 0 takes the generator's, which must then be
/// finite. Throws std::invalid_argument for dt <= 0 or an infinite duration.
std::vector<double> sample_signal(const SignalGenerator& generator, double dt_s,
                                  double duration_s = -1.0);

}  // namespace hystbench::sim
