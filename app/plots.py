"""HoloViews elements from the state's data: drawing only, no physics.

Every dimension has a name, a label and a unit, so plots that share a dimension share an axis.
"""

from __future__ import annotations

import holoviews as hv
import numpy as np

from .state import AMPLITUDE_DISPLAY, FORCE_DISPLAY, STIFFNESS_DISPLAY

BRANCH_COLORS = {"elastic": "#1f77b4", "viscoelastic": "#2ca02c", "friction": "#d62728"}
SWEEP_COLOR = "#8c9bab"
OPERATING_COLOR = "#e6550d"
REFERENCE_STYLE = {"color": "#444444", "line_dash": "dashed", "line_width": 2}
SLICE_COLORS = {1: "#1f77b4", 2: "#ff7f0e", 3: "#2ca02c", "continuum": "#9467bd"}

FREQUENCY = hv.Dimension("frequency_hz", label="Frequency", unit="Hz")
LOSS = hv.Dimension("loss_factor", label="Loss factor")


def amplitude_dim(mode):
    return hv.Dimension("amplitude", label="Amplitude", unit=AMPLITUDE_DISPLAY[mode][0])


def magnitude_dim(mode):
    return hv.Dimension("magnitude", label="|K|", unit=STIFFNESS_DISPLAY[mode][0])


def displacement_dim(mode):
    label = "Displacement" if mode == "axial" else "Angle"
    return hv.Dimension("displacement", label=label, unit=AMPLITUDE_DISPLAY[mode][0])


def force_dim(mode):
    label = "Force" if mode == "axial" else "Moment"
    return hv.Dimension("force", label=label, unit=FORCE_DISPLAY[mode][0])


def sweep_label(value, unit):
    return f"{value:.3g} {unit}"


# ---- hysteresis loop ----------------------------------------------------------------------


def loop_total(data, mode, label="total"):
    return hv.Curve(
        (data["displacement"], data["force"]), displacement_dim(mode), force_dim(mode), label=label
    )


def loop_branches(data, mode):
    curves = {
        name: hv.Curve(
            (data["displacement"], data[f"force_{name}"]), displacement_dim(mode), force_dim(mode)
        ).opts(color=color)
        for name, color in BRANCH_COLORS.items()
    }
    return hv.NdOverlay(curves, kdims="branch", sort=False)


# ---- stiffness against frequency or amplitude ---------------------------------------------


SWEEP_PALETTES = {  # light to dark with the swept value
    "amplitude": ["#9ecae1", "#6baed6", "#3182bd", "#08519c", "#08306b"],
    "frequency": ["#a1d99b", "#41ab5d", "#006d2c", "#00441b", "#002910"],
}


def sweep_overlay(x, xdim, curves_y, ydim, keys, key_label, unit):
    """Thin curves, one per swept value, coloured light to dark as the value grows."""
    palette = SWEEP_PALETTES[key_label]
    return hv.NdOverlay(
        {
            sweep_label(k, unit): hv.Curve((x, y), xdim, ydim).opts(color=palette[i % len(palette)])
            for i, (k, y) in enumerate(zip(keys, curves_y))
        },
        kdims=hv.Dimension(key_label),
        sort=False,
    )


def operating_curve(x, xdim, y, ydim, label):
    return hv.Curve((x, y), xdim, ydim, label=label)


def marker(value):
    return hv.VLine(value)


# ---- slices -------------------------------------------------------------------------------


def slice_curves(x, mode, values: dict, ydim):
    names = {1: "1 slice (eqs 17/18)", 2: "2 slices", 3: "3 slices", "continuum": "continuum"}
    return hv.NdOverlay(
        {
            names[s]: hv.Curve((x, y), amplitude_dim(mode), ydim).opts(color=SLICE_COLORS[s])
            for s, y in values.items()
        },
        kdims=hv.Dimension("model"),
        sort=False,
    )


# ---- teaching ------------------------------------------------------------------------------


def stacked_areas(x, xdim, parts: dict, ydim):
    """Areas stacked in branch order (hv.Area.stack): the top edge is the total."""
    areas = [
        hv.Area((x, parts[name]), xdim, ydim, label=name).opts(color=color)
        for name, color in BRANCH_COLORS.items()
    ]
    return hv.Area.stack(hv.Overlay(areas))


def normalised_loop(data):
    """Loop in units of its own peaks: the shape, not the size."""
    x = data["displacement"] / np.max(np.abs(data["displacement"]))
    peak = np.max(np.abs(data["force"]))
    dims = (hv.Dimension("x_rel", label="Drive / peak drive"), hv.Dimension("f_rel", label="Force / peak force"))
    curves = {"total": hv.Curve((x, data["force"] / peak), *dims).opts(color="black", line_width=2.5)}
    for name, color in BRANCH_COLORS.items():
        curves[name] = hv.Curve((x, data[f"force_{name}"] / peak), *dims).opts(color=color)
    return hv.NdOverlay(curves, kdims="part", sort=False)
