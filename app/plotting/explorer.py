"""The Explorer tab's plots: the hysteresis loop at the operating point, and |K| and the loss
factor against frequency and amplitude (the sweeps, the operating curve, a reference, measured
points, a tolerance band, the operating point's marker).
"""

from __future__ import annotations

import functools

import holoviews as hv
import numpy as np
from param.parameterized import shared_parameters

from core import Design

from .. import curves
from .style import (
    BRANCH_COLORS,
    MEASURED_STYLE,
    OPERATING_COLOR,
    REFERENCE_STYLE,
    SWEEP_PALETTES,
    axis_dimension,
    band_area,
    band_label,
    curve,
    dimensions,
    marker,
    overlay,
    ranged,
    scatter,
    sized,
    sweep_label,
)

TITLES = {
    ("magnitude", "frequency"): "|K| against frequency",
    ("loss_factor", "frequency"): "Loss factor against frequency",
    ("magnitude", "amplitude"): "|K| against amplitude",
    ("loss_factor", "amplitude"): "Loss factor against amplitude",
}


LOOP_TITLE = "Hysteresis loop at the operating point"

def strain_label(ratio: float) -> str:
    """The legend of a frequency sweep: its equivalent strain as a multiple of ε½ (the same for
    every design, so a legend never changes while the design does)."""
    return "ε̂ = ε½" if ratio == 1 else f"ε̂ = {ratio:g} ε½"


def loop_overlay(lp: dict, dims: dict, *, reference: dict | None = None, measured: dict | None = None,
                 title: str = LOOP_TITLE) -> hv.Overlay:
    """The hysteresis loop (:func:`app.curves.hysteresis_loop`) branch by branch, a reference
    loop (dashed) and measured points, on ``dims`` (:func:`dimensions`)."""
    x, f = dims["displacement"], dims["force"]
    items = [curve(lp["displacement"], lp[f"force_{name}"], x, f, name, color=color, line_width=1.5)
             for name, color in BRANCH_COLORS.items()]
    if reference is not None:
        items.append(curve(reference["displacement"], reference["force"], x, f, "reference", **REFERENCE_STYLE))
    items.append(curve(lp["displacement"], lp["force"], x, f, "total", color="black", line_width=2.5))
    if measured is not None:
        items.append(scatter(measured["displacement"], measured["force"], x, f, "measured", color="#222222",
                             alpha=0.5, size=4))
    return overlay(items, title, "bushing-hysteresis-loop", legend="top_left", height=330)


def sweep_curves(quantity: str, against: str, sweep: dict, dims: dict, labels) -> list:
    """One curve per swept value: |K| or the loss factor against frequency (a row per
    amplitude) or against amplitude (a row per frequency)."""
    x = sweep["frequency_hz"] if against == "frequency" else sweep["amplitude"]
    palette = SWEEP_PALETTES["amplitude" if against == "frequency" else "frequency"]
    return [curve(x, row, dims[against], dims[quantity], label, color=palette[i % len(palette)], line_width=1.3)
            for i, (row, label) in enumerate(zip(sweep[quantity], labels))]


def _x_of(against: str, sweep: dict):
    """The x values of a sweep (:func:`app.curves.frequency_sweep`, :func:`app.curves.amplitude_sweep`)
    on a plot against ``against``."""
    return sweep["frequency_hz"] if against == "frequency" else sweep["amplitude"]


def operating_curve(quantity: str, against: str, operating: dict, dims: dict) -> hv.Curve:
    """The curve through the operating point (``operating``, a one-row sweep)."""
    return curve(_x_of(against, operating), operating[quantity][0], dims[against], dims[quantity], "operating point",
                 color=OPERATING_COLOR, line_width=3)


def sweep_overlay(quantity: str, against: str, sweep_items: list, dims: dict, *, operating: dict | hv.Curve,
                  at: float | hv.VLine, reference: dict | None = None, measured: dict | None = None,
                  band: tuple | None = None, band_name: str = "") -> hv.Overlay:
    """|K| or the loss factor against ``against`` ("frequency" or "amplitude"): the sweeps
    (:func:`sweep_curves`), the tolerance band of the operating curve (``band``: low, high), the
    curve through the operating point (``operating``, a one-row sweep, or its curve made
    already), a reference design's (dashed), measured points and the marker at ``at`` (or the
    marker made already)."""
    xdim, ydim = dims[against], dims[quantity]
    items = list(sweep_items)
    if band is not None:
        x = operating.dimension_values(0) if isinstance(operating, hv.Curve) else _x_of(against, operating)
        items.append(band_area(x, *band, xdim, ydim, band_name, OPERATING_COLOR))
    if reference is not None:
        items.append(curve(_x_of(against, reference), reference[quantity][0], xdim, ydim, "reference", **REFERENCE_STYLE))
    items.append(operating if isinstance(operating, hv.Curve) else operating_curve(quantity, against, operating, dims))
    if measured is not None:
        items.append(scatter(_x_of(against, measured), measured[quantity], xdim, ydim, "measured", **MEASURED_STYLE))
    items.append(at if isinstance(at, hv.VLine) else marker(at, xdim))
    return overlay(items, TITLES[(quantity, against)], f"bushing-{quantity}-vs-{against}",
                   logx=against == "amplitude")


@functools.lru_cache(maxsize=64)
def sweep_layer(design: Design, freq_range: tuple[float, float], quantity: str, against: str,
                ranges: tuple, n_freq: int = 120, n_amp: int = 120) -> tuple:
    """The sweep curves of one plot of ``design`` (:func:`sweep_curves`: |K| or the loss factor
    against frequency at the sweep amplitudes, or against amplitude at the sweep frequencies) on
    axes of ``ranges`` ((x start, end), (y start, end), display units).

    Cached on these values: they change with the design, the sweep range and the axes, not with
    the operating point, and a change of the operating point finds the same curves (objects a
    live plot sends no data for)."""
    dims = {against: axis_dimension(design.mode, against, ranges[0]),
            quantity: axis_dimension(design.mode, quantity, ranges[1])}
    if against == "frequency":
        sweep = curves.frequency_sweep(design, np.linspace(*freq_range, n_freq), curves.sweep_amplitudes(design))
        labels = [strain_label(r) for r in curves.SWEEP_STRAINS]
    else:
        sweep = curves.amplitude_sweep(design, curves.amplitude_grid(design, n_amp),
                                       curves.sweep_frequencies(*freq_range))
        labels = [sweep_label(v, "Hz") for v in sweep["frequency_hz"]]
    return tuple(sweep_curves(quantity, against, sweep, dims, labels))


@functools.lru_cache(maxsize=64)
def operating_layer(design: Design, freq_range: tuple[float, float], quantity: str, against: str, ranges: tuple,
                    at: float, n_freq: int = 120, n_amp: int = 120) -> hv.Curve:
    """The curve through the operating point on one plot of ``design`` (:func:`operating_curve`:
    |K| or the loss factor against frequency at the operating amplitude ``at``, or against
    amplitude at the operating frequency ``at``), on axes of ``ranges`` as :func:`sweep_layer`'s.

    Cached on these values, as the sweeps are: moving the operating amplitude leaves the curves
    against amplitude as they were (the same objects: a live plot sends them no data), and the
    frequency likewise the curves against frequency."""
    dims = {against: axis_dimension(design.mode, against, ranges[0]),
            quantity: axis_dimension(design.mode, quantity, ranges[1])}
    if against == "frequency":
        operating = curves.frequency_sweep(design, np.linspace(*freq_range, n_freq), at)
    else:
        operating = curves.amplitude_sweep(design, curves.amplitude_grid(design, n_amp), at)
    return operating_curve(quantity, against, operating, dims)


@functools.lru_cache(maxsize=64)
def marker_layer(mode: str, against: str, x_range: tuple, at: float) -> hv.VLine:
    """The operating point's marker at ``at`` on an axis ``against`` of ``x_range`` (:func:`marker`),
    cached on these values: a change that leaves the operating point's coordinate on this axis
    finds the same object."""
    return marker(at, axis_dimension(mode, against, x_range))


def explorer_overlays(data: curves.ExplorerData, dims: dict | None = None) -> dict:
    """The five plots of ``data`` (:func:`app.curves.explorer_data`): ``"loop"`` and one per (quantity,
    against) of :data:`TITLES`. ``dims`` are the dimensions to draw on (a live view passes its
    own, so that its plots keep their axes); the plots carry the data's ranges on clones of them
    (:func:`app.plotting.style.ranged`), ``dims`` are left as they are. The sweeps' curves come
    from :func:`sweep_layer` (the same objects while the design, the sweep range and the axes
    are), and so do the operating curves (:func:`operating_layer`) and the markers
    (:func:`marker_layer`): a change of the operating point builds only what it moves."""
    # param deep-copies the default of each instantiated parameter of every element and dimension
    # made (lists and dicts that HoloViews replaces or never changes in place): shared while these
    # are made, copied once (measured: a tenth of the server's CPU per amplitude change)
    with shared_parameters():
        return _explorer_overlays(data, dims)


def _explorer_overlays(data: curves.ExplorerData, dims: dict | None) -> dict:
    dims = ranged(dims if dims is not None else dimensions(data.mode), data.ranges)
    out = {"loop": loop_overlay(data.loop, dims, reference=data.reference_loop, measured=data.measured_loop)}
    n_freq, n_amp = (len(data.sweeps[k][c]) for k, c in (("frequency", "frequency_hz"), ("amplitude", "amplitude")))
    for (quantity, against) in TITLES:
        ranges = (tuple(dims[against].range), tuple(dims[quantity].range))
        items = sweep_layer(data.design, data.freq_range, quantity, against, ranges, n_freq, n_amp)
        other, at = (data.amplitude, data.frequency_hz) if against == "frequency" else (data.frequency_hz, data.amplitude)
        out[(quantity, against)] = sweep_overlay(
            quantity, against, items, dims,
            operating=operating_layer(data.design, data.freq_range, quantity, against, ranges, float(other), n_freq, n_amp),
            at=marker_layer(data.mode, against, ranges[0], float(at)),
            reference=data.references[against] if data.references else None, measured=data.measured,
            band=data.bands[against][quantity] if data.bands else None,
            band_name=band_label(data.bands["point"]["percentiles"]) if data.bands else "")
    return out


def explorer_plots(design: Design, frequency_hz: float = 10.0, amplitude: float | None = None, *,
                   width: int | None = 600, **kwargs) -> hv.Layout:
    """The explorer's five plots of ``design`` at an operating point.

    The hysteresis loop, then |K| and the loss factor against frequency and against amplitude.
    The design is SI (m, Pa); the plots and ``amplitude`` are in the display units of
    :mod:`app.units`.

    Parameters
    ----------
    design : Design
        The bushing, in SI units.
    frequency_hz : float, default 10.0
        The operating frequency in Hz.
    amplitude : float or None, default None
        The operating amplitude in display units: mm (axial, radial) or rad (torsion,
        conical); None: mid-way through the Fletcher–Gent range.
    width : int or None, default 600
        The width of each plot in pixels; None: as wide as its container.
    **kwargs
        As :func:`app.curves.explorer_data`: ``freq_range`` (Hz), ``reference`` (a Design),
        ``measured`` (a MeasuredStiffness, SI: Hz, m or rad, N/m or N·m/rad), ``measured_loop``
        (a MeasuredLoop, SI: s, m or rad, N or N·m), ``n_freq`` and ``n_amp`` (point counts),
        ``bands`` (tolerance bands in display units).

    Returns
    -------
    holoviews.Layout
        Five plots in two columns: the loop (drive in mm or rad, force in N or N·m), and |K|
        (kN/mm or N·m/rad) and the loss factor (dimensionless) against frequency (Hz) and
        amplitude (mm or rad).
    """
    if amplitude is None:
        amplitude = float(curves.fletcher_gent_amplitudes(design)[2])
    overlays = explorer_overlays(curves.explorer_data(design, frequency_hz, amplitude, **kwargs))
    return sized(hv.Layout([overlays["loop"], *(overlays[k] for k in TITLES)]).cols(2), width)
