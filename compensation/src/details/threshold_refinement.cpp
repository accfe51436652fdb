#include "details/threshold_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <optional>
#include <unsupported/Eigen/LevenbergMarquardt>
#include <vector>

#include "details/constrained_lsq.hpp"
#include "details/forward_difference.hpp"

namespace hystbench::compensation::details {

namespace {

// Refined thresholds stay at least this fraction of their starting grid's mean gap apart.
constexpr double kMinMeanGapFraction = 0.1;
constexpr double kInf = std::numeric_limits<double>::infinity();

// max - min of the fitted rows' input.
double input_excursion(const RefinementRecord& record) {
  if (record.end <= record.begin || record.end > record.u.size()) return 0.0;
  const auto [lo, hi] =
      std::minmax_element(record.u.begin() + static_cast<std::ptrdiff_t>(record.begin),
                          record.u.begin() + static_cast<std::ptrdiff_t>(record.end));
  return *hi - *lo;
}

// Thresholds <-> log-increments.
class Packing {
 public:
  Packing(const ModelStructure& s, const RefinementSettings& settings,
          const RefinementRecord& record)
      : base_(s) {
    plays_ = settings.plays && s.plays() >= 2 ? static_cast<Eigen::Index>(s.plays()) - 1 : 0;
    if (settings.dead_zones && s.has_dead_zones()) {
      zero_ = s.zero_index();
      pos_ = static_cast<Eigen::Index>(s.dead_zone_thresholds.size() - zero_ - 1);
      neg_ = static_cast<Eigen::Index>(zero_);
    }
    if (settings.asymmetry && s.kind == ModelKind::kCoupledPlayPi && s.cp_scale[1] > 0.0) {
      // rb free (ra follows in proportion, so ra <= rb stays true); rc > r as 1 + exp(theta)
      // when it is above r (rc = r is the plain rising play and stays so).
      scales_ = s.cp_scale[2] > 1.0 ? 2 : 1;
    }
    // A gap the search drives towards zero stays a gap (next_threshold), of at least a tenth of
    // the starting grid's mean gap: two thresholds that merge are one operator with a near-step
    // weight pair (+1000 / -994 on a 5 nm dead-zone gap, say), which fits a record's fast parts
    // to the last nanometre and makes an inverse that jumps there.
    auto floor_gap = [](const std::vector<double>& t) {
      if (t.size() < 2) return 0.0;
      const double span = t.back() - t.front();
      return std::max(min_threshold_gap(span),
                      kMinMeanGapFraction * span / static_cast<double>(t.size() - 1));
    };
    play_gap_ = floor_gap(s.play_thresholds);
    dz_gap_ = floor_gap(s.dead_zone_thresholds);
    // And at most one mean grid step beyond the starting grid's outermost threshold (half the
    // input range for the uniform plays): a play whose threshold exceeds half the range, or a
    // dead zone beyond the outputs, never acts, and is a constant that depends on where the
    // record began.
    const auto& r = s.play_thresholds;
    if (r.size() >= 2)
      play_top_ = r.back() + (r.back() - r.front()) / static_cast<double>(r.size() - 1);
    // And a floor gap below half the fitted part's input excursion: a play moves there on every
    // pass between the excursion's extremes, whatever its state when the fitted part began. At
    // half the excursion it never moves within the fitted part, and its weight, fitted to
    // nothing there, can flatten the model where the first sweep left it (a negative weight that
    // cancels the others' slope, whose inverse then fails its check;
    // ThresholdRefinement.EveryRefinedPlayMovesWithinTheFittedRows holds the gap).
    const double excursion = input_excursion(record);
    if (excursion > 0.0) play_top_ = std::min(play_top_, 0.5 * excursion - play_gap_);
    const auto& d = s.dead_zone_thresholds;
    if (s.has_dead_zones() && d.size() >= 2) {
      const std::size_t z = s.zero_index(), above = d.size() - 1 - z;
      if (above > 0) dz_top_pos_ = d.back() * (1.0 + 1.0 / static_cast<double>(above));
      if (z > 0) dz_top_neg_ = -d.front() * (1.0 + 1.0 / static_cast<double>(z));
    }
  }

  Eigen::Index size() const noexcept { return plays_ + pos_ + neg_ + scales_; }

  Eigen::VectorXd pack() const {
    Eigen::VectorXd theta(size());
    Eigen::Index k = 0;
    const auto& r = base_.play_thresholds;
    for (Eigen::Index i = 1; i <= plays_; ++i) theta[k++] = std::log(r[i] - r[i - 1]);
    const auto& d = base_.dead_zone_thresholds;
    for (Eigen::Index j = 1; j <= pos_; ++j) theta[k++] = std::log(d[zero_ + j] - d[zero_ + j - 1]);
    for (Eigen::Index j = 1; j <= neg_; ++j) theta[k++] = std::log(d[zero_ - j + 1] - d[zero_ - j]);
    if (scales_ > 0) theta[k++] = std::log(base_.cp_scale[1]);
    if (scales_ > 1) theta[k++] = std::log(base_.cp_scale[2] - 1.0);
    return theta;
  }

  ModelStructure unpack(const Eigen::VectorXd& theta) const {
    ModelStructure s = base_;
    Eigen::Index k = 0;
    auto& r = s.play_thresholds;
    for (Eigen::Index i = 1; i <= plays_; ++i)
      r[i] = next_threshold(r[i - 1], theta[k++], play_gap_, play_top_ - r[i - 1]);
    auto& d = s.dead_zone_thresholds;
    for (Eigen::Index j = 1; j <= pos_; ++j)
      d[zero_ + j] =
          next_threshold(d[zero_ + j - 1], theta[k++], dz_gap_, dz_top_pos_ - d[zero_ + j - 1]);
    for (Eigen::Index j = 1; j <= neg_; ++j)
      d[zero_ - j] =
          -next_threshold(-d[zero_ - j + 1], theta[k++], dz_gap_, dz_top_neg_ + d[zero_ - j + 1]);
    if (scales_ > 0) {
      s.cp_scale[1] = std::exp(theta[k++]);
      s.cp_scale[0] = base_.cp_scale[0] / base_.cp_scale[1] * s.cp_scale[1];
    }
    if (scales_ > 1) s.cp_scale[2] = 1.0 + std::exp(theta[k++]);
    return s;
  }

 private:
  ModelStructure base_;
  double play_gap_ = 0.0, dz_gap_ = 0.0;
  double play_top_ = kInf, dz_top_pos_ = kInf, dz_top_neg_ = kInf;  // outermost thresholds
  Eigen::Index plays_ = 0;
  std::size_t zero_ = 0;
  Eigen::Index pos_ = 0;
  Eigen::Index neg_ = 0;
  Eigen::Index scales_ = 0;
};

// The samples a refinement steps its models on: every one up to the record's end, or, where the
// structure's output depends on the input's path alone, sample 0, each residual row and each
// turning point of the input (thin_path()).
struct ResidualPath {
  std::vector<double> u, y;
  std::vector<std::size_t> sample;  // the record's sample of each
  std::vector<std::size_t> rows;    // where the residual rows are among them, in order
};

// A classical or modified PI without creep lags: rate-independent plays and memoryless dead
// zones. Along a monotone run of the input each play steps to the same state from the run's last
// sample alone (max and min are exact in floating point), so such a model's output at a kept
// sample is bit for bit the output stepped on every sample.
bool path_decides_output(const ModelStructure& s) {
  return (s.kind == ModelKind::kPi || s.kind == ModelKind::kModifiedPi) &&
         s.creep_time_constants.empty();
}

// Sample 0, the residual rows and the input's turning points (a sample after which the input
// moves the other way than it last moved; plateaus step nothing) up to the record's end.
ResidualPath thin_path(const RefinementRecord& rec) {
  ResidualPath p;
  int last_move = 0;  // -1, 0, +1: the sign of the last nonzero input step
  for (std::size_t k = 0; k < rec.end; ++k) {
    const bool row = k >= rec.begin && (k - rec.begin) % rec.stride == 0;
    const double next = k + 1 < rec.end ? rec.u[k + 1] - rec.u[k] : 0.0;
    const int move = (next > 0.0) - (next < 0.0);
    const bool turns = move != 0 && last_move != 0 && move != last_move;
    if (move != 0) last_move = move;
    if (k != 0 && !row && !turns) continue;
    if (row) p.rows.push_back(p.u.size());
    p.u.push_back(rec.u[k]);
    p.y.push_back(rec.y[k]);
    p.sample.push_back(k);
  }
  return p;
}

// fit_design() over a thinned path: the same rows, the operators stepped on its samples only.
BoundedLsqResult fit_on_path(Design& design, const ResidualPath& p) {
  NormalEquations ne(design.unknowns());
  design.reset(p.u[0]);
  std::size_t next_row = 0;
  for (std::size_t j = 0; j < p.u.size(); ++j) {
    design.set_sample(p.sample[j]);
    if (next_row < p.rows.size() && p.rows[next_row] == j) {
      ne.push(design.row(p.u[j], p.y[j], ne.row()));
      ++next_row;
    } else {
      design.skip(p.u[j]);
    }
  }
  return solve_design(design, ne);
}

// Output error of the structure with its weights fitted by constrained least squares; on `path`
// where one is given (path_decides_output() of the structure), else on every sample.
void output_residuals(const ModelStructure& s, const RefinementRecord& rec, double* f,
                      const ResidualPath* path = nullptr) {
  const std::size_t n = rec.residuals();
  try {
    Design design(s);
    if (path != nullptr) {
      const BoundedLsqResult fit = fit_on_path(design, *path);
      ActuatorModel model = design.build(fit.x);
      const std::vector<double> yhat = model.simulate(path->u, s.dt);
      const double drift = s.drift ? fit.x[design.drift_column()] : 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t j = path->rows[i];
        const double predicted =
            s.drift ? yhat[j] + drift * s.drift_time_s(path->sample[j]) : yhat[j];
        f[i] = path->y[j] - predicted;
      }
      return;
    }
    const BoundedLsqResult fit = fit_design(design, rec.u, rec.y, rec.begin, rec.end, rec.stride);
    ActuatorModel model = design.build(fit.x);
    std::vector<double> yhat = model.simulate(rec.u.first(rec.end), s.dt);
    if (s.drift) add_drift(s, fit.x[design.drift_column()], yhat);
    for (std::size_t i = 0, k = rec.begin; i < n; ++i, k += rec.stride) f[i] = rec.y[k] - yhat[k];
  } catch (const std::exception&) {
    // A structure the models reject (it cannot happen with positive slope bounds): make it
    // look bad rather than abort the search.
    for (std::size_t i = 0; i < n; ++i)
      f[i] = 1e3 * (1.0 + std::abs(rec.y[rec.begin + i * rec.stride]));
  }
}

struct Residuals : Eigen::DenseFunctor<double> {
  Residuals(const Packing& packing, const RefinementRecord& record, const ResidualPath* path,
            int* evaluations)
      : Eigen::DenseFunctor<double>(static_cast<int>(packing.size()),
                                    static_cast<int>(record.residuals())),
        packing_(packing),
        record_(record),
        path_(path),
        evaluations_(evaluations) {}

  int operator()(const InputType& theta, ValueType& f) const {
    ++*evaluations_;
    output_residuals(packing_.unpack(theta), record_, f.data(), path_);
    return 0;
  }

  // Forward differences; the plays are piecewise linear in their thresholds, so a small
  // fixed step in log-increment space is well inside one linear piece most of the time.
  int df(const InputType& theta, JacobianType& jac) const {
    forward_difference_jacobian(*this, theta, jac, 1e-4);
    return 0;
  }

  const Packing& packing_;
  const RefinementRecord& record_;
  const ResidualPath* path_;
  int* evaluations_;
};

double path_rmse(const ModelStructure& s, const RefinementRecord& record,
                 const ResidualPath* path) {
  Eigen::VectorXd f(static_cast<Eigen::Index>(record.residuals()));
  output_residuals(s, record, f.data(), path);
  return f.size() > 0 ? std::sqrt(f.squaredNorm() / static_cast<double>(f.size())) : 0.0;
}

}  // namespace

double next_threshold(double previous, double log_gap, double min_gap, double max_gap) noexcept {
  return previous + std::max(std::min(std::exp(log_gap), max_gap), min_gap);
}

double min_threshold_gap(double span) noexcept { return 1e-6 * std::max(std::abs(span), 1.0); }

double structure_rmse(const ModelStructure& s, const RefinementRecord& record) {
  return path_rmse(s, record, nullptr);
}

RefinementResult refine_structure(const ModelStructure& s, const RefinementRecord& full,
                                  const RefinementSettings& settings) {
  RefinementRecord record = full;
  const std::size_t rows = full.end > full.begin ? full.end - full.begin : 0;
  record.stride = std::max<std::size_t>(
      1, (rows + settings.max_rows - 1) / std::max<std::size_t>(1, settings.max_rows));
  RefinementResult out;
  out.structure = s;
  // Every threshold the search tries keeps the structure's kind and lags: one path serves all.
  std::optional<ResidualPath> path;
  if (path_decides_output(s) && record.end > record.begin) path = thin_path(record);
  const ResidualPath* on = path ? &*path : nullptr;
  out.initial_rmse = out.final_rmse = path_rmse(s, record, on);
  const Packing packing(s, settings, record);
  if (packing.size() == 0 || record.end <= record.begin) return out;

  Residuals functor(packing, record, on, &out.evaluations);
  Eigen::LevenbergMarquardt<Residuals> lm(functor);
  lm.setMaxfev(settings.max_iterations);
  lm.setFtol(1e-6);
  lm.setXtol(1e-6);
  Eigen::VectorXd theta = packing.pack();
  lm.minimize(theta);
  const ModelStructure refined = packing.unpack(theta);
  const double rmse = path_rmse(refined, record, on);
  if (rmse < out.initial_rmse) {
    out.structure = refined;
    out.final_rmse = rmse;
  }
  return out;
}

}  // namespace hystbench::compensation::details
