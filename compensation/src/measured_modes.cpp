#include "hystbench/compensation/measured_modes.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hystbench::compensation {

namespace {

constexpr double kProminenceDb = 3.0;  // a peak stands out of its neighbourhood by this
constexpr double kReachDb = -10.0;     // and reaches this close to the low-frequency gain
constexpr double kSameMode = 0.10;     // peaks this close in frequency are one mode

double db(double x) { return 20.0 * std::log10(std::max(x, 1e-300)); }

// A unit mode discretised for a held input, as a stage behind a DAC is: the response of
// SecondOrderDynamics at f, H(z) = z [1 0] (zI - Phi)^-1 Gam (its output is the state after the
// step).
std::complex<double> unit_mode(double f, double fn, double zeta, double dt) {
  const SecondOrderDynamics m({fn, zeta}, dt);
  const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * f * dt);
  const std::complex<double> det =
      (z - m.phi(0, 0)) * (z - m.phi(1, 1)) - m.phi(0, 1) * m.phi(1, 0);
  return z * ((z - m.phi(1, 1)) * m.gam(0) + m.phi(0, 1) * m.gam(1)) / det;
}

// Where the magnitude (dB, over the lines) falls `drop` below line i's, walking from i by
// `step`: interpolated in frequency; 0 when it does not within the response.
double half_power_frequency(const MeasuredResponse& r, const std::vector<double>& mag,
                            std::size_t i, int step, double drop) {
  const double level = mag[i] - drop;
  for (auto j = static_cast<std::ptrdiff_t>(i) + step;
       j >= 0 && j < static_cast<std::ptrdiff_t>(mag.size()); j += step) {
    const auto k = static_cast<std::size_t>(j);
    if (mag[k] <= level) {
      const auto k0 = static_cast<std::size_t>(j - step);
      const double w = (mag[k0] - level) / (mag[k0] - mag[k]);
      return r.frequency_hz[k0] + w * (r.frequency_hz[k] - r.frequency_hz[k0]);
    }
  }
  return 0.0;
}

std::vector<MeasuredMode> modes_of(const MeasuredResponse& r) {
  std::vector<MeasuredMode> out;
  const std::size_t n = r.size();
  if (n < 5) return out;
  const double g0 = db(low_frequency_gain(r));
  std::vector<double> mag(n);
  for (std::size_t i = 0; i < n; ++i) mag[i] = db(std::abs(r.response[i]));
  for (std::size_t i = 1; i + 1 < n; ++i) {
    if (!(mag[i] >= mag[i - 1] && mag[i] > mag[i + 1])) continue;
    // Prominence: down to the lowest point before a higher line, on each side.
    double left = mag[i], right = mag[i];
    for (std::size_t j = i; j-- > 0 && mag[j] <= mag[i];) left = std::min(left, mag[j]);
    for (std::size_t j = i + 1; j < n && mag[j] <= mag[i]; ++j) right = std::min(right, mag[j]);
    const double prominence = mag[i] - std::max(left, right);
    if (prominence < kProminenceDb || mag[i] - g0 < kReachDb) continue;
    const double f1 = half_power_frequency(r, mag, i, -1, 3.0);
    const double f2 = half_power_frequency(r, mag, i, +1, 3.0);
    const double fr = r.frequency_hz[i];
    double zeta = 0.0;
    if (f1 > 0.0 && f2 > 0.0) {
      zeta = (f2 - f1) / (2.0 * fr);
    } else if (f1 > 0.0 || f2 > 0.0) {
      zeta = std::abs(fr - (f1 > 0.0 ? f1 : f2)) / fr;
    } else {
      zeta = 0.5;
    }
    out.push_back({fr, std::clamp(zeta, 0.005, 1.0), mag[i] - g0});
  }
  return out;
}

}  // namespace

double low_frequency_gain(const MeasuredResponse& r) {
  if (r.size() == 0) return 0.0;
  const double top = r.frequency_hz.back();
  std::size_t count = 0;
  while (count < r.size() && r.frequency_hz[count] <= top / 20.0) ++count;
  count = std::clamp<std::size_t>(std::min(count, std::max<std::size_t>(r.size() / 10, 3)), 1,
                                  r.size());
  std::vector<double> mags(count);
  for (std::size_t i = 0; i < count; ++i) mags[i] = std::abs(r.response[i]);
  std::nth_element(mags.begin(), mags.begin() + static_cast<std::ptrdiff_t>(count / 2), mags.end());
  return mags[count / 2];
}

std::vector<MeasuredMode> measured_modes(std::span<const MeasuredResponse> responses) {
  struct Found {
    MeasuredMode mode;
    std::size_t response;
  };
  std::vector<Found> all;
  for (std::size_t i = 0; i < responses.size(); ++i) {
    for (const MeasuredMode& m : modes_of(responses[i])) all.push_back({m, i});
  }
  std::sort(all.begin(), all.end(),
            [](const Found& a, const Found& b) { return a.mode.peak_db > b.mode.peak_db; });
  // Each mode with the responses that show it: the highest peak stands for the others near it.
  std::vector<MeasuredMode> merged;
  std::vector<std::vector<bool>> shown_in;
  for (const Found& f : all) {
    std::size_t k = 0;
    while (k < merged.size() && std::abs(merged[k].frequency_hz - f.mode.frequency_hz) >
                                    kSameMode * merged[k].frequency_hz) {
      ++k;
    }
    if (k == merged.size()) {
      merged.push_back(f.mode);
      shown_in.emplace_back(responses.size(), false);
    }
    shown_in[k][f.response] = true;
  }
  // A stage's mode shows in most of its responses; a peak of one response alone is what a
  // nonlinearity's distortion made of that one's lines.
  const std::size_t needed = (responses.size() + 1) / 2;
  std::vector<MeasuredMode> out;
  for (std::size_t k = 0; k < merged.size(); ++k) {
    if (static_cast<std::size_t>(std::count(shown_in[k].begin(), shown_in[k].end(), true)) >=
        needed) {
      out.push_back(merged[k]);
    }
  }
  return out;
}

MeasuredResponse with_mode_moved(const MeasuredResponse& r, const MeasuredMode& m, double factor,
                                 double dt_s) {
  MeasuredResponse out = r;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double f = r.frequency_hz[i];
    out.response[i] *= unit_mode(f, m.frequency_hz * factor, m.damping_ratio, dt_s) /
                       unit_mode(f, m.frequency_hz, m.damping_ratio, dt_s);
  }
  return out;
}

}  // namespace hystbench::compensation
