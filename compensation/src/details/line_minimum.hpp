#pragma once
// The minimum of a function of one variable on an interval, without derivatives: Brent's method
// (R. P. Brent, Algorithms for Minimization without Derivatives, 1973, ch. 5), golden-section
// steps where a parabola through the three best points is not trusted, the parabola's vertex
// where it is. On a smooth minimum it needs a few evaluations where golden sections alone need
// a dozen for the same bracket.
#include <algorithm>
#include <cmath>
#include <limits>

namespace hystbench::compensation::details {

/// Where a line search ended: the best point found, its value, and the evaluations it took.
struct LineMinimum {
  double x = 0.0;
  double value = std::numeric_limits<double>::infinity();
  int evaluations = 0;
};

/// The minimum of f on [a, b] (a < b), started at x0 in [a, b] whose value f0 = f(x0) is known
/// (it is not evaluated again). Stops when the bracket about the best point is within
/// `tolerance` (in x's units, > 0) of it, or after `max_evaluations` evaluations of f. A local
/// minimum: f should be unimodal on [a, b].
template <class F>
LineMinimum line_minimum(F&& f, double a, double b, double x0, double f0, double tolerance,
                         int max_evaluations) {
  const double golden = 0.5 * (3.0 - std::sqrt(5.0));  // the smaller golden-section fraction
  double x = std::clamp(x0, a, b), w = x, v = x;       // best, second best, previous w
  double fx = f0, fw = f0, fv = f0;
  double step = 0.0, before_last = 0.0;  // the last step, and the one before it
  int evaluations = 0;
  while (evaluations < max_evaluations) {
    const double middle = 0.5 * (a + b);
    const double tol2 = 2.0 * tolerance;
    if (std::abs(x - middle) <= tol2 - 0.5 * (b - a)) break;
    bool parabolic = false;
    if (std::abs(before_last) > tolerance) {
      // The vertex of the parabola through (v, fv), (w, fw), (x, fx), as x + p / q.
      const double r = (x - w) * (fx - fv);
      double q = (x - v) * (fx - fw);
      double p = (x - v) * q - (x - w) * r;
      q = 2.0 * (q - r);
      if (q > 0.0) p = -p;
      q = std::abs(q);
      const double older = before_last;
      before_last = step;
      // Trusted when it moves less than half the step before last, and stays inside [a, b].
      if (std::abs(p) < std::abs(0.5 * q * older) && p > q * (a - x) && p < q * (b - x)) {
        step = p / q;
        const double u = x + step;
        if (u - a < tol2 || b - u < tol2) step = x < middle ? tolerance : -tolerance;
        parabolic = true;
      }
    }
    if (!parabolic) {
      before_last = x < middle ? b - x : a - x;
      step = golden * before_last;
    }
    const double u = x + (std::abs(step) >= tolerance ? step : std::copysign(tolerance, step));
    const double fu = f(u);
    ++evaluations;
    if (fu <= fx) {
      (u < x ? b : a) = x;
      v = w, fv = fw;
      w = x, fw = fx;
      x = u, fx = fu;
    } else {
      (u < x ? a : b) = u;
      if (fu <= fw || w == x) {
        v = w, fv = fw;
        w = u, fw = fu;
      } else if (fu <= fv || v == x || v == w) {
        v = u, fv = fu;
      }
    }
  }
  return {x, fx, evaluations};
}

}  // namespace hystbench::compensation::details
