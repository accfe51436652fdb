#pragma once
// What the diagnosis reads off a record besides the models (internals): input events
// (reversals, steps, holds) and rate, the noise floor of a residual, and binned residual
// profiles against an explanatory variable.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details {

/// Per-sample description of the input's motion.
struct InputEvents {
  std::vector<double> rate;                ///< du/dt over about 1 ms (>= 1 sample) [u/s]
  std::vector<signed char> direction;      ///< +1 rising, -1 falling, 0 holding
  std::vector<signed char> last_move;      ///< sign of the last excursion (0 before any)
  std::vector<double> since_event_s;       ///< time since the last reversal or step [s]
  std::vector<unsigned char> holding;      ///< input held (within 0.2 % of its span) >= 50 ms
  std::vector<unsigned char> step;         ///< a jump within one sample
  std::vector<std::size_t> event_samples;  ///< reversal turning points and steps, in order
  std::size_t reversals = 0;
  std::size_t steps = 0;
  std::size_t holds = 0;
  double hold_seconds = 0.0;  ///< total time the input holds [s]
};

/// Samples where the input jumps within one sample: by more than 1 % of its span and three
/// times the neighbouring increments.
std::vector<std::size_t> find_steps(std::span<const double> u);

/// Reversals are turning points of more than 0.5 % of the input span; a step is a one-sample
/// jump of more than 1 % of the span and three times the neighbouring increments.
InputEvents find_input_events(std::span<const double> u, double dt);

/// The median of v (the upper of the two middle values for an even count), `if_empty` for none.
double median(std::vector<double> v, double if_empty);

/// Noise rms of a residual from its second differences (robust: median absolute deviation),
/// so slow model errors and isolated transients hardly count.
double noise_rms(std::span<const double> residual);

/// The period of a repeating input in samples (a multisine or a repeated wave played at least
/// twice): the first autocorrelation peak after the first drop, accepted only when the input
/// repeats to within 2 % of its standard deviation over at least one whole period; 0 when the
/// input does not repeat.
std::size_t input_period(std::span<const double> u);

/// Noise rms of the output from its period-to-period difference, given the input's period:
/// y(k + P) - y(k) cancels everything the input explains, however fast; its second difference
/// also cancels slow drift and creep; what is left is noise (robust: median absolute deviation).
double periodic_noise_rms(std::span<const double> y, std::size_t period);

/// Binned means of `value` against `x` over the samples with use[k] (all when `use` is empty),
/// with `edges` the bin edges (increasing; values outside fall into the end bins).
ResidualProfile binned_profile(std::string variable, std::string label, std::span<const double> x,
                               std::span<const double> value, std::span<const unsigned char> use,
                               const std::vector<double>& edges);

/// `count` equal-width edges on [lo, hi]; `count` log-spaced edges on [lo, hi] (lo > 0);
/// quantile edges of x over the used samples.
std::vector<double> linear_edges(double lo, double hi, std::size_t bins);
std::vector<double> log_edges(double lo, double hi, std::size_t bins);
std::vector<double> quantile_edges(std::span<const double> x, std::span<const unsigned char> use,
                                   std::size_t bins);

/// Welch estimate of the response from `input` to `output` (Hann windows, 50 % overlap,
/// segments of a power of two between 256 and 16384 samples, about 8 per record); bins are
/// informative against white noise of rms `noise_rms` on the output (see FrequencyResponse).
FrequencyResponse frequency_response(std::span<const double> input, std::span<const double> output,
                                     double dt, double noise_rms);

}  // namespace hystbench::compensation::details
