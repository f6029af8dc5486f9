#!/usr/bin/env python3
"""Exact pull between two touching (or nearly touching) soft balls in a uniform field along the
line of their centres: an independent reference for soft-soft contact in the coupled induction
solve (issue 14), written to tests/data/two_ball_series.json.

Two equal linear balls (radius a, permeability mu = 1 + chi), centres D apart on the x axis, in a
uniform applied field H0 along x. The problem is axisymmetric about the x axis. Outside the balls
the scalar potential (H = -grad phi) is

    phi = -H0 x + sum_n A_n r1^-(n+1) P_n(cos t1) + sum_n B_n r2^-(n+1) P_n(cos t2)

about each centre. The mirror plane between the balls makes phi odd, so B_n = (-1)^(n+1) A_n.
An exterior axial multipole of ball 2 seen from ball 1 (centre 2 at +D) is regular there:

    r2^-(n+1) P_n(cos t2) = sum_m (-1)^n C(m+n, n) r1^m P_m(cos t1) / D^(m+n+1)      (r1 < D)

and a linear ball answers each regular order m with A_m = -alpha_m a^(2m+1) E_m,
alpha_m = (mu-1) m / (mu m + m + 1) (continuity of phi and of the normal B at r = a). With
A_n = a^(n+2) H0 x_n and rho = a/D <= 1/2 the system is

    x_m - alpha_m sum_n C(m+n, n) rho^(m+n+1) x_n = alpha_m delta_m1,

whose coefficients are at most 1/2 even at contact (C(m+n, n) <= 2^(m+n)); they are formed
through lgamma. The force on ball 2 is that of ball 1's field on ball 2's magnetic charge
(the uniform field and a body's own field exert no net force): with ball 1's field regular about
centre 2, phi_1 = sum_m c_m r2^m P_m, c_m = sum_n A_n (-1)^(m+1) C(m+n, n) / D^(m+n+1), and
d/dx (r^m P_m) = m r^(m-1) P_(m-1),

    F_x(ball 2) = -4 pi mu0 sum_(m>=2) m c_m B_(m-1).

Checked two ways: the pull equals (mu0/2) H0 d(m_total)/dD by central differences (the energy
of linear matter in a fixed applied field, -mu0/2 H0 m_total; physics.md §8), and far apart it
tends to the induced point dipoles' pull. The truncation order N is doubled until the force
moves by less than 1e-6: at contact with chi 700 this takes thousands of orders (the field in the
wedge of the contact is resolved only on a scale of a/chi, physics.md §7).

Usage: make_two_ball_series.py [OUT.json]
"""
import json
import math
import sys

import numpy as np

MU0 = 4e-7 * math.pi
A_MM = 5.0                     # BowlSpheres' steel balls
B0_T = 0.1                     # applied field mu0 H0 along x
GAPS_MM = [0.0, 0.01, 0.05, 0.5, 2.0, 5.0]
CHIS = [100.0, 700.0]


def log_factorials(k):
    """log(j!) for j = 0..k."""
    return np.concatenate([[0.0], np.cumsum(np.log(np.arange(1, k + 1, dtype=float)))])


def solve(chi, a, D, N):
    """Dimensionless coefficients x_1..x_N (A_n = x_n H0 a^(n+2)) and the coupling matrix K."""
    mu = 1.0 + chi
    i = np.arange(1, N + 1)
    alpha = (mu - 1) * i / (mu * i + i + 1)
    lf = log_factorials(2 * N + 1)
    s = i[:, None] + i[None, :]
    K = np.exp(lf[s] - lf[i][:, None] - lf[i][None, :] + (s + 1) * math.log(a / D))
    rhs = np.zeros(N)
    rhs[0] = alpha[0]
    return np.linalg.solve(np.eye(N) - alpha[:, None] * K, rhs), K


def pull(chi, a, D, H0, N):
    """Force on ball 2 along +x (negative: towards ball 1) and the pair's total moment.

    c_m B_(m-1) = -x_(m-1) (K x)_m H0^2 a^2 (the signs (-1)^(m+1) (-1)^m), so
    F = -4 pi mu0 H0^2 a^2 sum_(m>=2) m x_(m-1) (K x)_m."""
    x, K = solve(chi, a, D, N)
    Kx = K @ x
    m = np.arange(2, N + 1)
    F = -4 * math.pi * MU0 * H0 ** 2 * a ** 2 * float(np.sum(m * x[m - 2] * Kx[m - 1]))
    return F, 2 * 4 * math.pi * x[0] * H0 * a ** 3


def converged(chi, a, D, H0, tol=1e-6, N0=50, Nmax=8192):
    N, last = N0, None
    while True:
        F, m = pull(chi, a, D, H0, N)
        if last is not None and abs(F - last) <= tol * abs(F):
            return F, m, N
        if N >= Nmax:
            return F, m, -N  # not converged to tol: negative order says so
        last, N = F, 2 * N


def scene(gap_mm, chi):
    x = A_MM + gap_mm / 2
    return (
        "magbake: 1\nname: two_touching_balls\nunits: {length: mm, angle: deg}\n"
        f"magnetics: {{quality: QUALITY, induction: coupled, external_field: [{B0_T}, 0, 0] CELL}}\n"
        f"materials:\n  steel: {{kind: soft, chi: {chi:g}, density: 7850}}\n"
        f"bodies:\n  - {{name: a, shape: {{sphere: {{radius: {A_MM}}}}}, material: steel, position: [{-x!r}, 0, 0], motion: static}}\n"
        f"  - {{name: b, shape: {{sphere: {{radius: {A_MM}}}}}, material: steel, position: [{x!r}, 0, 0], motion: static}}\n")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "tests/data/two_ball_series.json"
    a, H0 = A_MM * 1e-3, B0_T / MU0
    cases = []
    for chi in CHIS:
        for gap in GAPS_MM:
            D = 2 * a + gap * 1e-3
            F, moment, N = converged(chi, a, D, H0)
            # Energy check: F = (mu0/2) H0 d(m_total)/dD by differences (one-sided at contact, where
            # the pull is steep: a check of the sign and size only).
            h, Ne = 1e-4 * a, min(abs(N), 1600)
            if gap > 0:
                dm = (pull(chi, a, D + h, H0, Ne)[1] - pull(chi, a, D - h, H0, Ne)[1]) / (2 * h)
            else:  # second-order one-sided
                dm = (-3 * pull(chi, a, D, H0, Ne)[1] + 4 * pull(chi, a, D + h, H0, Ne)[1]
                      - pull(chi, a, D + 2 * h, H0, Ne)[1]) / (2 * h)
            F_energy = 0.5 * MU0 * H0 * dm
            # Far-field check: two induced point dipoles p = 4 pi a^3 (mu-1)/(mu+2) H0.
            p = 4 * math.pi * a ** 3 * chi / (chi + 3) * H0
            F_dip = -3 * MU0 * p * p * 2 / (4 * math.pi * D ** 4)
            cases.append({"name": f"chi{chi:g}_gap{gap:g}mm", "chi": chi, "gap_mm": gap, "scene": scene(gap, chi),
                          "quantity": "force_x", "body": 1, "reference": F, "orders": abs(N), "converged": N > 0,
                          "pair_moment_Am2": moment, "energy_check": F_energy, "induced_dipoles_only": F_dip})
            print(f"chi {chi:6g} gap {gap:5.2f} mm  F_x(b) = {F:.7g} N  (N = {N}; energy check {F_energy:.6g}, "
                  f"point dipoles {F_dip:.4g})", flush=True)
    doc = {"generator": "scripts/make_two_ball_series.py",
           "method": "exact multipole (Legendre) series for two equal linear balls in a uniform field along the line "
                     "of their centres; force on ball b (at +x) along +x, N (negative: towards ball a)",
           "radius_mm": A_MM, "applied_field_T": B0_T, "cases": cases}
    with open(out, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
