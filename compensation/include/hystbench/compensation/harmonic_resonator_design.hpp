#pragma once
// The resonators a periodic reference's run adds to its designed loop (harmonic_resonators.hpp),
// chosen on the stage's measured frequency responses. For each harmonic k f of the reference's
// fundamental f (k <= max_harmonics, and beyond min_harmonics only where a tick turns the phase
// by at most max_tick_phase_deg; below max_frequency_fraction of the loop rate, below the lowest
// of `modes` and below every response's top line; a response is held at its lowest line below
// it), the loop C z^-1 P
// closed on each response gives S and what the resonator's output does to the error, G = z^-1 P S.
// A harmonic gets a resonator where:
//   - the loop alone leaves more than min_sensitivity of it (worst |S| over the responses): a
//     loop that amplifies it (|S| > 1 above its crossover) most of all;
//   - G's phase stays within max_phase_spread_deg of its mean on every response, on each with
//     its gain times 1 -/+ gain_uncertainty, and with each mode moved by -/+ mode_uncertainty
//     (measured_modes.hpp): the resonator converges while G's phase is off by less than 90
//     degrees, so a harmonic near a mode that may move is left out;
//   - 1 / max |G| is at most max_gain (where the stage with its loop answers too little, a
//     resonator would drive hard for little).
// Each kept resonator's c = exp(-j arg mean G) / max |G|: on the fastest response it converges
// in its settling's periods of the reference (2 / mu ticks), on the others slower. Between the
// harmonics a resonator's gain falls as mu over the distance, but several add up there: each
// settles from settle_periods on, and while |R G| on a variant, between the kept harmonics or up
// to three fundamentals beyond them, exceeds max_between (the loop's return difference 1 + L
// moved by that share, away from the harmonics themselves, where G's phase holds the loop), the
// resonator that gives most of it there settles twice as slowly, up to max_settle_periods. Where
// that does not hold it, the highest kept harmonic is left out, and so on until it holds (the
// lower harmonics carry more of a periodic error). Pure maths; allocates: not real-time.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/feedback_controller.hpp"
#include "hystbench/compensation/measured_modes.hpp"
#include "hystbench/compensation/measured_response.hpp"

namespace hystbench::compensation {

struct HarmonicResonatorOptions {
  double dt_s = 1e-4;              ///< the loop's period [s]
  double fundamental_hz = 0.0;     ///< the reference's, > 0 [Hz]
  std::size_t max_harmonics = 30;  ///< k at most
  /// Beyond the first min_harmonics, k f only where one tick more of delay (a stale reading, an
  /// exchange's jitter) turns the phase by at most this [deg]: 360 k f dt.
  double max_tick_phase_deg = 30.0;     ///< in (0, 180)
  std::size_t min_harmonics = 10;       ///< k up to this whatever a tick does to the phase
  double max_frequency_fraction = 0.4;  ///< k f at most this times the loop rate
  double min_sensitivity = 0.5;         ///< worst |S| above this
  double max_phase_spread_deg = 60.0;   ///< in (0, 90)
  double gain_uncertainty = 0.3;
  double mode_uncertainty = 0.2;
  double max_gain = 10.0;            ///< |c| at most
  double settle_periods = 2.0;       ///< the fastest convergence, in the reference's periods, > 0
  double max_settle_periods = 32.0;  ///< the slowest
  double max_between = 0.3;          ///< |R G| between the harmonics, at most
};

/// One harmonic as the design judged it.
struct HarmonicChoice {
  std::size_t harmonic = 0;  ///< k
  double frequency_hz = 0.0;
  double sensitivity = 0.0;  ///< worst |S| of the loop alone there
  double phase_spread_deg = 0.0;
  bool kept = false;
  double settle_periods = 0.0;  ///< a kept one's, in the reference's periods
  std::string why;              ///< why it is left out ("" when kept)
};

struct HarmonicResonatorDesign {
  HarmonicResonatorsSpec spec;  ///< empty: none kept
  std::vector<HarmonicChoice> harmonics;
  double settle_periods = 0.0;  ///< the slowest kept resonator's, in the reference's periods
  double between = 0.0;         ///< their largest |R G| between the harmonics
};

/// Throws std::invalid_argument for no response or bad options. `law` is the loop without
/// resonators; `modes` those the responses show; each resonator's amplitude is held within
/// law.pid.output_max.
HarmonicResonatorDesign design_harmonic_resonators(std::span<const MeasuredResponse> responses,
                                                   const FeedbackLaw& law,
                                                   std::span<const MeasuredMode> modes,
                                                   const HarmonicResonatorOptions& o);

}  // namespace hystbench::compensation
