"""Model against measured data, as HoloViews elements: the residuals at every measured point, a
fit's predicted rows, and a diagnosis (:mod:`core.identify.diagnose`) step by step. The design
functions of :mod:`app.plots` lay them out; the measured-data and diagnosis tabs draw them live.
"""

from __future__ import annotations

import holoviews as hv
import numpy as np

from core.parameters import MODES

from . import curves
from .elements import (
    MODE_COLORS,
    OPERATING_COLOR,
    SWEEP_PALETTES,
    curve,
    dimensions,
    overlay,
    ranged,
    scatter,
    styled,
    sweep_label,
)


def residual_overlays(points: dict | None, residuals: dict | None, dims: dict) -> dict:
    """Model − measured at every measured point: |K| in % and the loss factor, against
    frequency and amplitude (``points`` from :func:`app.curves.measured_points`, ``residuals`` as
    :meth:`app.state.ExplorerState.measured_residuals`)."""
    out = {}
    for against in ("frequency", "amplitude"):
        x = [] if points is None else points["frequency_hz" if against == "frequency" else "amplitude"]
        for quantity, ydim, column in (("magnitude", dims["residual_magnitude"], "magnitude_residual_pct"),
                                       ("loss", dims["residual_loss"], "loss_factor_residual")):
            y = [] if residuals is None else residuals[column]
            title = f"{ydim.label}, model − measured, against {against}"
            out[(quantity, against)] = overlay(
                [scatter(x, y, dims[against], ydim, "residual", color=OPERATING_COLOR, alpha=0.7, size=6)],
                title, f"bushing-residual-{quantity}-vs-{against}", logx=against == "amplitude", legend=None,
                height=240)
    return out


def gap_bars(stages: dict, dims: dict) -> hv.Overlay:
    """The gap after each step of a diagnosis as bars, with the noise level (dashed)."""
    bars = styled("Bars", (list(stages["stage"]), np.asarray(stages["gap"], dtype=float)),
                  kdims=[dims["stage"]], vdims=[dims["gap"]], color="#3182bd", bar_width=0.6, tools=["hover"])
    items = [bars]
    if stages.get("noise") is not None:
        items.append(styled("HLine", float(stages["noise"]), kdims=[hv.Dimension("x"), dims["gap"]],
                            color="#d62728", line_dash="dashed", line_width=2))
    return overlay(items, "Gap (relative RMS misfit of complex stiffness) after each step", "bushing-diagnosis-gap",
                   legend=None, height=230)


def diagnosis_curves(groups: list, dims: dict) -> dict:
    """Data (points) against the baseline (dashed) and the final model (solid), one colour per
    amplitude, for |K| and the loss factor (``groups`` as
    :meth:`app.diagnosis_state.DiagnosisState.curves`)."""
    palette = SWEEP_PALETTES["amplitude"]
    out = {}
    for i, (quantity, ydim) in enumerate((("magnitude", dims["magnitude"]), ("loss", dims["loss_factor"]))):
        items = []
        for n, g in enumerate(groups):
            color = palette[n % len(palette)]
            label = sweep_label(g["amplitude"], dims["amplitude"].unit)
            items.append(curve(g["frequency_hz"], g["baseline"][i], dims["frequency"], ydim, f"{label} baseline",
                               color=color, line_dash="dashed", line_width=1.5))
            items.append(curve(g["frequency_hz"], g["final"][i], dims["frequency"], ydim, f"{label} final",
                               color=color, line_width=2))
            items.append(scatter(g["frequency_hz"], g["data"][i], dims["frequency"], ydim, f"{label} data",
                                 color=color, size=6, alpha=0.8))
        out[quantity] = overlay(items, f"{ydim.label}: data, baseline and final model",
                                f"bushing-diagnosis-{quantity}", legend=None, height=280)
    return out


MISFIT_PNG = {"magnitude_pct": "magnitude", "loss_factor": "loss"}


def misfit_map(m: dict, column: str, title: str, dims: dict, limit: float, png: str) -> hv.Overlay:
    """A misfit over the (frequency, amplitude) plane: one square per measured point, coloured
    on a diverging scale from −``limit`` to +``limit`` (red: model above the data)."""
    zdim = dims["misfit_magnitude" if column == "magnitude_pct" else "misfit_loss"]
    pts = styled("Points", (np.asarray(m["frequency_hz"], dtype=float), np.asarray(m["amplitude"], dtype=float),
                            np.asarray(m[column], dtype=float)),
                 kdims=[dims["frequency"], dims["amplitude"]], vdims=[zdim], color=zdim.name, cmap="RdBu_r",
                 marker="square", size=11, colorbar=True, line_color="#777777", line_width=0.5,
                 clim=(-limit, limit), tools=["hover"])
    return overlay([pts], title, png, logy=True, legend=None, height=260)


def diagnosis_overlays(diagnosis) -> dict:
    """The plots of a :class:`core.identify.diagnose.Diagnosis`: ``"gap"`` (one plot: the gap after each
    step), ``"curves"`` (|K| and the loss factor: data, baseline, final model) and ``"maps"``
    (the misfit before, then after: |K| and the loss factor each, on one colour scale per
    quantity); ``"groups"`` the curves' amplitude groups (:func:`app.curves.curve_groups`)."""
    stages = curves.gap_stages(diagnosis)
    groups = curves.curve_groups(diagnosis)
    base, final = curves.misfit_points(diagnosis, "baseline"), curves.misfit_points(diagnosis, "final")
    ranges = {"gap": (0.0, 1.1 * max(float(np.max(stages["gap"])), stages["noise"] or 0.0)),
              "amplitude": curves.padded([final["amplitude"]], log=True)}
    for i, quantity in enumerate(("magnitude", "loss_factor")):  # the data and both models in view
        ranges[quantity] = curves.padded([v for g in groups for v in (g["data"][i], g["baseline"][i], g["final"][i])])
    dims = ranged(dimensions(diagnosis.final.design.mode), ranges)
    maps = []
    for which, m in (("baseline", base), ("final", final)):
        for column, name in (("magnitude_pct", "|K| misfit (%)"), ("loss_factor", "loss-factor misfit")):
            limit = float(np.max(np.abs(base[column]))) or 1.0  # one colour scale for before and after
            maps.append(misfit_map(m, column, f"{which.capitalize()}: {name}", dims, limit,
                                   f"bushing-misfit-{which}-{MISFIT_PNG[column]}"))
    return {"gap": [gap_bars(stages, dims)], "curves": list(diagnosis_curves(groups, dims).values()),
            "maps": maps, "groups": groups}


def prediction_overlay(data: dict) -> hv.Overlay:
    """A fit on a subset predicting the rest (:func:`app.curves.prediction_misfit`): the |K|
    misfit of every mode against frequency, fitted rows filled, predicted rows hollow."""
    xdim = dimensions(MODES[0])["frequency"]  # the same in every mode
    ydim = hv.Dimension("prediction_misfit", label="|K|, model − measured", unit="%")
    items = []
    for mode, parts in data.items():
        color = MODE_COLORS.get(mode, OPERATING_COLOR)
        for which, fill in (("fitted", 0.8), ("predicted", 0.0)):
            part = parts[which]
            if len(part["frequency_hz"]):
                items.append(scatter(part["frequency_hz"], part["misfit_pct"], xdim, ydim,
                                     f"{mode}, {which}", color=color, fill_alpha=fill, line_color=color, size=6))
    return overlay(items, "Fitted and predicted rows, every mode: |K| misfit", "bushing-prediction", height=300)