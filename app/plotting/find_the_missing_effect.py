"""The Find the missing effect tab's plots: a diagnosis (:mod:`core.identify.diagnose`) step by
step, the curves of the data and both models, the misfit maps before and after.
"""

from __future__ import annotations

import holoviews as hv
import numpy as np

from .. import curves, report_curves, units
from .style import (
    amplitude_curves,
    dimensions,
    overlay,
    ranged,
    sized,
    styled,
)

MISFIT_PNG = {"magnitude_pct": "magnitude", "loss_factor": "loss"}


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
    return amplitude_curves(groups, dims, (("baseline", "baseline", {"line_dash": "dashed", "line_width": 1.5}),
                                           ("final", "final", {"line_width": 2})),
                            "data, baseline and final model", "bushing-diagnosis")


def misfit_map(m: dict, column: str, title: str, dims: dict, limit: float, png: str) -> hv.Overlay:
    """A misfit over the (frequency, amplitude) plane: one square per measured point, coloured
    on a diverging scale from −``limit`` to +``limit`` (red: model above the data). The scale is
    the colour dimension's range (not an option): maps of one look with other limits are drawn
    alike, their numbers written into the plot shown (:mod:`app.live`)."""
    zdim = dims["misfit_magnitude" if column == "magnitude_pct" else "misfit_loss"].clone(range=(-limit, limit))
    pts = styled("Points", (np.asarray(m["frequency_hz"], dtype=float), np.asarray(m["amplitude"], dtype=float),
                            np.asarray(m[column], dtype=float)),
                 kdims=[dims["frequency"], dims["amplitude"]], vdims=[zdim], color=zdim.name, cmap="RdBu_r",
                 marker="square", size=11, colorbar=True, line_color="#777777", line_width=0.5,
                 tools=["hover"])
    return overlay([pts], title, png, logy=True, legend=None, height=260)


def report_overlays(stages: dict, groups: list, misfits: dict, mode: str) -> dict:
    """The report's plots from their data (display units): ``"gap"`` (one plot: the gap after each
    step, ``stages`` as :func:`app.report_curves.gap_stages`), ``"curves"`` (|K| and the loss factor:
    data, baseline, final model; ``groups`` as :func:`app.report_curves.curve_groups`) and ``"maps"``
    (the misfit before, then after: |K| in % and the loss factor each, on one colour scale per
    quantity; ``misfits``: "baseline" and "final", each as :func:`app.report_curves.misfit_points`);
    ``"groups"`` the curves' amplitude groups."""
    base, final = misfits["baseline"], misfits["final"]
    ranges = {"gap": (0.0, 1.1 * max(float(np.max(stages["gap"])), stages["noise"] or 0.0) or 1.0),
              "amplitude": curves.padded([final["amplitude"]], log=True)}
    for i, quantity in enumerate(("magnitude", "loss_factor")):  # the data and both models in view
        ranges[quantity] = curves.padded([v for g in groups for v in (g["data"][i], g["baseline"][i], g["final"][i])])
    dims = ranged(dimensions(mode), ranges)
    maps = []
    for which, m in (("baseline", base), ("final", final)):
        for column, name in (("magnitude_pct", "|K| misfit (%)"), ("loss_factor", "loss-factor misfit")):
            limit = float(np.max(np.abs(base[column]))) or 1.0  # one colour scale for before and after
            maps.append(misfit_map(m, column, f"{which.capitalize()}: {name}", dims, limit,
                                   f"bushing-misfit-{which}-{MISFIT_PNG[column]}"))
    return {"gap": [gap_bars(stages, dims)], "curves": list(diagnosis_curves(groups, dims).values()),
            "maps": maps, "groups": groups}


def diagnosis_overlays(diagnosis) -> dict:
    """The plots of a :class:`core.identify.diagnose.Diagnosis` (:func:`report_overlays`)."""
    return report_overlays(report_curves.gap_stages(diagnosis), report_curves.curve_groups(diagnosis),
                           {which: report_curves.misfit_points(diagnosis, which) for which in ("baseline", "final")},
                           diagnosis.final.design.mode)


def pending_overlays(data, mode: str) -> dict:
    """The plots a diagnosis of ``data`` (a :class:`core.data.MeasuredStiffness`, the rows of ``mode``)
    will have, before it has run: the report's elements, labels and styles (one curve per measured
    amplitude), both models standing at the data and no misfit. Built while the data wait to be
    diagnosed, so that the report's numbers are then written into plots that exist
    (:meth:`app.live.LivePlot.show`); never shown."""
    groups = curves.amplitude_groups(data, mode, {"baseline": data.stiffness, "final": data.stiffness})
    none = {"frequency_hz": data.frequency_hz, "amplitude": units.display_amplitude(data.amplitude, mode),
            "magnitude_pct": np.zeros(len(data)), "loss_factor": np.zeros(len(data))}
    return report_overlays({"stage": ["baseline"], "gap": np.zeros(1), "noise": 0.0}, groups,
                           {"baseline": none, "final": none}, mode)


def diagnosis_plots(diagnosis, *, width: int | None = 560) -> hv.Layout:
    """The plots of a diagnosis: the gap after each step, the curves, the misfit maps.

    Parameters
    ----------
    diagnosis : Diagnosis
        A :class:`core.identify.diagnose.Diagnosis` (SI inside).
    width : int or None, default 560
        The width of each plot in pixels; None: as wide as its container.

    Returns
    -------
    holoviews.Layout
        In two columns: the gap after each step (dimensionless); |K| (kN/mm or N·m/rad) and the
        loss factor (dimensionless) of the data, the baseline and the final model; the misfit
        maps before and after (|K| in %, the loss factor dimensionless) over frequency (Hz) and
        amplitude (mm or rad).
    """
    overlays = diagnosis_overlays(diagnosis)
    return sized(hv.Layout(overlays["gap"] + overlays["curves"] + overlays["maps"]).cols(2), width)
