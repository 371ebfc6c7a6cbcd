"""Sensitivities at an operating point: which input moves |K| and the loss factor most.

The elasticity of |K| to a parameter p is ∂ln|K|/∂ln p: +1 % in p moves |K| by that many per
cent. The loss factor η is itself a ratio, so its sensitivity is given as ∂η/∂ln p: +1 % in p
moves η by a hundredth of that. Both are central differences in ln p (step :data:`STEP`, error
of order STEP²), one-sided where the parameter sits at the end of its range (α = 1).

Some are fixed by the model (``docs/model.md``) and checked in the tests: for long bushings
K ∝ L at a given drive (the strain does not depend on L), so ∂ln|K|/∂ln L = 1 and ∂η/∂ln L = 0;
the stresses scale with µ, m and σ_fmax together, so their three elasticities sum to 1.
"""

from __future__ import annotations

import math

import numpy as np

from ..bushing import stiffness_points
from ..design import Design
from ..numbers import format_signed, format_signed_number
from ..parameters import BY_NAME, NAMES
from ..response import loss_factor

STEP = 1e-4  # the step in ln p of the central differences


def log_derivatives(design: Design, frequency_hz, amplitude, names=NAMES,
                    step: float = STEP, **kwargs) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """∂|K|/∂ln p and ∂η/∂ln p of every parameter in ``names`` at the points (``frequency_hz``,
    ``amplitude``, broadcast), by central differences in ln p (one-sided where a step leaves the
    parameter's range). ``kwargs`` go to :func:`core.bushing.stiffness_points`."""
    out = {}
    for name in names:
        p = design.value(name)
        ends = []
        for sign in (1.0, -1.0):
            try:
                k = stiffness_points(design.replace(**{name: p * math.exp(sign * step)}), frequency_hz, amplitude,
                                     **kwargs)
                ends.append((sign * step, k))
            except ValueError:  # beyond the parameter's range (α > 1, b ≤ a, the edge of the
                continue        # finite-length table): one side only (DesignError is a ValueError)
        if len(ends) < 2:
            ends.append((0.0, stiffness_points(design, frequency_hz, amplitude, **kwargs)))
        (h1, k1), (h2, k2) = ends
        out[name] = ((np.abs(k1) - np.abs(k2)) / (h1 - h2), (loss_factor(k1) - loss_factor(k2)) / (h1 - h2))
    return out


def elasticities(design: Design, frequency_hz: float, amplitude: float,
                 names=NAMES) -> dict[str, dict[str, float]]:
    """At one operating point: for every parameter, ``magnitude`` ∂ln|K|/∂ln p and
    ``loss_factor`` ∂η/∂ln p."""
    k = complex(stiffness_points(design, frequency_hz, amplitude))
    return {name: {"magnitude": float(dk) / abs(k), "loss_factor": float(de)}
            for name, (dk, de) in log_derivatives(design, frequency_hz, amplitude, names).items()}


def ranked(values: dict[str, dict[str, float]], quantity: str) -> list[tuple[str, float]]:
    """(parameter, sensitivity) of ``quantity``, the largest in size first."""
    return sorted(((n, v[quantity]) for n, v in values.items()), key=lambda item: -abs(item[1]))


def sentence(values: dict[str, dict[str, float]]) -> str:
    """What dominates, in one sentence: each parameter named in words with its symbol
    ("|K| depends most on the inner radius a"), never a bare symbol that reads as a word."""
    (k1, e1), (k2, e2) = ranked(values, "magnitude")[:2]
    (l1, d1) = ranked(values, "loss_factor")[0]
    n1, n2, n3 = (_named(n) for n in (k1, k2, l1))
    s1, s3 = BY_NAME[k1].symbol, BY_NAME[l1].symbol
    return (f"|K| depends most on {n1} (+1 % in {s1} gives {format_signed(e1, 2)} % in |K|), then on "
            f"{n2} ({format_signed(e2, 2)} %); the loss factor depends most on {n3} "
            f"(+1 % in {s3} moves it by {format_signed_number(d1 / 100, 2)}).")


def _named(name: str) -> str:
    """A parameter in a sentence: "the inner radius a"."""
    label = BY_NAME[name].label
    return f"the {label[0].lower()}{label[1:]}"