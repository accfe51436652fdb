#pragma once
// The structural modes a measured frequency response shows: peaks of its magnitude that stand
// out of their neighbourhood by 3 dB or more and reach within 10 dB of the response's
// low-frequency gain, each with the damping its half-power band gives (one side when the other
// is out of the measured band). Peaks within 10 % of each other in several responses are one
// mode, the highest, and a mode is one that at least half of the responses show (a peak of one
// response alone is what a nonlinearity's distortion made of its lines). And a response with a mode
// moved (robustness checks): the measured response times a unit second-order mode at the new
// frequency over one at the measured frequency, both discretised for a held input at the loop's
// period, so everything else stays as measured. Pure maths; allocates: not real-time.
#include <span>
#include <vector>

#include "hystbench/compensation/measured_response.hpp"

namespace hystbench::compensation {

struct MeasuredMode {
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  double peak_db = 0.0;  ///< the peak over the response's low-frequency gain [dB]
};

/// The low-frequency gain of r: the median magnitude over its lowest tenth of lines (at least
/// three, at most its lines below a twentieth of its top line's frequency where it has them).
double low_frequency_gain(const MeasuredResponse& r);

/// The modes of every response, merged, highest peak first.
std::vector<MeasuredMode> measured_modes(std::span<const MeasuredResponse> responses);

/// r, measured at the loop period dt_s, with mode m moved to m.frequency_hz x factor (> 0).
MeasuredResponse with_mode_moved(const MeasuredResponse& r, const MeasuredMode& m, double factor,
                                 double dt_s);

}  // namespace hystbench::compensation
