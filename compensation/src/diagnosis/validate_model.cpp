// A model's error on a record it was not fitted on (validate_model, diagnosis.hpp): scored after
// the record's start-up, the mean error apart.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "details/record_startup.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation {

ValidationScore validate_model(ActuatorModel model, std::span<const double> u,
                               std::span<const double> y, double dt) {
  if (u.size() != y.size() || u.size() < 2 || !(dt > 0.0)) {
    throw std::invalid_argument("validate_model: u and y need equal lengths >= 2 and dt > 0");
  }
  const std::vector<double> yhat = model.simulate(u, dt);
  ValidationScore v;
  v.skipped = details::startup_samples(u, u.size() / 4);
  v.samples = u.size() - v.skipped;
  const auto n = static_cast<double>(v.samples);
  for (std::size_t k = v.skipped; k < u.size(); ++k) v.offset += (y[k] - yhat[k]) / n;
  double square = 0.0;
  for (std::size_t k = v.skipped; k < u.size(); ++k) {
    const double e = y[k] - yhat[k] - v.offset;
    square += e * e;
    v.max_abs = std::max(v.max_abs, std::abs(e));
  }
  v.rmse = std::sqrt(square / n);
  return v;
}

}  // namespace hystbench::compensation
