"""The Slices tab's plots: Paper A's sliced bushing against the single equivalent modulus."""

from __future__ import annotations

import holoviews as hv

from core import Design

from .. import curves
from .style import (
    REFERENCE_STYLE,
    curve,
    dimensions,
    marker,
    overlay,
    sized,
)

SLICE_COLORS = {1: "#1f77b4", 2: "#ff7f0e", 3: "#2ca02c", "continuum": "#9467bd"}

SLICE_NAMES = {1: "1 slice (eqs 17/18)", 2: "2 slices", 3: "3 slices", "continuum": "continuum"}


def slices_overlays(data: dict, dims: dict, at: float, reference: dict | None = None) -> dict:
    """Paper A's comparison (:func:`app.curves.slice_comparison`) as three plots against
    amplitude: |K|, its difference from the single modulus in %, and the loss factor;
    ``reference`` the pinned reference's single-modulus |K| and loss factor at the same
    amplitudes (:func:`app.curves.branch_breakdown`), drawn dashed, if any."""
    specs = {"magnitude": ("|K|: single modulus, slices and continuum", dims["magnitude"], (1, 2, 3, "continuum")),
             "magnitude_diff_pct": ("|K| difference from the single modulus (%)", dims["difference"], (2, 3, "continuum")),
             "loss_factor": ("Loss factor", dims["loss_factor"], (1, 2, 3, "continuum"))}
    out = {}
    for which, (title, ydim, models) in specs.items():
        items = []
        for m in models:
            y = data[which].get(m)
            items.append(curve(data["amplitude"] if y is not None else [], y if y is not None else [],
                               dims["amplitude"], ydim, SLICE_NAMES[m], color=SLICE_COLORS[m], line_width=2))
        if reference is not None and which in reference:
            items.append(curve(data["amplitude"], reference[which], dims["amplitude"], ydim, "reference",
                               **REFERENCE_STYLE))
        items.append(marker(at, dims["amplitude"]))
        out[which] = overlay(items, title, f"bushing-slices-{which}", logx=True, height=280)
    return out


def slices_plots(design: Design, frequency_hz: float = 10.0, amplitude: float | None = None, n: int = 60, *,
                 width: int | None = 800) -> hv.Layout:
    """One equivalent modulus against 2 and 3 slices and the continuum (Paper A), at one frequency.

    Parameters
    ----------
    design : Design
        The bushing, in SI units; its stiffness-level effects are left out (the material model).
    frequency_hz : float, default 10.0
        The frequency in Hz.
    amplitude : float or None, default None
        Where the marker stands, in display units: mm (axial, radial) or rad (torsion,
        conical); None: mid-way through the Fletcher–Gent range.
    n : int, default 60
        The count of amplitudes on the axis.
    width : int or None, default 800
        The width of each plot in pixels; None: as wide as its container.

    Returns
    -------
    holoviews.Layout
        Three plots in one column against amplitude (mm or rad): |K| (kN/mm or N·m/rad), its
        difference from the single modulus (%), the loss factor (dimensionless).
    """
    data = curves.slice_comparison(design, frequency_hz, curves.amplitude_grid(design, n))
    at = amplitude if amplitude is not None else float(curves.fletcher_gent_amplitudes(design)[2])
    return sized(hv.Layout(list(slices_overlays(data, dimensions(design.mode), at).values())).cols(1), width)
