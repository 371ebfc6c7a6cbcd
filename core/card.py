"""The bushing card: the dynamic stiffness in every direction at one operating point.

Axial and radial at a displacement amplitude, torsion and conical at an angle amplitude, all from
the same material and geometry, each direction with the shape factor the design file's rule gives
it (docs/files.md): the thesis' closed forms for axial and torsion unless the design's ``shape``
is ``finite``, the finite-length table for radial and conical always (the plane-strain radial
formula is about twice too stiff for real lengths). Plus the ratios
engineers quote: radial / axial, and radial / the torsion-equivalent translational stiffness
K_torsion / r_m², r_m = (a + b)/2 (the circumferential stiffness at the mean radius).
"""

from __future__ import annotations

import math

import numpy as np

from .bushing import factors, stiffness_points
from .design import Design
from .parameters import ROTATIONS, THESIS_MODES, TRANSLATIONS
from .response import loss_factor

CARD_MODES = TRANSLATIONS + ROTATIONS  # axial, radial, torsion, conical


def card_design(design: Design, mode: str) -> Design:
    """``design`` in ``mode`` with the card's shape factor: the closed forms (``long``) for axial
    and torsion unless ``design``'s ``shape`` is ``finite``, the finite-length table for radial and
    conical (a test rig's apparent mass stays with its own mode, as
    :meth:`core.design.Design.in_mode` keeps it)."""
    shape = "long" if mode in THESIS_MODES and design.shape != "finite" else "finite"
    return design.replace(mode=mode, shape=shape, effects=design.portable_effects)


def card(design: Design, frequency_hz: float, displacement: float, angle: float) -> list[dict]:
    """One row per direction: mode, amplitude (m or rad), the complex stiffness, |K|, the loss
    factor and the shape factor used (m or m³)."""
    rows = []
    for mode in CARD_MODES:
        d = card_design(design, mode)
        x = displacement if mode in TRANSLATIONS else angle
        k = complex(stiffness_points(d, frequency_hz, x))
        rows.append({"mode": mode, "amplitude": float(x), "stiffness_real": k.real, "stiffness_imag": k.imag,
                     "magnitude": abs(k), "loss_factor": float(loss_factor(np.array([k]))[0]),
                     "shape_factor": factors(d)[0]})
    return rows


def against_incompressible(design: Design, frequency_hz: float, rows: list[dict]) -> dict[str, tuple[float, float]]:
    """How far each direction of the card (:func:`card`'s ``rows`` at ``frequency_hz``) lies
    from the same bushing of an incompressible rubber: the relative change of |K| and of the
    loss factor, by mode. The limit is the stiffness at µ/K = 0 (``bulk_modulus`` ∞ in
    :func:`core.bushing.stiffness_points`: the series law's real factor on S·µ_eq, with µ_eq at
    the whole drive's strain in the shear layer); a design without ``bulk_modulus`` has
    K = 5000 µ."""
    out = {}
    for r in rows:
        d = card_design(design, r["mode"])
        k = complex(stiffness_points(d, frequency_hz, r["amplitude"], bulk_modulus=math.inf))
        eta = float(loss_factor(np.array([k]))[0])
        out[r["mode"]] = (r["magnitude"] / abs(k) - 1.0, r["loss_factor"] / eta - 1.0)
    return out


def ratios(design: Design, rows: list[dict]) -> dict[str, float]:
    """radial/axial and radial/(K_torsion / r_m²) of the card's |K|."""
    k = {r["mode"]: r["magnitude"] for r in rows}
    r_m = 0.5 * (design.geometry.inner_radius + design.geometry.outer_radius)
    return {"radial/axial": k["radial"] / k["axial"], "radial/torsion-equivalent": k["radial"] / (k["torsion"] / r_m**2)}
