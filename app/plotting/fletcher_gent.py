"""The Fletcher–Gent tab's plots: Re K and the loss factor against amplitude, branch by branch,
and the loop's shape.
"""

from __future__ import annotations

import holoviews as hv
import numpy as np

from core import Design

from .. import curves
from .style import (
    BRANCH_COLORS,
    REFERENCE_STYLE,
    curve,
    dimensions,
    marker,
    overlay,
    ranged,
    sized,
    styled,
)


def branch_overlays(data: dict, dims: dict, at: float, reference: dict | None = None) -> dict:
    """Re K and the loss factor against amplitude as stacked areas, branch by branch
    (:func:`app.curves.branch_breakdown`); ``reference`` the pinned reference's breakdown at the
    same amplitudes, its totals drawn dashed, if any."""
    out = {}
    for which, title, ydim in (("real", "Re K, branch by branch (stacked)", dims["real"]),
                               ("loss", "Loss factor, branch by branch (stacked)", dims["branch_loss"])):
        areas = []
        base = np.zeros_like(data["amplitude"])
        for name, color in BRANCH_COLORS.items():
            top = base + data[which][name]
            areas.append(styled("Area", (data["amplitude"], top, base), kdims=[dims["amplitude"]],
                                vdims=[ydim, hv.Dimension(f"{which}_base")], label=name, color=color,
                                fill_alpha=0.55, line_alpha=0))
            base = top
        if reference is not None:
            areas.append(curve(data["amplitude"], sum(reference[which].values()), dims["amplitude"], ydim,
                               "reference", **REFERENCE_STYLE))
        areas.append(marker(at, dims["amplitude"]))
        out[which] = overlay(areas, title, f"bushing-branches-{which}", logx=True, legend="top_left")
    return out


def loop_shape_overlay(lp: dict, dims: dict, title: str = "Loop shape during the amplitude sweep") -> hv.Overlay:
    """A loop scaled to its peak drive and peak force, branch by branch: its shape alone."""
    x = lp["displacement"] / np.max(np.abs(lp["displacement"]))
    peak = np.max(np.abs(lp["force"]))
    # scaled to ±1: the same axes for every loop
    scaled = ranged(dims, {"drive_rel": (-1.05, 1.05), "force_rel": (-1.1, 1.1)})
    xd, fd = scaled["drive_rel"], scaled["force_rel"]
    items = [curve(x, lp["force"] / peak, xd, fd, "total", color="black", line_width=2.5)]
    items += [curve(x, lp[f"force_{name}"] / peak, xd, fd, name, color=color, line_width=1.5)
              for name, color in BRANCH_COLORS.items()]
    return overlay(items, title, "bushing-loop-shape", legend="top_left", height=420)


def branch_plots(design: Design, frequency_hz: float = 10.0, amplitude: float | None = None, n: int = 80, *,
                 width: int | None = 600) -> hv.Layout:
    """The Fletcher–Gent effect branch by branch at one frequency, and the loop's shape.

    Parameters
    ----------
    design : Design
        The bushing, in SI units; its stiffness-level effects are left out (the material model).
    frequency_hz : float, default 10.0
        The frequency in Hz.
    amplitude : float or None, default None
        The loop's amplitude and the marker's place, in display units: mm (axial, radial) or
        rad (torsion, conical); None: mid-way through the Fletcher–Gent range.
    n : int, default 80
        The count of amplitudes on the axis.
    width : int or None, default 600
        The width of each plot in pixels; None: as wide as its container.

    Returns
    -------
    holoviews.Layout
        Three plots in one column: Re K (kN/mm or N·m/rad) and the loss factor (dimensionless)
        against amplitude (mm or rad), stacked branch by branch; the loop scaled to its peak
        drive and force (dimensionless).
    """
    at = amplitude if amplitude is not None else float(curves.fletcher_gent_amplitudes(design)[2])
    dims = dimensions(design.mode)
    overlays = branch_overlays(curves.branch_breakdown(design, frequency_hz, curves.amplitude_grid(design, n)), dims, at)
    shape = loop_shape_overlay(curves.hysteresis_loop(design, frequency_hz, at), dims)
    return sized(hv.Layout([*overlays.values(), shape]).cols(1), width)
