#pragma once
// Feedforward compensators: given a desired output y_ref, the input u that makes the model give it.
// Every inverse starts from the state the model is in when the inverse is built (so simulate the
// model through the actuator's known history first), or from reset(u0).
// step() is real-time safe (no allocation, no exceptions, bounded work).
#include <algorithm>
#include <memory>
#include <span>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/rate_estimator.hpp"

namespace hystbench::compensation {

class InverseModel {
 public:
  virtual ~InverseModel() = default;
  /// Returns the input u for desired output y_ref [output unit -> input unit].
  virtual double step(double y_ref) noexcept = 0;
  /// How many targets ahead this inverse can use (0: none). When > 0 the caller may call
  /// step_previewed() instead of step().
  virtual std::size_t preview_samples() const noexcept { return 0; }
  /// step() given the targets of this tick (targets[0]) and of the ticks ahead (targets[j] is
  /// j ticks ahead; at most preview_samples() values, at least one).
  virtual double step_previewed(std::span<const double> targets) noexcept {
    return step(targets.front());
  }
  /// State consistent with the model relaxed at input u0 (ActuatorModel::reset(u0)).
  virtual void reset(double u0) noexcept = 0;
  virtual std::unique_ptr<InverseModel> clone() const = 0;
};

/// An input range [min, max] for an analytic inverse; empty (min >= max) when unbounded.
struct InputRange {
  double min = 0.0;  ///< [input unit]
  double max = 0.0;  ///< [input unit]
  bool bounded() const noexcept { return min < max; }
};

namespace details {
/// The forward model beside an analytic inverse with a bounded range, stepped with every drive
/// the inverse gives (unbounded: not stepped, the drive is the inverse's).
/// A target beyond what the input range reaches from the present state becomes the output at
/// the bound, so the inverse saturates there instead of winding its state up beyond the range
/// (where a branch is nearly flat its inverse's slope is huge: a target just below reach asks
/// for hundreds of volts, and the inverse's memory then no longer matches the actuator's).
template <typename Model>
class ReachableTarget {
 public:
  ReachableTarget(const Model& model, InputRange range) : forward_(model), range_(range) {}
  /// The drive invert(y) gives for y_ref limited to [output at range.min, output at
  /// range.max] from the present state (a target at or beyond one gives that bound exactly),
  /// applied to the forward model.
  template <typename Invert>
  double step(double y_ref, Invert invert) noexcept {
    if (!range_.bounded()) return invert(y_ref);
    double u = 0.0;
    if (const double lo = forward_.peek(range_.min); y_ref <= lo) {
      invert(lo);
      u = range_.min;
    } else if (const double hi = forward_.peek(range_.max); y_ref >= hi) {
      invert(hi);
      u = range_.max;
    } else {
      u = std::clamp(invert(y_ref), range_.min, range_.max);
    }
    forward_.step(u);
    return u;
  }
  void reset(double u0) noexcept {
    if (range_.bounded()) forward_.reset(u0);
  }

 private:
  Model forward_;
  InputRange range_;
};
}  // namespace details

/// Analytic inverse of a classical PI (itself a PI on y - offset). Throws NotInvertibleError.
/// With a bounded `range` the drive saturates at its bounds (details::ReachableTarget).
class PiInverse final : public InverseModel {
 public:
  explicit PiInverse(const PiModel& model, InputRange range = {});
  double step(double y_ref) noexcept override;
  void reset(double u0) noexcept override;
  std::unique_ptr<InverseModel> clone() const override;
  const PiParameters& inverse_parameters() const noexcept { return inv_.parameters(); }

 private:
  PiParameters model_;
  PiModel inv_;
  details::ReachableTarget<PiModel> reach_;
};

/// Analytic inverse of a modified PI: u = PI^-1[ S^-1[y - center] + center ].
/// With a bounded `range` the drive saturates at its bounds (details::ReachableTarget).
class ModifiedPiInverse final : public InverseModel {
 public:
  explicit ModifiedPiInverse(const ModifiedPiModel& model, InputRange range = {});
  double step(double y_ref) noexcept override;
  void reset(double u0) noexcept override;
  std::unique_ptr<InverseModel> clone() const override;

 private:
  double center_;
  DeadZoneSuperposition dz_inv_;
  PiInverse pi_inv_;
  details::ReachableTarget<ModifiedPiModel> reach_;
};

/// Numeric inverse for any static model (hysteresis + creep): per sample, brackets the input
/// u in [input_min, input_max] with model.peek_static(u) = y_ref and refines it (regula falsi
/// with bisection safeguard, at most `max_iterations`), then steps the internal model copy.
/// Beyond the reachable range the input saturates at the bound.
/// A rate-dependent model with |du/dt| is solved at an input rate predicted from the reference,
/// never from the drive being solved for (that feedback made the drive chatter, and on a falling
/// branch the exact own-rate inverse is unstable): the rate-free modified PI's inverse follows the
/// reference, its drive's rate r_0 (the model's rate filter) is scaled to the rate-dependent
/// map's larger slope, r = r_0 W_n(0) / W_n(r) (W_n the total cumulative play weight), and the
/// drive is solved at r. Every step is a function of the reference alone.
/// With the targets ahead (step_previewed(), a per-sample rate law, rate_filter_s = 0) the
/// rate-dependent drive is solved where the rate law makes the inversion well posed: rising,
/// the output grows with u and with its own rate, so the drive is solved at its own per-sample
/// rate (exact, stable forward in time); falling, the faster fall raises the output, the forward
/// solution is unstable, and the drive is integrated backwards from the end of the falling run
/// ahead (rate 0 at a reversal in the window), rate = rate_for_output(u, y) per sample, which
/// converges within a few time constants F_r / s of the rate law. Where a falling run starts,
/// the drive joins that solution over kFallingBlendS instead of jumping (a jump is a one-tick
/// rate spike to the per-sample law).
/// The signed rate law (the paper's eq. 16) with weights that grow with the rate has no such
/// asymmetry: step() solves the drive at its own filtered rate on both branches, exact and
/// stable forward in time, and needs no targets ahead.
class NumericInverse final : public InverseModel {
 public:
  struct Options {
    double input_min = 0.0;    ///< bracket bounds [input unit]; default: the model's
    double input_max = 0.0;    ///< identification range (used when min >= max)
    double tolerance = 1e-12;  ///< relative to the output range
    int max_iterations = 80;
  };
  NumericInverse(const ActuatorModel& model, Options options);
  explicit NumericInverse(const ActuatorModel& model) : NumericInverse(model, Options{}) {}
  NumericInverse(const NumericInverse& other);
  NumericInverse& operator=(const NumericInverse&) = delete;
  double step(double y_ref) noexcept override;
  std::size_t preview_samples() const noexcept override { return window_; }
  double step_previewed(std::span<const double> targets) noexcept override;
  void reset(double u0) noexcept override;
  std::unique_ptr<InverseModel> clone() const override;

  /// Look-ahead of step_previewed() [s] (rate-dependent models with a per-sample rate law).
  static constexpr double kPreviewS = 0.03;
  /// Time over which a falling run's drive joins the backward solution [s].
  static constexpr double kFallingBlendS = 0.005;

 private:
  /// The drive of a falling run at this tick: integrated backwards from the run's end.
  double falling_drive(std::span<const double> targets) const noexcept;
  /// The input near u_start with model.peek_static_at_rate(u, rate) = y_ref (or the bound).
  double solve(const ActuatorModel& model, double y_ref, double u_start,
               double rate) const noexcept;
  /// The input near u_start with output(u) = y_ref (or the bound), output increasing in u.
  template <typename Output>
  double solve_with(double y_ref, double u_start, Output output) const noexcept;

  ActuatorModel model_;
  Options opt_;
  double u_prev_ = 0.0;
  double y_tol_ = 1e-12;
  // Rate-dependent models only: the rate-free inverse and its drive's rate; total cumulative
  // weight W_n(r) = total_ + total_slope_ r.
  std::unique_ptr<InverseModel> rate_free_;
  RateEstimator rate_free_rate_;
  double total_ = 0.0, total_slope_ = 0.0, max_rate_ = 0.0;
  bool signed_ = false;       // the signed rate law
  double u_free_prev_ = 0.0;  // signed law: the rate-free inverse's last drive
  bool own_rate_ = false;     // signed, weights growing with rate: step() at its own rate
  // step_previewed(): look-ahead in samples (0 = not available), and the falling run's state.
  std::size_t window_ = 0;
  double blend_ = 1.0;    // per-tick share of the gap to the backward solution closed
  double w_prev_ = 0.0;   // the backward solution's drive at the last tick
  bool falling_ = false;  // the last tick was in a falling run
};

/// Inverse multiplicative structure (classical-PI paper, Theorem 3.1), generalised with a
/// nominal gain g so that y and u may have different units:
///   u(k) = u(k-1) + (y_ref(k) - y_model(k-1)) / g,   y_model(k-1) = H[u](k-1),
/// then, for a rate-independent model, u <- u + (y_ref(k) - H[u]) / g repeated within the tick
/// (at most kMaxIterations passes, each one model step; hystbench-bench times them) until it
/// settles: the implicit equation solved, not its one-tick-delayed form. A thresholds rate law is
/// iterated the same way, at the drive's own rate where the output still grows with it, else at the
/// rate its rate-free self's drive (the same structure on the law's modified PI) predicts: one pass
/// a tick through widening thresholds chatters. Needs no inverse parameters: it runs the model
/// itself in feedback. step() is real-time safe.
class InverseMultiplicativeCompensator final : public InverseModel {
 public:
  /// gain <= 0 selects the steepest local slope of the model's major loop over its
  /// identification range (stable for every local slope; see the .cpp).
  explicit InverseMultiplicativeCompensator(const ActuatorModel& model, double gain = 0.0);
  InverseMultiplicativeCompensator(const InverseMultiplicativeCompensator& other);
  double step(double y_ref) noexcept override;
  void reset(double u0) noexcept override;
  std::unique_ptr<InverseModel> clone() const override;
  double gain() const noexcept { return gain_; }

 private:
  static constexpr int kMaxIterations = 256;
  ActuatorModel model_;
  double gain_;
  double u_prev_ = 0.0;
  double y_prev_ = 0.0;
  bool iterate_ = true;     // rate-independent, or a thresholds rate law
  double tolerance_ = 0.0;  // [input unit]
  // A thresholds law whose output falls with the drive's own rate (beta a / dt beyond the
  // margin): iterated at the rate its rate-free self's drive predicts (rate_ follows that drive).
  std::unique_ptr<InverseMultiplicativeCompensator> rate_free_;
  RateEstimator rate_;
};

enum class InverseKind { kAnalytic, kNumeric, kMultiplicative, kAuto };

/// Builds the inverse for a model: kAuto picks analytic for PI / modified PI without creep,
/// numeric otherwise. Dynamics and delay are not inverted (quasi-static feedforward). The
/// analytic and numeric inverses saturate at the model's input range when it has one.
/// Throws NotInvertibleError naming the offending index, or std::invalid_argument.
/// The drive for a whole known target sequence, stepping `inverse` on from its present state:
/// each tick sees the targets ahead it can use (preview_samples()), fewer near the end.
/// Allocates: not for the real-time path.
std::vector<double> invert_sequence(InverseModel& inverse, std::span<const double> targets);

std::unique_ptr<InverseModel> make_inverse(const ActuatorModel& model,
                                           InverseKind kind = InverseKind::kAuto);

}  // namespace hystbench::compensation
