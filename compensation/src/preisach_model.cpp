#include "hystbench/compensation/preisach_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "details/validate.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation {

namespace {

// The input's place on the grid: its cell (clamped to N - 1) and where in it, in [0, 1].
struct GridPoint {
  std::size_t cell = 0;
  double along = 0.0;
};

GridPoint on_grid(double x, double u_min, double h, std::size_t n) {
  const double f = (x - u_min) / h;
  const auto cell = std::min(n - 1, static_cast<std::size_t>(std::max(0.0, f)));
  return {cell, std::clamp(f - static_cast<double>(cell), 0.0, 1.0)};
}

}  // namespace

PreisachModel::PreisachModel(PreisachParameters p) : p_(std::move(p)), map_(p_.output_map) {
  details::require(std::isfinite(p_.u_min) && std::isfinite(p_.u_max) && p_.u_min < p_.u_max,
                   "preisach: u_min must be below u_max");
  details::require(p_.cells >= 1 && p_.cells <= kMaxCells,
                   "preisach: cells must be in [1, " + std::to_string(kMaxCells) + "]");
  const std::size_t n = p_.cells, stride = n + 1;
  details::require(
      p_.densities.size() == cell_count(n),
      "preisach: densities must hold N (N + 1) / 2 = " + std::to_string(cell_count(n)) +
          " values, got " + std::to_string(p_.densities.size()));
  details::require_finite(p_.densities, "preisach: densities");
  details::require_finite(p_.slope, "preisach: slope");
  details::require_finite(p_.offset, "preisach: offset");
  details::require_finite(p_.center, "preisach: center");
  const ThresholdsRateLaw& law = p_.rate_law;
  details::require(std::isfinite(law.threshold_rate_s) && law.threshold_rate_s >= 0.0,
                   "preisach: rate.threshold_s must be >= 0");
  details::require(law.exponent > 0.0 && law.exponent <= 1.0,
                   "preisach: rate.threshold_exponent must be in (0, 1]");
  details::require(law.exponent == 1.0 || law.max_rate > 0.0,
                   "preisach: rate.threshold_exponent below 1 needs rate.max_rate > 0");
  for (const auto& [value, name] : {std::pair{law.max_rate, "rate.max_rate"},
                                    std::pair{law.record_max_rate, "rate.record_max_rate"},
                                    std::pair{law.rate_filter_s, "rate.filter_s"}}) {
    details::require(std::isfinite(value) && value >= 0.0,
                     std::string("preisach: ") + name + " must be >= 0");
  }
  rate_.configure(law.rate_filter_s, 1e-3);
  h_ = (p_.u_max - p_.u_min) / static_cast<double>(n);
  mass_.resize(p_.densities.size());
  for (std::size_t q = 0, i = 0; q < n; ++q) {
    for (std::size_t c = 0; c <= q; ++c, ++i) {
      mass_[i] = p_.densities[i] * h_ * h_ * (c == q ? 0.5 : 1.0);
    }
  }
  auto mass = [&](std::size_t row, std::size_t col) { return mass_[cell_index(row, col)]; };
  row_.assign(n * stride, 0.0);
  column_.assign(n * stride, 0.0);
  for (std::size_t r = 0; r < n; ++r) {
    for (std::size_t k = 1; k <= n; ++k) {
      row_[r * stride + k] = row_[r * stride + k - 1] + (k - 1 < r ? mass(r, k - 1) : 0.0);
    }
  }
  for (std::size_t c = 0; c < n; ++c) {
    for (std::size_t k = 1; k <= n; ++k) {
      // Cells (r, c) with c < r < k.
      const std::size_t r = k - 1;
      column_[c * stride + k] = column_[c * stride + k - 1] + (r > c ? mass(r, c) : 0.0);
    }
  }
  triangle_.assign(stride * stride, 0.0);
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = i; j-- > 0;) {
      // G(x_i, x_j) = G(x_i, x_(j+1)) + column j below row i + the diagonal cell j.
      triangle_[i * stride + j] =
          triangle_[i * stride + j + 1] + column_[j * stride + i] + mass(j, j);
    }
  }
  reset(p_.u_min);
}

double PreisachModel::clamp(double u) const noexcept {
  return std::isfinite(u) ? std::clamp(u, p_.u_min, p_.u_max) : u_;
}

double PreisachModel::everett(double a, double b) const noexcept {
  a = clamp(a);
  b = clamp(b);
  if (!(a > b)) return 0.0;
  const std::size_t n = p_.cells, stride = n + 1;
  const GridPoint ga = on_grid(a, p_.u_min, h_, n), gb = on_grid(b, p_.u_min, h_, n);
  const std::size_t i = ga.cell, j = gb.cell;
  const double s = ga.along, t = gb.along;
  auto diagonal = [&](std::size_t c) { return mass_[cell_index(c, c)]; };
  if (i == j) return (s - t) * (s - t) * diagonal(i);
  const double below = 1.0 - t;  // of b's cell, the part above b
  return triangle_[i * stride + j + 1] + s * (row_[i * stride + i] - row_[i * stride + j + 1]) +
         s * s * diagonal(i) + below * column_[j * stride + i] + below * below * diagonal(j) +
         s * below * mass_[cell_index(i, j)];
}

double PreisachModel::closing(const Memory& m, std::size_t n, double v) const noexcept {
  if (n == 0) return 0.0;
  // Onto a minimum, a maximum opens its term; onto a maximum, a minimum closes it.
  return n % 2 == 1 ? everett(v, m.e[n - 1]) : -everett(m.e[n - 1], v);
}

PreisachModel::Turn PreisachModel::turn(const Memory& m, double x) const noexcept {
  Turn t{m.n, kNoPush, 0.0};
  if (x == u_) return t;
  const bool rising = x > u_;
  if (rising != (t.n % 2 == 1)) {
    // The last input turned: it joins the memory (a full memory forgets its innermost pair).
    if (t.n == kMaxExtrema) t.n -= 2;
    t.pushed_at = t.n;
    t.pushed_prefix = m.p[t.n] + closing(m, t.n, u_);
    ++t.n;
  }
  // The wiping reads below the pushed extremum only (n - 2 < pushed_at).
  if (rising) {
    while (t.n >= 3 && x >= m.e[t.n - 2]) t.n -= 2;  // maxima below x are wiped out
  } else {
    while (t.n >= 2 && x <= m.e[t.n - 2]) {
      if (t.n == 2) {  // down to u_min: every relay down
        t.n = 1;
        break;
      }
      t.n -= 2;
    }
  }
  return t;
}

void PreisachModel::apply(double u, Memory& m) const noexcept {
  const Turn t = turn(m, clamp(u));
  if (t.pushed_at < t.n) {
    m.e[t.pushed_at] = u_;
    m.p[t.pushed_at + 1] = t.pushed_prefix;
  }
  m.n = t.n;
}

double PreisachModel::hysteresis(const Memory& m, const Turn& t, double x) const noexcept {
  // The closed terms' sum, then the open one the input x closes now.
  const bool pushed = t.pushed_at + 1 == t.n;
  const double prefix = pushed ? t.pushed_prefix : m.p[t.n];
  const double top = pushed ? u_ : m.e[t.n - 1];
  return t.n % 2 == 0 ? prefix - everett(top, x) : prefix + everett(x, top);
}

double PreisachModel::front(double u, double rate) const noexcept {
  if (!p_.rate_law.active()) return u;
  const double w = p_.rate_law.widening(rate);
  return std::clamp(front_, u - w, u + w);
}

double PreisachModel::relays(double x) const noexcept {
  x = clamp(x);
  return hysteresis(memory_, turn(memory_, x), x);
}

double PreisachModel::step(double u) noexcept {
  // The same input again: the relays stay, the output is what it was (bit for bit).
  if (u == held_u_) return held_output_;
  // A non-finite input leaves the relays where they are (clamp()), and the front and rate too.
  if (p_.rate_law.active() && std::isfinite(u)) front_ = front(u, rate_.step(u));
  const double x = clamp(p_.rate_law.active() ? front_ : u);
  const Turn t = turn(memory_, x);
  const double y = hysteresis(memory_, t, x);
  if (t.pushed_at < t.n) {
    memory_.e[t.pushed_at] = u_;
    memory_.p[t.pushed_at + 1] = t.pushed_prefix;
  }
  memory_.n = t.n;
  u_ = x;
  const double out = p_.center + map_.apply(p_.offset + p_.slope * u + y);
  // With a rate law a held input still moves the front and the rate: nothing is kept.
  held_u_ = p_.rate_law.active() ? std::numeric_limits<double>::quiet_NaN() : u;
  held_output_ = out;
  return out;
}

double PreisachModel::peek(double u) const noexcept {
  const double x = p_.rate_law.active() ? front(u, rate_.peek(u)) : u;
  return p_.center + map_.apply(p_.offset + p_.slope * u + relays(x));
}

double PreisachModel::peek_at_rate(double u, double rate) const noexcept {
  return p_.center + map_.apply(p_.offset + p_.slope * u + relays(front(u, rate)));
}

void PreisachModel::set_sample_period(double dt_s) {
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "sample period must be > 0");
  rate_.configure(p_.rate_law.rate_filter_s, dt_s);
}

std::optional<ThresholdsRateLaw> PreisachModel::thresholds_law() const {
  if (!p_.rate_law.active()) return std::nullopt;
  return p_.rate_law;
}

std::unique_ptr<HysteresisModel> PreisachModel::rate_free_part() const {
  if (!p_.rate_law.active()) return nullptr;
  PreisachParameters p = p_;
  p.rate_law = {};
  return std::make_unique<PreisachModel>(std::move(p));
}

void PreisachModel::reset(double u0) noexcept {
  held_u_ = std::numeric_limits<double>::quiet_NaN();
  rate_.reset(u0);
  front_ = u0;
  memory_.n = 1;
  memory_.e[0] = p_.u_min;
  memory_.p[0] = memory_.p[1] = 0.0;
  u_ = p_.u_min;
  apply(u0, memory_);
  u_ = clamp(u0);
}

void PreisachModel::cell_areas(double u, std::span<double> out) const noexcept {
  if (out.size() != p_.densities.size()) return;
  // The relays' input as step(u) would leave it.
  const double f = p_.rate_law.active() ? front(u, rate_.peek(u)) : u;
  Memory m = memory_;
  apply(f, m);
  write_cell_areas(m, clamp(f), out);
}

void PreisachModel::step_cell_areas(double u, std::span<double> out) noexcept {
  if (out.size() != p_.densities.size()) return;
  step_relays(u);
  write_cell_areas(memory_, u_, out);
}

void PreisachModel::step_relays(double u) noexcept {
  // As step(u), without the output's Everett value.
  held_u_ = std::numeric_limits<double>::quiet_NaN();
  if (p_.rate_law.active() && std::isfinite(u)) front_ = front(u, rate_.step(u));
  const double x = clamp(p_.rate_law.active() ? front_ : u);
  apply(x, memory_);
  u_ = x;
}

void PreisachModel::write_cell_areas(const Memory& m, double x,
                                     std::span<double> out) const noexcept {
  std::fill(out.begin(), out.end(), 0.0);
  // The up region in stripes of beta. With the memory's extrema and the input in a row,
  // s = e_0 .. e_(n-1), x (minima at even places, maxima at odd ones), stripe k holds
  // s_k <= beta < s_(k+2) under the top s_(k+1); the last one runs to its top.
  const std::size_t len = m.n + 1;
  auto s = [&](std::size_t k) { return k < m.n ? m.e[k] : x; };
  for (std::size_t k = 0; k + 1 < len; k += 2) {
    const double top = s(k + 1);
    add_stripe_areas(s(k), k + 2 < len ? s(k + 2) : top, top, out);
  }
}

void PreisachModel::add_stripe_areas(double from, double to, double top,
                                     std::span<double> out) const noexcept {
  if (!(to > from) || !(top > from)) return;
  const std::size_t n = p_.cells;
  const std::size_t first = on_grid(from, p_.u_min, h_, n).cell;
  const std::size_t last = on_grid(to, p_.u_min, h_, n).cell;
  for (std::size_t c = first; c <= last; ++c) {
    const double cell_lo = p_.u_min + static_cast<double>(c) * h_;
    const double b_lo = std::max(cell_lo, from), b_hi = std::min(cell_lo + h_, to);
    if (!(b_hi > b_lo)) continue;
    // The diagonal cell: beta <= alpha <= min(top, its top edge) over [b_lo, b_hi].
    const double u = std::min(top, cell_lo + h_);
    if (u > b_lo) {
      const double v = std::min(b_hi, u);
      out[cell_index(c, c)] += 0.5 * ((u - b_lo) * (u - b_lo) - (u - v) * (u - v));
    }
    // The cells above it: alpha up to the top, wholly above beta.
    const double width = b_hi - b_lo;
    for (std::size_t r = c + 1; r < n; ++r) {
      const double a_lo = p_.u_min + static_cast<double>(r) * h_;
      if (!(top > a_lo)) break;
      out[cell_index(r, c)] += width * (std::min(a_lo + h_, top) - a_lo);
    }
  }
}

Invertibility PreisachModel::invertibility() const {
  for (std::size_t i = 0; i < p_.densities.size(); ++i) {
    if (p_.densities[i] < 0.0) {
      return Invertibility::failure("preisach", static_cast<int>(i), p_.densities[i],
                                    "preisach density[" + std::to_string(i) +
                                        "] = " + significant(p_.densities[i], 6) +
                                        " is negative: the output would fall as the input rises");
    }
  }
  if (p_.slope < 0.0) {
    return Invertibility::failure("preisach", -1, p_.slope,
                                  "preisach slope = " + significant(p_.slope, 6) + " is negative");
  }
  if (Invertibility map = map_.invertibility(); !map.invertible) {
    map.block = "preisach.output_map";
    map.reason = "preisach output map: " + map.reason;
    return map;
  }
  const bool any = p_.slope > 0.0 || std::any_of(p_.densities.begin(), p_.densities.end(),
                                                 [](double d) { return d > 0.0; });
  if (!any) {
    return Invertibility::failure("preisach", -1, 0.0,
                                  "preisach: every density and the slope are 0 (a constant)");
  }
  return Invertibility::ok();
}

std::unique_ptr<HysteresisModel> PreisachModel::clone() const {
  return std::make_unique<PreisachModel>(*this);
}

}  // namespace hystbench::compensation
