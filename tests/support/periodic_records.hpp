#pragma once
// Periodic records of several inputs for tests: random-phase multisines, discrete modes, and a
// two-input two-output stage whose first mode stiffens with its amplitude (a cubic spring).
#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <cstddef>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "hystbench/compensation/mimo_identification.hpp"

namespace hystbench::test {

/// A pair at f [Hz] with damping zeta as a discrete pole (Im > 0) at sample period dt [s].
inline std::complex<double> discrete_mode(double f, double zeta, double dt) {
  const double wn = 2.0 * std::numbers::pi * f, wd = wn * std::sqrt(1.0 - zeta * zeta);
  return std::exp(std::complex<double>(-zeta * wn * dt, wd * dt));
}

/// `realizations` records of `inputs` random-phase multisines, each of `periods` periods of
/// `period` samples, on bins 1..bins with `amplitude` per bin; independent phases throughout.
inline std::vector<Eigen::MatrixXd> random_multisines(std::size_t inputs, std::size_t realizations,
                                                      std::size_t period, std::size_t periods,
                                                      std::size_t bins, double amplitude,
                                                      unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  std::vector<Eigen::MatrixXd> u;
  for (std::size_t r = 0; r < realizations; ++r) {
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(inputs),
                                              static_cast<Eigen::Index>(period * periods));
    for (Eigen::Index j = 0; j < m.rows(); ++j) {
      for (std::size_t k = 1; k <= bins; ++k) {
        const double ph = phase(rng);
        const double w =
            2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(period);
        for (Eigen::Index t = 0; t < m.cols(); ++t) {
          m(j, t) += amplitude * std::cos(w * static_cast<double>(t) + ph);
        }
      }
    }
    u.push_back(std::move(m));
  }
  return u;
}

/// The record of a system (y = simulate(u), from rest) driven by u.
inline compensation::PeriodicRecord periodic_record_of(
    const std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)>& simulate,
    const std::vector<Eigen::MatrixXd>& u, std::size_t period, std::size_t periods, double dt) {
  compensation::PeriodicRecord rec;
  rec.period = period;
  rec.periods = periods;
  rec.dt = dt;
  for (const auto& ur : u) {
    rec.u.push_back(ur);
    rec.y.push_back(simulate(ur));
  }
  return rec;
}

/// Two inputs, two outputs, two modes: x_a at f_a [Hz] with a cubic spring (stiffness
/// k (1 + beta x_a^2): its frequency rises with its amplitude), x_b at f_b linear; x_a driven by
/// u1 + 0.5 u2, x_b by 0.4 u1 + u2 (unit static gain each); y1 = x_a + 0.5 x_b, y2 = 0.3 x_a +
/// x_b. Sampled at dt [s], integrated by RK4 at dt / substeps, from rest.
inline Eigen::MatrixXd cubic_spring_stage(const Eigen::MatrixXd& u, double dt, double beta,
                                          double f_a = 150.0, double f_b = 600.0,
                                          int substeps = 8) {
  const double wa = 2.0 * std::numbers::pi * f_a, wb = 2.0 * std::numbers::pi * f_b;
  const double za = 0.05, zb = 0.04;
  // State: x_a, v_a, x_b, v_b.
  Eigen::Vector4d s = Eigen::Vector4d::Zero();
  const auto deriv = [&](const Eigen::Vector4d& x, double fa, double fb) {
    Eigen::Vector4d d;
    d(0) = x(1);
    d(1) = wa * wa * (fa - x(0) - beta * x(0) * x(0) * x(0)) - 2.0 * za * wa * x(1);
    d(2) = x(3);
    d(3) = wb * wb * (fb - x(2)) - 2.0 * zb * wb * x(3);
    return d;
  };
  const double h = dt / substeps;
  Eigen::MatrixXd y(2, u.cols());
  for (Eigen::Index t = 0; t < u.cols(); ++t) {
    y(0, t) = s(0) + 0.5 * s(2);
    y(1, t) = 0.3 * s(0) + s(2);
    const double fa = u(0, t) + 0.5 * u(1, t), fb = 0.4 * u(0, t) + u(1, t);  // held over dt
    for (int k = 0; k < substeps; ++k) {
      const Eigen::Vector4d k1 = deriv(s, fa, fb);
      const Eigen::Vector4d k2 = deriv(s + 0.5 * h * k1, fa, fb);
      const Eigen::Vector4d k3 = deriv(s + 0.5 * h * k2, fa, fb);
      const Eigen::Vector4d k4 = deriv(s + h * k3, fa, fb);
      s += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
  }
  return y;
}

}  // namespace hystbench::test
