#!/usr/bin/env python3
"""The best drive any feedforward could play to the loopback's rate-dependent truth.

How well can *any* drive track the loopback actuator with its rate dependence on, at 1-19 Hz?
This script asks it: it takes the
simulator's truth (sim/include/hystbench/sim/simulated_actuator_config.hpp: modified PI with the
rate-dependent paper's per-sample law W_i + c_i |du/dt|, its defaults), a sine over 80 % of the
output range (22.5 +- 18 um), and minimises sum (y - y_r)^2 over every sample of the drive with
Levenberg-Marquardt on the exact Jacobian of the model (sparse: a play's output depends on the
drive of the tick it last moved, the rate on this tick and the last). It knows the whole
reference and the exact model, so it bounds every causal and previewed inverse from below (up to
its local minimum). Hysteresis and rate law only: no creep, resonance, noise or converters.

  python3 docs/experiments/rate_dependent_optimum.py 10        # 10 Hz, about 3 min
  python3 docs/experiments/rate_dependent_optimum.py 19 --cap 5000

--cap is the truth's max_rate_v_per_s (5000 V/s in the simulator). The default here, no cap, is
the physical question: past the cap the simulated law turns static, and a one-tick jump of the
drive by tens of volts would exploit that. Needs python3-numpy (Debian package).
"""
import argparse

import numpy as np

DT = 1e-4
R = np.array([0, 7.5, 15, 22.5, 30, 37.5, 45, 52.5, 60, 67.5])
W = np.array([0.18] + [0.02] * 9)
OFFSET = -6.75
C = np.array([0, 2e-6, 4e-6, 6e-6, 8e-6, 1e-5, 1.2e-5, 1.4e-5, 1.6e-5, 1.8e-5])
DW = np.diff(np.concatenate([[0.0], C]))  # per-play rate coefficients
DZ_T = np.array([-15.0, 0.0, 12.0])
DZ_W = np.array([0.15, 1.0, 0.4])
CENTER = 21.0
SPAN = 36.0  # the reference's span [um]: errors are in % of it


def dead_zone(z):
    s = np.where(DZ_T > 0, np.maximum(z - DZ_T, 0), np.where(DZ_T < 0, np.minimum(z - DZ_T, 0), z))
    ds = np.where(DZ_T > 0, z > DZ_T, np.where(DZ_T < 0, z < DZ_T, True)) * 1.0
    return (DZ_W * s).sum(), (DZ_W * ds).sum()


def simulate(x, cap, jacobian=False):
    """Output of the truth for drive x (relaxed at 0 V); optionally dy/dx (n x n)."""
    n = len(x)
    F = np.maximum(-R, np.minimum(R, np.zeros(len(R))))
    y = np.zeros(n)
    J = np.zeros((n, n)) if jacobian else None
    last = np.full(len(R), -1)
    xp = 0.0
    for k in range(n):
        d = (x[k] - xp) / DT
        rate = min(abs(d), cap)
        moved = (x[k] - R > F) | (x[k] + R < F)
        F = np.maximum(x[k] - R, np.minimum(x[k] + R, F))
        z, dz = dead_zone(OFFSET + ((W + DW * rate) * F).sum() - CENTER)
        y[k] = CENTER + z
        if jacobian:
            last = np.where(moved, k, last)
            coef = dz * (W + DW * rate)
            for i in np.nonzero(last >= 0)[0]:
                J[k, last[i]] += coef[i]
            if abs(d) < cap:
                g = dz * (DW * F).sum() * np.sign(d) / DT
                J[k, k] += g
                if k > 0:
                    J[k, k - 1] -= g
        xp = x[k]
    return y, J


def rate_free_drive(yr):
    """The rate-free inverse (the rate terms ignored), per sample by bisection."""
    F = np.zeros(len(R))
    out = []
    for target in yr:
        lo, hi = 0.0, 150.0
        for _ in range(50):
            m = 0.5 * (lo + hi)
            Fm = np.maximum(m - R, np.minimum(m + R, F))
            lo, hi = (m, hi) if CENTER + dead_zone(OFFSET + (W * Fm).sum() - CENTER)[0] < target else (lo, m)
        F = np.maximum(lo - R, np.minimum(lo + R, F))
        out.append(lo)
    return np.array(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("frequency_hz", type=float)
    ap.add_argument("--cycles", type=int, default=2, help="periods simulated; the last is scored")
    ap.add_argument("--iterations", type=int, default=25)
    ap.add_argument("--cap", type=float, default=1e12, help="the truth's rate cap [V/s]")
    a = ap.parse_args()
    period = int(round(1.0 / a.frequency_hz / DT))
    n = a.cycles * period
    t = np.arange(n) * DT
    yr = 22.5 - 18.0 * np.cos(2 * np.pi * a.frequency_hz * t)
    weight = np.ones(n)
    weight[: period // 2] = 0.3  # the start-up half period counts less

    def report(name, x, y):
        e = (y - yr)[-period:]
        print(f"{name}: rms {np.sqrt((e ** 2).mean()) / SPAN * 100:.3f} % max "
              f"{np.abs(e).max() / SPAN * 100:.2f} % of the span, max drive step "
              f"{np.abs(np.diff(x[-period:])).max():.2f} V", flush=True)

    x = rate_free_drive(yr)
    y, J = simulate(x, a.cap, True)
    report("rate-free inverse", x, y)
    cost = (((y - yr) * weight) ** 2).sum()
    mu = 1e-2
    for it in range(a.iterations):
        Jw = J * weight[:, None]
        A = Jw.T @ Jw
        b = Jw.T @ ((y - yr) * weight)
        while mu < 1e6:
            xn = np.clip(x + np.linalg.solve(A + mu * np.eye(n), -b), 0.0, 150.0)
            yn, Jn = simulate(xn, a.cap, True)
            cn = (((yn - yr) * weight) ** 2).sum()
            if cn < cost:
                mu = max(mu / 3, 1e-9)
                break
            mu *= 4
        if cn >= cost:
            break
        x, y, J, cost = xn, yn, Jn, cn
        report(f"optimised, iteration {it + 1}", x, y)


if __name__ == "__main__":
    main()
