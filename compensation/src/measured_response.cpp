#include "hystbench/compensation/measured_response.hpp"

#include <algorithm>
#include <cmath>
#include <unsupported/Eigen/FFT>

#include "details/validate.hpp"

namespace hystbench::compensation {

namespace {

// x less a straight line through its periods' means: the drift of a hold (creep, a thermal
// drift) moves every period's mean, a periodic part none of them.
std::vector<double> detrended(std::span<const double> x, std::size_t period) {
  const std::size_t periods = x.size() / period;
  std::vector<double> means(periods, 0.0);
  for (std::size_t k = 0; k < x.size(); ++k)
    means[k / period] += x[k] / static_cast<double>(period);
  // The least-squares line through (p, mean_p), its slope per sample.
  const double pm = (static_cast<double>(periods) - 1.0) / 2.0;
  double num = 0.0, den = 0.0, mean = 0.0;
  for (std::size_t p = 0; p < periods; ++p) {
    num += (static_cast<double>(p) - pm) * means[p];
    den += (static_cast<double>(p) - pm) * (static_cast<double>(p) - pm);
    mean += means[p] / static_cast<double>(periods);
  }
  const double slope = den > 0.0 ? num / den / static_cast<double>(period) : 0.0;
  const double centre = (static_cast<double>(x.size()) - static_cast<double>(period)) / 2.0;
  std::vector<double> out(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    // A period's mean sits at its start + (period - 1) / 2: the line through the means.
    out[k] = x[k] - mean -
             slope * (static_cast<double>(k) - centre - (static_cast<double>(period) - 1.0) / 2.0);
  }
  return out;
}

}  // namespace

MeasuredResponse estimate_response(std::span<const double> u, std::span<const double> y,
                                   std::size_t period, std::span<const std::size_t> lines,
                                   double rate_hz) {
  details::require(u.size() == y.size(), "frequency response: u and y differ in length");
  details::require(period >= 4 && u.size() % period == 0,
                   "frequency response: the record must be whole periods of at least 4 samples");
  const std::size_t periods = u.size() / period;
  details::require(periods >= 2, "frequency response: needs two periods or more to average");
  details::require(std::isfinite(rate_hz) && rate_hz > 0.0,
                   "frequency response: the rate must be > 0");
  details::require(!lines.empty(), "frequency response: no line to estimate");
  details::require_finite(u, "u");
  details::require_finite(y, "y");
  for (std::size_t i = 0; i < lines.size(); ++i) {
    details::require(lines[i] >= 1 && 2 * lines[i] < period && (i == 0 || lines[i] > lines[i - 1]),
                     "frequency response: line " + std::to_string(lines[i]) +
                         " is not an increasing DFT line in [1, period / 2)");
  }
  const std::vector<double> ud = detrended(u, period), yd = detrended(y, period);
  Eigen::FFT<double> fft;
  const std::size_t m = lines.size();
  // A line the input excites holds more than rounding: against the drive's own size.
  double u_peak = 0.0;
  for (const double v : ud) u_peak = std::max(u_peak, std::abs(v));
  const double excited = 1e-9 * u_peak * static_cast<double>(period) + 1e-300;
  std::vector<std::vector<std::complex<double>>> g(periods, std::vector<std::complex<double>>(m));
  std::vector<std::complex<double>> y_mean(m);
  std::vector<double> y_power(m, 0.0);
  std::vector<double> up(period), yp(period), y_avg(period, 0.0);
  std::vector<std::complex<double>> uf, yf;
  for (std::size_t p = 0; p < periods; ++p) {
    std::copy_n(ud.begin() + static_cast<std::ptrdiff_t>(p * period), period, up.begin());
    std::copy_n(yd.begin() + static_cast<std::ptrdiff_t>(p * period), period, yp.begin());
    for (std::size_t k = 0; k < period; ++k) y_avg[k] += yp[k] / static_cast<double>(periods);
    fft.fwd(uf, up);
    fft.fwd(yf, yp);
    for (std::size_t i = 0; i < m; ++i) {
      const std::complex<double> ui = uf[lines[i]];
      details::require(
          std::abs(ui) > excited,
          "frequency response: the input does not excite line " + std::to_string(lines[i]));
      g[p][i] = yf[lines[i]] / ui;
      y_mean[i] += yf[lines[i]] / static_cast<double>(periods);
      y_power[i] += std::norm(yf[lines[i]]) / static_cast<double>(periods);
    }
  }
  MeasuredResponse r;
  const double df = rate_hz / static_cast<double>(period);
  const auto np = static_cast<double>(periods);
  for (std::size_t i = 0; i < m; ++i) {
    std::complex<double> mean = 0.0;
    for (std::size_t p = 0; p < periods; ++p) mean += g[p][i] / np;
    double var = 0.0;
    for (std::size_t p = 0; p < periods; ++p) var += std::norm(g[p][i] - mean);
    var /= (np - 1.0) * np;  // of the mean
    r.frequency_hz.push_back(df * static_cast<double>(lines[i]));
    r.response.push_back(mean);
    r.noise.push_back(std::sqrt(var));
    // The input repeats exactly: the coherence is the share of the output's power that repeats.
    r.coherence.push_back(y_power[i] > 0.0 ? std::min(1.0, std::norm(y_mean[i]) / y_power[i])
                                           : 0.0);
  }
  double residual = 0.0;
  for (std::size_t k = 0; k < yd.size(); ++k) {
    const double e = yd[k] - y_avg[k % period];
    residual += e * e;
  }
  // The spread about the periodic mean, scaled up for the mean it was taken from.
  r.output_noise_rms = std::sqrt(residual / static_cast<double>(yd.size()) * np / (np - 1.0));
  return r;
}

void validate(const MeasuredResponse& r, const std::string& what) {
  const std::size_t n = r.frequency_hz.size();
  details::require(n > 0, what + ": no frequency");
  details::require(r.response.size() == n && r.noise.size() == n && r.coherence.size() == n,
                   what + ": frequency_hz, response, noise and coherence differ in length");
  // The message is built only where a value fails.
  auto fail = [&](const char* field, std::size_t i, const char* why) {
    throw std::invalid_argument(what + "." + field + "[" + std::to_string(i) + "] " + why);
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(r.frequency_hz[i]) && r.frequency_hz[i] > 0.0 &&
          (i == 0 || r.frequency_hz[i] > r.frequency_hz[i - 1]))) {
      fail("frequency_hz", i, "must be finite, > 0 and increasing");
    }
    if (!(std::isfinite(r.response[i].real()) && std::isfinite(r.response[i].imag()))) {
      fail("response", i, "is not finite");
    }
    if (!(std::isfinite(r.noise[i]) && r.noise[i] >= 0.0)) fail("noise", i, "must be >= 0");
    if (!(std::isfinite(r.coherence[i]) && r.coherence[i] >= 0.0 && r.coherence[i] <= 1.0)) {
      fail("coherence", i, "must be in [0, 1]");
    }
  }
}

}  // namespace hystbench::compensation
