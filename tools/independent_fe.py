"""The stiffness of a compressible rubber against an FE route independent of the shipped table
(issue #29; docs/model.md, "Compressibility"): prints, per geometry, direction and K/µ, how far
`stiffness` is from it in |K| (%).

    PYTHONPATH=$PWD python tools/independent_fe.py [--levels 2 3]

The route (tests/independent_fe.py, felupe: the `fe` extra): triquadratic mixed hexahedra on a
uniform mesh mapped onto the true circles, two meshes extrapolated. The compound is Paper B's
with friction and the fractional branch made negligible, so |K| = µ·S; a = 20 mm, six geometries
between the table's nodes, b/a 1.22–1.95, radial and conical, K/µ 800 and 2000. About a minute
on one core.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from core import PAPER_B, stiffness
from tests.independent_fe import extrapolated

GEOMETRIES = [(1.22, 10.5), (1.28, 5.0), (1.42, 7.0), (1.62, 2.6), (1.85, 4.5), (1.95, 1.3)]  # b/a, L/(b − a)
INNER = 0.02  # m


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, nargs=2, default=(2, 3), help="elements across the wall of the two meshes")
    levels = tuple(parser.parse_args().levels)
    worst = 0.0
    print("b/a    L/(b−a)  mode     K/µ    |K| bushing    |K| FE         gap")
    for q, lam in GEOMETRIES:
        for mode in ("radial", "conical"):
            for ratio in (800.0, 2000.0):
                design = PAPER_B.replace(mode=mode, inner_radius=INNER, outer_radius=q * INNER,
                                         length=lam * (q - 1.0) * INNER, fractional_coefficient=1e-3,
                                         friction_stress_max=1e-3)
                design = design.replace(bulk_modulus=ratio * design.material.shear_modulus)
                scale = INNER if mode == "radial" else INNER**3  # S of a = 1 at this size: m, m³
                fe = extrapolated(q, lam, mode, ratio, levels) * scale * design.material.shear_modulus
                k = float(stiffness(design, [1.0], [1e-6]).magnitude[0, 0])
                worst = max(worst, abs(k / fe - 1))
                print(f"{q:<6.2f} {lam:<8.2f} {mode:<8s} {ratio:<6.0f} {k:<14.6g} {fe:<14.6g} {100 * (k / fe - 1):+.3f} %")
    print(f"largest gap {100 * worst:.2f} % (issue #29's bound: 1 %)")


if __name__ == "__main__":
    main()
