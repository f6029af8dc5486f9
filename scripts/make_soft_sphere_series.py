#!/usr/bin/env python3
"""Exact force on a soft (linear) sphere next to a ball magnet: an independent reference for the
coupled induction solve (issue 14), written to tests/data/soft_sphere_series.json.

A uniformly magnetized ball's field outside it is exactly that of a point dipole m = Br V / mu0 at
its centre (magbake keeps a permanent ball as that one exact cell, physics.md §4), and a linear
sphere of radius a and permeability mu = 1 + chi in the field of an axial point dipole at distance
D from its centre answers, order by order in Legendre polynomials about its centre, with the
exterior potential C_l r^-(l+1) P_l(cos theta),

    C_l = (m / 4 pi) (l + 1) l (mu - 1) / (mu l + l + 1) a^(2l+1) / D^(l+2)

(continuity of the potential and of the normal B at r = a). The force the sphere's field exerts on
the dipole, mu0 m dH_z/dz at the dipole, is minus the force on the sphere:

    F_z(sphere, towards the magnet) = mu0 m^2 / (4 pi D^4) sum_l l (l+1)^2 (l+2) (mu-1)/(mu l + l + 1) (a/D)^(2l+1)

The l = 1 term is the induced point dipole (4 pi a^3 (mu-1)/(mu+2) H) in the dipole's field
gradient; the series converges like (a/D)^(2l), i.e. within 60 terms at contact. Summed in
double precision to a relative 1e-16.

Usage: make_soft_sphere_series.py [OUT.json]
"""
import json
import math
import sys

MU0 = 4e-7 * math.pi
A_MM, MAGNET_MM, BR = 6.35, 6.0, 1.3        # soft ball radius (1/2 inch), magnet ball radius, N42
GAPS_MM = [0.05, 1.0, 5.0, 20.0]
CHIS = [700.0, 20000.0]


def force(chi, a, D, m):
    mu = 1.0 + chi
    total, l = 0.0, 1
    while True:
        term = l * (l + 1) ** 2 * (l + 2) * (mu - 1) / (mu * l + l + 1) * (a / D) ** (2 * l + 1)
        total += term
        if term < 1e-17 * total or l > 5000:
            break
        l += 1
    return MU0 * m * m / (4 * math.pi * D ** 4) * total, l


def scene(gap_mm, chi):
    z = A_MM + MAGNET_MM + gap_mm
    return (
        "magbake: 1\nname: soft_ball_under_ball_magnet\nunits: {length: mm, angle: deg}\n"
        "magnetics: {quality: QUALITY, induction: coupled CELL}\n"
        f"materials:\n  N42: {{kind: permanent, remanence: {BR}, density: 7500}}\n"
        f"  steel: {{kind: soft, chi: {chi:g}, density: 7850}}\n"
        f"bodies:\n  - {{name: ball, shape: {{sphere: {{radius: {A_MM}}}}}, material: steel, motion: static}}\n"
        f"  - {{name: magnet, shape: {{sphere: {{radius: {MAGNET_MM}}}}}, material: N42, magnetization: [0, 0, 1], "
        f"position: [0, 0, {z!r}], motion: static}}\n")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "tests/data/soft_sphere_series.json"
    a, rm = A_MM * 1e-3, MAGNET_MM * 1e-3
    m = BR * (4.0 / 3.0) * math.pi * rm ** 3 / MU0
    cases = []
    for chi in CHIS:
        for gap in GAPS_MM:
            D = a + rm + gap * 1e-3
            f, terms = force(chi, a, D, m)
            # Sanity: far away the l = 1 term alone (an induced point dipole) must dominate.
            dipole = 3 * MU0 * m * m * (chi / (chi + 3)) * a ** 3 / (math.pi * D ** 7)
            cases.append({"name": f"chi{chi:g}_gap{gap:g}mm", "chi": chi, "gap_mm": gap, "scene": scene(gap, chi),
                          "quantity": "force_z", "body": 0, "reference": f, "terms": terms,
                          "induced_dipole_only": dipole})
    doc = {"generator": "scripts/make_soft_sphere_series.py",
           "method": "exact Legendre series for a linear sphere in the field of a point dipole (a ball magnet); "
                     "force on the soft ball along +z (towards the magnet), N",
           "soft_radius_mm": A_MM, "magnet_radius_mm": MAGNET_MM, "remanence_T": BR, "magnet_moment_Am2": m,
           "cases": cases}
    with open(out, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    for c in cases:
        print(f"{c['name']:<22} F = {c['reference']:.6g} N ({c['terms']} terms; induced dipole alone "
              f"{c['induced_dipole_only'] / c['reference']:.3f} of it)")


if __name__ == "__main__":
    main()
