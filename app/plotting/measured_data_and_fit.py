"""The Measured data and fit tab's plots: the model against measured stiffness at every point,
and a fit on a subset predicting the rest.
"""

from __future__ import annotations

import holoviews as hv

from core import Design
from core.data import MeasuredStiffness
from core.parameters import MODES

from .. import curves
from .style import (
    MODE_COLORS,
    OPERATING_COLOR,
    amplitude_curves,
    dimensions,
    overlay,
    scatter,
    sized,
)


def residual_overlays(points: dict | None, residuals: dict | None, dims: dict) -> dict:
    """Model − measured at every measured point: |K| in % and the loss factor, against
    frequency and amplitude (``points`` from :func:`app.curves.measured_points`, ``residuals`` as
    :func:`app.curves.measured_residuals`)."""
    out = {}
    for against in ("frequency", "amplitude"):
        x = [] if points is None else points["frequency_hz" if against == "frequency" else "amplitude"]
        for quantity, ydim, column in (("magnitude", dims["residual_magnitude"], "magnitude_residual_pct"),
                                       ("loss", dims["residual_loss"], "loss_factor_residual")):
            y = [] if residuals is None else residuals[column]
            title = f"{ydim.label} against {against}"  # (model − measured: the tab's text says)
            out[(quantity, against)] = overlay(
                [scatter(x, y, dims[against], ydim, "residual", color=OPERATING_COLOR, alpha=0.7, size=6)],
                title, f"bushing-residual-{quantity}-vs-{against}", logx=against == "amplitude", legend=None,
                height=240)
    return out


def data_overlays(groups: list, dims: dict) -> dict:
    """The measured points, one colour per amplitude, over the model at those amplitudes: the
    design shown (``"start"``, dashed after a fit) and the fitted one (``"fitted"``, solid);
    ``groups`` as :func:`app.curves.measured_groups`. Keys "magnitude" and "loss"."""
    fitted = bool(groups) and "fitted" in groups[0]
    models = ((("start", "start", {"line_dash": "dashed", "line_width": 1.5}),
               ("fitted", "fitted", {"line_width": 2})) if fitted else (("start", "model", {"line_width": 2}),))
    return amplitude_curves(groups, dims, models, "data (dots), model (lines)",
                            "bushing-measured")


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


def residual_plots(design: Design, measured: MeasuredStiffness, *, width: int | None = 500) -> hv.Layout:
    """The residuals of ``design`` against measured stiffness: model − measured.

    Parameters
    ----------
    design : Design
        The bushing, in SI units; only the measured rows of its mode are drawn.
    measured : MeasuredStiffness
        The measured points, SI (docs/files.md): frequency in Hz, amplitude in m or rad,
        stiffness in N/m or N·m/rad.
    width : int or None, default 500
        The width of each plot in pixels; None: as wide as its container.

    Returns
    -------
    holoviews.Layout
        Four plots in two columns: the |K| residual (%) and the loss-factor residual
        (dimensionless) against frequency (Hz) and amplitude (mm or rad).
    """
    residuals = curves.measured_residuals(design, measured)
    overlays = residual_overlays(curves.measured_points(measured, design.mode), residuals, dimensions(design.mode))
    return sized(hv.Layout(list(overlays.values())).cols(2), width)
