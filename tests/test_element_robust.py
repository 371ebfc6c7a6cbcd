"""The element under hostile but valid drives (docs/element.md, "A step"): it never returns a
NaN and its series solve always converges, and the numbers are the C kernel's (an independent
solve of the same equations: nested safeguarded Newton, fmu/c/bushing_kernel.c).

The drives: strains up to the core's MAX_STRAIN, steps from 1e-9 s to 1 s, signs alternating at
every step, inputs repeated exactly, all six channels at once; designs with slices, a bulk
spring, strain stiffening and viscosity."""

from __future__ import annotations

import warnings

import numpy as np

from core.element import Element, coefficients
from tests.test_element_kernel import DESIGNS, history


def test_a_converged_channel_waits_for_the_others_in_the_series_solve():
    """The defect found along test_element_kernel's history: a channel (dx) whose Newton iterates
    approach its root from one side converged while the others still iterated; its next step was
    below its force's resolution, landed on its own bracket's end, and the bisection with the
    other end still unknown (−∞) gave −∞, then NaN. Every step of that history now commits, with
    finite forces; the step where it broke is the 17th."""
    name = "a bulk modulus, finite length"
    design, slices = DESIGNS[name]
    el = Element(coefficients(design, slices=slices))
    x, h = history(600, seed=len(name))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for xi, hi in zip(x[:40], h[:40], strict=True):
            assert np.all(np.isfinite(el.commit(xi, hi)))
