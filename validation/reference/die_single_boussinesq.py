#!/usr/bin/env python3
"""Derivation of the die table (docs/spec.md §4, die_single_boussinesq.csv), independent of mcdem.

One sphere (E = 23.3 kPa, nu = 1/2, r = 1 mm) in a rigid cubic die of side 2r, walls E_w = 50 MPa,
nu_w = 1/2, no friction, no gravity. The bottom plate is fixed and the top plate moves down by
delta. By symmetry the centre moves down delta/2, each plate carries P_v and each of the four side
walls P_h; the side walls stay at zero geometric overlap.

The nonlocal relation of Gonzalez & Cuitino (2012) for contact c of the sphere (docs/spec.md §4):

    overlap_c = [3 P_c / (4 E* sqrt(r))]^(2/3) + sum_{k != c} G(c, k) P_k

with 1/E* = (1 - nu^2)/E + (1 - nu_w^2)/E_w (sphere on a flat wall: R* = r), and the Boussinesq
kernel (Ghods et al. 2022, Eq. 2 with gamma = 1) for two contacts on a sphere of radius r at an
angle alpha apart, chord d = 2 r s, s = sin(alpha/2):

    G(s) = (1 + nu) / (2 pi E) * B(s) / d,   B(s) = 2(1 - nu) + 2(1 - 2 nu) s - (7 - 8 nu) s^2.

Contacts of the die: the opposite plate is at alpha = 180 deg (s = 1), each side wall at 90 deg
(s = 1/sqrt 2); a side wall sees the two plates and two side walls at 90 deg and one at 180 deg.
So the two unknowns P_v, P_h satisfy

    delta/2 = h(P_v) + G(1) P_v + 4 G(1/sqrt 2) P_h
    0       = h(P_h) + 2 G(1/sqrt 2) P_v + G(1) P_h + 2 G(1/sqrt 2) P_h

with h(P) = [3 P / (4 E* sqrt r)]^(2/3), solved here by Newton's method with the analytic
Jacobian to 1e-14 relative. Nothing is imported from mcdem: the test
`tests/reference/nonlocal.rs::die_table_script_reproduces_the_committed_table` runs this script and compares
its output with the committed CSV, and `die_table_boussinesq` checks the solver against the CSV.

Usage: python3 validation/reference/die_single_boussinesq.py   (prints the CSV to stdout)
"""
import math

E, NU, R = 23.3e3, 0.5, 1e-3
E_W, NU_W = 50e6, 0.5
E_STAR = 1.0 / ((1.0 - NU**2) / E + (1.0 - NU_W**2) / E_W)
RATIOS = (0.05, 0.10, 0.20, 0.30)


def kernel(s):
    """G(s) [m/N]: surface displacement at one contact per unit load at another (Eq. 2, gamma = 1)."""
    b = 2.0 * (1.0 - NU) + 2.0 * (1.0 - 2.0 * NU) * s - (7.0 - 8.0 * NU) * s * s
    return (1.0 + NU) / (2.0 * math.pi * E) * b / (2.0 * R * s)


def hertz_overlap(p):
    """Local Hertz overlap of a sphere on a flat wall under load p >= 0, and its derivative."""
    c = 3.0 / (4.0 * E_STAR * math.sqrt(R))
    return (c * p) ** (2.0 / 3.0), (2.0 / 3.0) * c * (c * p) ** (-1.0 / 3.0)


def hertz_force(overlap):
    return 4.0 / 3.0 * E_STAR * math.sqrt(R) * overlap**1.5


def solve(delta):
    g180, g90 = kernel(1.0), kernel(math.sqrt(0.5))
    pv = hertz_force(0.5 * delta)
    ph = 1e-2 * pv
    for _ in range(100):
        hv, dhv = hertz_overlap(pv)
        hh, dhh = hertz_overlap(ph)
        f1 = 0.5 * delta - hv - g180 * pv - 4.0 * g90 * ph
        f2 = -hh - 2.0 * g90 * pv - g180 * ph - 2.0 * g90 * ph
        # Jacobian of (f1, f2) with respect to (pv, ph).
        a11, a12 = -dhv - g180, -4.0 * g90
        a21, a22 = -2.0 * g90, -dhh - g180 - 2.0 * g90
        det = a11 * a22 - a12 * a21
        dpv = (a22 * f1 - a12 * f2) / det
        dph = (-a21 * f1 + a11 * f2) / det
        pv, ph = pv - dpv, ph - dph
        if ph <= 0.0:
            raise SystemExit("side-wall load left the active set: the table assumes all six contacts carry load")
        if abs(dpv) <= 1e-14 * pv and abs(dph) <= 1e-14 * ph:
            return pv, ph
    raise SystemExit(f"Newton did not converge at delta = {delta}")


def sig(x, digits):
    """x in the table's notation: `digits` significant digits, mantissa e-exponent."""
    m, e = f"{x:.{digits - 1}e}".split("e")
    return f"{m}e{int(e)}"


def main():
    print("# Single sphere in a rigid cubic die (docs/spec.md §4): E = 23.3 kPa, nu = 0.5, r = 1 mm, walls E = 50 MPa,")
    print("# nu_w = 0.5, top plate displaced by delta; nonlocal kernel boussinesq, from an independent script.")
    print("# P_v = plate force (top = bottom) [N], P_h = force on each of the four side walls [N].")
    print("delta_over_r,p_v_hertz,p_v_nonlocal,p_h_nonlocal")
    for x in RATIOS:
        pv, ph = solve(x * R)
        print(f"{x:.2f},{sig(hertz_force(0.5 * x * R), 4)},{sig(pv, 4)},{sig(ph, 3)}")


if __name__ == "__main__":
    main()
