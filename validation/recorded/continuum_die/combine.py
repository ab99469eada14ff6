#!/usr/bin/env python3
"""Combines `mcdem continuum` runs of one die scene at several mesh resolutions into the reference
CSV of validation/reference/.

Reads the per-load-step lines each run prints ("N intervals delta/r X: plate P Pa, side S Pa
(A + B contact nodes, ...)", six significant digits) from the runs' logs (a log may hold several
resolutions) and keeps the Δ/r every resolution reached.

Reference value: the finest mesh. Error bar: the largest difference between the finest mesh and the
two next-finest ones. This replaces the three-level Richardson extrapolation because the die's
mesh sequence is not in the asymptotic range: the nodal contact active set moves by whole node rows
and the discretisation error changes sign from one mesh to the next (see README.md). For reference
the script prints, per Δ/r, every mesh's value and the three-level Richardson estimate of
`mcdem::fem::richardson` over the resolutions given by --richardson n1,n2,n3 (constant ratio):

    d12 = f1 - f2, d23 = f2 - f3, g = d12 / d23
    g > 1 (monotone, converging): p = ln g / ln q, value = f3 - d23 / (q^p - 1), error = |value - f3|
    otherwise (not monotone):     value = f3 - d23, error = max(|d12|, |d23|), "order 1.00"

Usage: combine.py LAW NU OUT.csv [--richardson n1,n2,n3] LOG...
"""
import math
import re
import sys

LINE = re.compile(
    r"^(\d+) intervals delta/r ([0-9.]+): plate ([-0-9.e+]+) Pa, side ([-0-9.e+]+) Pa \((\d+) \+ (\d+) contact"
)


def read(paths):
    runs = {}
    for path in paths:
        for line in open(path):
            m = LINE.match(line.strip())
            if m:
                n = int(m.group(1))
                runs.setdefault(n, {})[round(float(m.group(2)), 4)] = (
                    float(m.group(3)),
                    float(m.group(4)),
                    int(m.group(5)),
                    int(m.group(6)),
                )
    return runs


def richardson(f1, f2, f3, q):
    d12, d23 = f1 - f2, f2 - f3
    if d23 == 0.0:
        return f3, abs(d12), math.inf
    g = d12 / d23
    if g > 1.0:
        p = math.log(g) / math.log(q)
        v = f3 - d23 / (q**p - 1.0)
        return v, abs(v - f3), p
    return f3 - d23, max(abs(d12), abs(d23)), 1.0


def main():
    args = sys.argv[1:]
    law, nu, out = args[:3]
    rest = args[3:]
    rich = None
    if rest and rest[0] == "--richardson":
        rich = [int(x) for x in rest[1].split(",")]
        rest = rest[2:]
    runs = read(rest)
    ns = sorted(runs)
    assert len(ns) >= 3, f"need at least three resolutions, got {ns}"
    fine = ns[-3:]
    xs = sorted(set.intersection(*(set(runs[n]) for n in ns)))
    with open(out, "w") as f:
        f.write(
            f"# Single sphere (r = 1 mm, E = 23.3 kPa, {law}, nu = {nu}, F-bar) in a rigid frictionless die of side 2r,\n"
            f"# finite elements (mcdem continuum), mesh intervals per block edge {', '.join(map(str, ns))}.\n"
            f"# stress = wall force / (2r)^2 [Pa], side = one side wall. Value: the finest mesh ({fine[2]} intervals);\n"
            f"# *_err: max |f({fine[2]}) - f(n)| over n = {fine[1]}, {fine[0]} (the mesh spread; the sequence is not monotone,\n"
            "# so three-level Richardson extrapolation does not apply). Made by validation/recorded/continuum_die/combine.py,\n"
            "# see validation/reference/README.md.\n"
        )
        f.write("delta_over_r,plate_stress_pa,plate_err_pa,side_stress_pa,side_err_pa\n")
        for x in xs:
            v = runs[fine[2]][x]
            pe = max(abs(v[0] - runs[n][x][0]) for n in fine[:2])
            se = max(abs(v[1] - runs[n][x][1]) for n in fine[:2])
            f.write(f"{x:g},{v[0]:.5e},{pe:.3e},{v[1]:.5e},{se:.3e}\n")
    print(f"meshes {ns}; plate then side stress [Pa] per mesh, contact nodes plate+side per mesh")
    for x in xs:
        pl = " ".join(f"{runs[n][x][0]:9.3f}" for n in ns)
        sd = " ".join(f"{runs[n][x][1]:8.4f}" for n in ns)
        nodes = " ".join(f"{runs[n][x][2]}+{runs[n][x][3]}" for n in ns)
        line = f"{x:5.2f} | plate {pl} | side {sd} | nodes {nodes}"
        if rich:
            q = rich[1] / rich[0]
            rp = richardson(*(runs[n][x][0] for n in rich), q)
            rs = richardson(*(runs[n][x][1] for n in rich), q)
            line += f" | Richardson {rich}: plate {rp[0]:.2f} ± {rp[1]:.2f} (p {rp[2]:.2f}), side {rs[0]:.3f} ± {rs[1]:.3f} (p {rs[2]:.2f})"
        print(line)


if __name__ == "__main__":
    main()
