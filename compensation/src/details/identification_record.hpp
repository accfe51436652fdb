#pragma once
// What every PI-family fit works on (identification internals): the record as the fits see it
// (input delayed, a skipped start, a fitted part and a held-out part) and a scored candidate
// model. Not real-time: allocates.
#include <Eigen/Dense>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "details/designs.hpp"
#include "hystbench/compensation/identification.hpp"

namespace hystbench::compensation::details::identification {

// The record as the fits see it: input delayed, fitted part and held-out part.
struct Record {
  std::span<const double> t, u, y;
  double dt = 1e-3;
  std::size_t n = 0;
  std::size_t begin = 0;    // first fitted sample (after the skipped transient)
  std::size_t fit_end = 0;  // held-out part is [fit_end, n)
  int delay = 0;
  std::vector<double> ud;     // u delayed by `delay` samples (u[0] before the start)
  double u_lo = 0, u_hi = 0;  // input range up to the held-out part (skipped start included)
  double y_lo = 0, y_hi = 0;  // output range over the fitted part
  double drift_t0_s = 0.0;    // FitOptions::drift: the drift line's zero, mid fitted part [s]

  void set_delay(int d);
};

// The record split as the options ask (held-out fraction, skipped start), undelayed. Throws
// std::invalid_argument when too few samples are left to fit or the fitted part is constant.
Record make_record(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                   const FitOptions& o);

struct Candidate {
  ModelStructure structure;
  Eigen::VectorXd x;
  std::optional<ActuatorModel> model;
  ErrorStats fit, heldout;
  std::string method;
  /// FitOptions::drift: the record's drift fitted with the weights [output unit / s]; no part
  /// of the model, added to its output where it is scored.
  double drift = 0.0;

  double score() const { return heldout.samples > 0 ? heldout.rmse : fit.rmse; }
};

// Simulates the model (no delay: the record's input is already delayed) and scores it.
// The slope bounds make every fitted model invertible; that is checked, never assumed: a model
// that fails the check scores +inf and cannot be chosen.
void score(Candidate& c, const Record& r);

inline int dead_zones_of(const ModelStructure& s) {
  return s.has_dead_zones() ? static_cast<int>(s.dead_zone_thresholds.size() / 2) : 0;
}

// Plays, or the Preisach plane's cells per side.
inline int operators_of(const ModelStructure& s) {
  return static_cast<int>(s.kind == ModelKind::kPreisach ? s.preisach_cells : s.plays());
}

}  // namespace hystbench::compensation::details::identification
