"""The long radial closed form with a bulk modulus through its matched series (docs/model.md,
"Compressibility"): how far each output is from `stiffness`, which takes the closed form exactly.

    PYTHONPATH=$PWD python tools/long_radial_series.py            # the loop and the fixed pair
    PYTHONPATH=$PWD python tools/long_radial_series.py --element  # and the element (minutes)

Paper B's material (a friction-heavy compound), a = 20 mm, K/µ 50–5000, b/a 1.1–3, the drive's
equivalent strain 1e-4 to 1e-2, 1, 10 and 100 Hz. Printed per K/µ, the largest gap in |K| (%) and
in the loss factor:

* the loop: the first harmonic of `core.loops.loop` (its series matched at its own point);
* the fixed pair: the series matched once at `core.compressible.REFERENCE_FREQUENCY` and
  `REFERENCE_STRAIN` (the element's), driven elsewhere: its describing function (the shear
  strain amplitude solved with brentq), against the same stiffness;
* with ``--element``: the element itself, 4 periods of 400 steps from rest, first harmonic of the
  last (b/a 1.2–3, L = min(90 mm, 10 (b − a)), inside the finite table for its conical channels),
  and the same without a bulk modulus (the element's own error).
"""

from __future__ import annotations

import sys
import warnings

import numpy as np
from scipy.optimize import brentq

from core import PAPER_B, stiffness
from core.bushing import modulus_function
from core.compressible import REFERENCE_FREQUENCY, REFERENCE_STRAIN, series_at
from core.element import Element
from core.loops import loop

RATIOS = (50, 250, 1000, 2000, 5000)
STRAINS = (1e-4, 1e-3, 1e-2)
FREQUENCIES = (1.0, 10.0, 100.0)


def design_of(q: float, ratio: float | None, length: float = 0.09):
    d = PAPER_B.in_mode("radial").replace(shape="long", inner_radius=0.02, outer_radius=0.02 * q, length=length)
    return d.replace(bulk_modulus=None if ratio is None else ratio * d.material.shear_modulus)


def first_harmonic(phase, force, amplitude) -> complex:
    return complex(2 * np.mean(force * np.sin(phase)) + 2j * np.mean(force * np.cos(phase))) / amplitude


def gap(k: complex, k0: complex) -> tuple[float, float]:
    return abs(abs(k) / abs(k0) - 1), abs(k.imag / k.real - k0.imag / k0.real)


def describing(design, series, f, x) -> complex:
    """The series' first harmonic: |ε̂(1 + 2κµ_eq(ε̂))| = c'x̂, K = 1/(1/(S'µ_eq) + C_b)."""
    mu = modulus_function(design)
    e = brentq(lambda e: abs(e * (1 + 2 * series.kappa * complex(mu(f, e)))) - series.strain_factor * x,
               1e-4 * series.strain_factor * x, series.strain_factor * x, xtol=1e-18, rtol=1e-14)
    return 1 / (1 / (series.shape_factor * complex(mu(f, e))) + series.compliance)


def worst(rows):
    return max(r[0] for r in rows), max(r[1] for r in rows)


def loop_and_pair() -> None:
    for ratio in RATIOS:
        looped, fixed = [], []
        for q in (1.1, 1.2, 1.5, 2.0, 3.0):
            d = design_of(q, ratio)
            pair = series_at(d, modulus_function(d), REFERENCE_FREQUENCY, d.drive(REFERENCE_STRAIN))
            for strain in STRAINS:
                for f in FREQUENCIES:
                    x = d.drive(strain)
                    k0 = complex(stiffness(d, f, x).stiffness[0, 0])
                    lp = loop(d, f, x, 512)
                    looped.append(gap(first_harmonic(lp.phase, lp.force, x), k0))
                    fixed.append(gap(describing(d, pair, f, x), k0))
        (lk, le), (fk, fe) = worst(looped), worst(fixed)
        print(f"K/µ {ratio:5d}: loop {100 * lk:.4f} % {le:.5f}   fixed pair {100 * fk:.3f} % {fe:.4f}", flush=True)


def element() -> None:
    steps, periods = 400, 4
    for ratio in (None, *RATIOS):
        rows = []
        for q in (1.2, 1.5, 3.0):
            d = design_of(q, ratio, min(0.09, 10 * 0.02 * (q - 1)))
            for f in FREQUENCIES:
                for strain in STRAINS:
                    x = d.drive(strain)
                    el = Element.from_design(d, 1, band=(0.1, 200.0), channels=("dx",))
                    theta = 2 * np.pi * np.arange(1, periods * steps + 1) / steps
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        force = np.array([el.commit([x * np.sin(t)], 1 / (f * steps))[0] for t in theta])[-steps:]
                    k = first_harmonic(theta[-steps:], force - force.mean(), x)
                    rows.append(gap(k, complex(stiffness(d, f, x).stiffness[0, 0])))
        k, e = worst(rows)
        print(f"element, K/µ {ratio or 'none':>5}: {100 * k:.3f} % {e:.4f}", flush=True)


if __name__ == "__main__":
    loop_and_pair()
    if "--element" in sys.argv[1:]:
        element()
