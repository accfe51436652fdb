#pragma once
// Classical Preisach hysteresis with a continuous density (Mayergoyz): a continuum of relays, each
// switching up when the input reaches alpha and down when it falls to beta <= alpha, on the input
// range [u_min, u_max]. The density, in the relays' coercive and bias coordinates
// h_c = (alpha - beta) / 2 and h_b = (alpha + beta) / 2, is a lognormal in h_c times a normal in
// h_b:
//   mu(alpha, beta) = A * LogNormal(h_c; median, spread) * Normal(h_b; mean, std),
// scaled so that all relays up minus all down is switching_um. The output is the weight of the
// relays that are up, through the Everett function E(alpha, beta) (the weight of the triangle
// beta <= b <= a <= alpha), tabulated at construction on a grid over the input range and
// interpolated, and a memory of the input's dominant alternating extrema (the wiping-out rule).
//
// It is not a sum of play operators (a PI model is a Preisach model whose density depends on h_c
// only), nor one followed by a static output map (the modified PI): its minor loops between the
// same two inputs are congruent wherever they sit, and its branches bend with h_b.
//
// Units: input in V, output in µm. Construction allocates and throws std::invalid_argument naming
// the field; step(), reset() and the accessors are real-time safe (no allocation, no
// exception; O(1) per step, amortised over the extrema it wipes out).
#include <cstddef>
#include <vector>

namespace hystbench::sim {

struct PreisachParameters {
  double u_min_v = 0.0;             ///< input range the relays cover [V]
  double u_max_v = 150.0;           ///< > u_min_v [V]
  double coercive_median_v = 20.0;  ///< median relay half-width h_c [V], > 0
  double coercive_spread = 0.6;     ///< lognormal shape of h_c (std of ln h_c), > 0
  double bias_mean_v = 50.0;        ///< mean relay centre h_b [V]
  double bias_std_v = 30.0;         ///< spread of the relay centres [V], > 0
  double switching_um = 20.0;       ///< output from every relay down to every relay up [µm], > 0
  int grid_points = 513;            ///< Everett table points per axis, [33, 4097]
};

/// Throws std::invalid_argument naming the field, with `prefix` before it ("hysteresis.").
void validate(const PreisachParameters& p, const char* prefix = "");

class PreisachHysteresis {
 public:
  /// Tabulates the Everett function; starts relaxed at u_min_v (see reset()).
  explicit PreisachHysteresis(const PreisachParameters& p);

  /// Moves the input to u [V] (clamped to the range) and returns the output [µm]. A non-finite
  /// u leaves the state as it is.
  double step(double u) noexcept;
  /// The output after the last step() or reset() [µm].
  double output() const noexcept { return y_; }
  /// Relaxed at u0: the state a slowly decaying alternating input around u0 leaves (AC
  /// demagnetisation), every relay whose centre h_b is below u0 up, the others down (to within
  /// 1e-4 of the range). Output 0 is every relay down.
  void reset(double u0) noexcept;

  /// Everett function E(alpha, beta) [µm] for alpha >= beta in the range (0 otherwise).
  double everett(double alpha, double beta) const noexcept;
  /// Dominant extrema held in memory (the reversal points not yet wiped out), for tests.
  std::size_t memory_size() const noexcept { return n_ - 1; }
  /// Reversal points dropped because the memory was full (a pathological input), for tests.
  std::size_t memory_overflows() const noexcept { return overflows_; }
  const PreisachParameters& parameters() const noexcept { return p_; }
  /// Maximum dominant extrema kept; beyond it the innermost minor loop is merged away.
  static constexpr std::size_t kMemoryCapacity = 1024;

 private:
  double clamp_input(double u) const noexcept;
  /// Contribution of the branch from reversal point `from` to input `to`.
  double branch(double from, double to) const noexcept {
    return to >= from ? everett(to, from) : -everett(from, to);
  }
  void push(double point) noexcept;
  double table(std::size_t i, std::size_t j) const noexcept { return table_[i * m_ + j]; }

  PreisachParameters p_;
  std::size_t m_;  // grid points per axis
  double h_;       // grid step [V]
  std::vector<double> table_;
  // points_[0] = u_min (all relays down); then alternating maxima (odd) and minima (even).
  // sums_[k] = output with the input at points_[k] having come along every branch up to it.
  std::vector<double> points_;
  std::vector<double> sums_;
  std::size_t n_ = 1;
  double u_ = 0.0;
  double y_ = 0.0;
  std::size_t overflows_ = 0;
};

}  // namespace hystbench::sim
