// Creep lags beside any family's hysteresis (CreepOperatorBank): fitted jointly with the
// weights, alternating with them where dead zones make the joint fit approximate; kept only
// where they lower the held-out error (or always, as the options ask).
#include <algorithm>
#include <limits>
#include <vector>

#include "details/constrained_lsq.hpp"
#include "details/identifier.hpp"
#include "hystbench/compensation/creep_operator_bank.hpp"

namespace hystbench::compensation::details::identification {

std::vector<double> Identifier::creep_time_constants() const {
  if (!o_.creep_time_constants_s.empty()) return o_.creep_time_constants_s;
  const double duration = r_.t.back() - r_.t.front();
  return log_spaced_time_constants(static_cast<std::size_t>(o_.creep_operators),
                                   std::max(0.05 * duration, 2.0 * r_.dt), 0.5 * duration);
}

void Identifier::add_creep(Candidate& c) {
  ModelStructure s = c.structure;
  s.creep_time_constants = creep_time_constants();
  // Joint linear fit: exact for PI / CPI (creep adds to the output); for MPI / RPI the
  // error model puts the lags before the dead zone, so it is only a starting point. The Preisach
  // plane chooses its output map again with the lags beside its cells (without them, its map
  // bends to the creep the record holds).
  Candidate best = s.kind == ModelKind::kPreisach ? plane_fit(s.creep_time_constants)
                                                  : evaluate(s, c.method + "+creep");
  if (best.structure.has_dead_zones()) {
    // Alternate: hysteresis on y - creep, creep gains on y - hysteresis (both linear).
    ModelStructure hs = best.structure;
    hs.creep_time_constants.clear();
    std::vector<double> gains(s.creep_time_constants.size(), 0.0);  // first pass: c's own H
    std::vector<double> y_adj(r_.n);
    const Eigen::Index K = static_cast<Eigen::Index>(gains.size());
    for (int iteration = 0; iteration < 4; ++iteration) {
      CreepOperatorBank bank({s.creep_time_constants, gains}, r_.dt);
      bank.reset(r_.ud[0]);
      for (std::size_t k = 0; k < r_.n; ++k) y_adj[k] = r_.y[k] - bank.step(r_.ud[k]);
      Design design(hs);
      const auto fit = details::fit_design(design, r_.ud, y_adj, r_.begin, r_.fit_end);
      auto hysteresis = design.build_hysteresis(fit.x);
      const double drift = hs.drift ? fit.x[design.drift_column()] : 0.0;
      hysteresis->reset(r_.ud[0]);
      details::NormalEquations ne(K);
      bank.reset(r_.ud[0]);
      for (std::size_t k = 0; k < r_.fit_end; ++k) {
        const double h = hysteresis->step(r_.ud[k]);
        bank.step(r_.ud[k]);
        if (k < r_.begin) continue;
        std::copy(bank.state().begin(), bank.state().end(), ne.row());
        ne.push(r_.y[k] - h - drift * hs.drift_time_s(k));
      }
      // Creep follows the move it answers: its lags' gains >= 0 (unbounded, long lags that are
      // near each other cancel in large opposite gains).
      const Eigen::VectorXd inf =
          Eigen::VectorXd::Constant(K, std::numeric_limits<double>::infinity());
      const Eigen::VectorXd g =
          details::solve_bounded_lsq(ne.gram(), ne.rhs(), Eigen::VectorXd::Zero(K), inf).x;
      gains.assign(g.data(), g.data() + K);
      Candidate alt;
      alt.structure = hs;
      alt.structure.creep_time_constants = s.creep_time_constants;
      alt.method = c.method + "+creep-alternating";
      alt.drift = drift;
      alt.model = ActuatorModel(design.build_hysteresis(fit.x));
      alt.model->set_creep(CreepParameters{s.creep_time_constants, gains});
      score(alt, r_);
      log_.push_back({s.kind, operators_of(hs), dead_zones_of(hs), r_.delay, alt.fit.rmse,
                      alt.heldout.rmse, alt.method});
      if (alt.fit.rmse < best.fit.rmse) best = std::move(alt);
    }
  }
  if (o_.creep_always || best.score() < c.score()) c = std::move(best);
}

}  // namespace hystbench::compensation::details::identification
