#include "diagnosis/details/baseline.hpp"

#include <cmath>
#include <limits>

#include "diagnosis/details/candidates.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/preisach_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr int kPlayGrid[] = {8, 12, 16, 24, 32};
constexpr double kBaselineParsimony = 0.01;

}  // namespace

PiBaseline fit_pi_baseline(const DiagnosisRecord& r) {
  std::vector<ExtensionFit> fits;
  double best = std::numeric_limits<double>::infinity();
  for (const int plays : kPlayGrid) {
    if (static_cast<std::size_t>(plays + 1) * 10 > r.split.fit_samples) break;
    ExtensionSpec spec;
    spec.structure = pi_structure(r, plays);
    fits.push_back(fit_extension(r, spec));
    best = std::min(best, fits.back().heldout.rmse);
  }
  if (fits.empty()) {
    ExtensionSpec spec;
    spec.structure = pi_structure(r, 4);
    fits.push_back(fit_extension(r, spec));
    best = fits.back().heldout.rmse;
  }
  PiBaseline out;
  out.finest_spec = fits.back().spec;
  out.finest_fit = fits.back();
  for (ExtensionFit& f : fits) {
    if (f.heldout.rmse <= best * (1.0 + kBaselineParsimony)) {
      out.spec = f.spec;
      out.fit = std::move(f);
      break;
    }
  }
  out.description =
      "classical PI identified on the fit part: " + std::to_string(out.spec.structure.plays()) +
      " plays uniform on 0.." + num(0.5 * (r.u_hi - r.u_lo)) + " " + r.units.input + " (order " +
      std::to_string(kPlayGrid[0]) + ".." + std::to_string(std::end(kPlayGrid)[-1]) +
      " chosen by held-out error; the extensions are built on the finest, " +
      std::to_string(out.finest_spec.structure.plays()) +
      " plays, so that no gain comes from the order)";
  return out;
}

ExtensionSpec spec_of_model(const ActuatorModel& model, const DiagnosisRecord& r) {
  ExtensionSpec spec;
  if (auto s = structure_of(model, r)) {
    spec.structure = std::move(*s);
  } else {
    spec.structure =
        pi_structure(r, static_cast<int>(std::max<std::size_t>(
                            4, model.valid() ? model.hysteresis().operator_count() : 0)));
  }
  spec.structure.dt = r.dt;
  spec.dynamics = model.dynamics();
  spec.delay_samples = model.delay_s() / r.dt;
  return spec;
}

std::string describe_model(const ActuatorModel& model) {
  if (!model.valid()) return "(none)";
  const HysteresisModel& h = model.hysteresis();
  std::string s(to_string(h.kind()));
  auto dead_zones = [](const DeadZoneParameters& d) {
    std::size_t zero = 0;
    while (zero < d.thresholds.size() && d.thresholds[zero] < 0.0) ++zero;
    return std::to_string(zero) + "+" + std::to_string(d.thresholds.size() - zero - 1) +
           " dead zones";
  };
  switch (h.kind()) {
    case ModelKind::kModifiedPi: {
      const auto& p = dynamic_cast<const ModifiedPiModel&>(h).parameters();
      s += ", " + std::to_string(p.play.thresholds.size()) + " plays, " + dead_zones(p.dead_zone);
      break;
    }
    case ModelKind::kRateDependentPi: {
      const auto& p = dynamic_cast<const RateDependentPiModel&>(h).parameters();
      s += ", " + std::to_string(p.base.play.thresholds.size()) + " plays, " +
           dead_zones(p.base.dead_zone) + ", rate-dependent up to " + num(p.max_rate) + "/s";
      break;
    }
    case ModelKind::kPreisach: {
      const auto& p = dynamic_cast<const PreisachModel&>(h).parameters();
      s += ", " + std::to_string(p.cells) + " x " + std::to_string(p.cells) + " cells, " +
           dead_zones(p.output_map) + " on its output";
      if (p.rate_law.active()) s += ", relays widening with |du/dt|";
      break;
    }
    default:
      s += ", " + std::to_string(h.operator_count()) + " operators";
  }
  if (model.creep()) {
    const auto& tau = model.creep()->time_constants_s;
    s += ", creep " + std::to_string(tau.size()) + " lags " + num(tau.front()) + ".." +
         num(tau.back()) + " s";
  }
  if (model.dynamics()) {
    s += ", dynamics " + num(model.dynamics()->natural_frequency_hz) + " Hz zeta " +
         num(model.dynamics()->damping_ratio);
  }
  if (model.delay_s() > 0.0) {
    s += ", delay " + num(model.delay_s() / model.sample_period()) + " samples (" +
         num(model.delay_s() * 1e3) + " ms)";
  }
  return s;
}

}  // namespace hystbench::compensation::details
