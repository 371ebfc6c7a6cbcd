"""The plotting API: HoloViews objects of a bushing design, its operating point and measured data.

Plain functions, the same the explorer draws with; they need no server and work in a notebook::

    import holoviews as hv
    from core import PAPER_B
    from app import plots

    layout = plots.explorer_plots(PAPER_B, frequency_hz=10.0, amplitude=0.1)   # hv.Layout
    hv.save(layout, "paper_b.html")

Every axis is an :class:`holoviews.Dimension` with its name, label and unit
(:func:`app.elements.dimensions`); plots of the same quantity share the dimension, so a layout
links their axes. Axis ranges are set per plot, on clones of the dimensions: nothing built earlier
changes. Importing the API changes nothing global (each plot asks for canvas, not WebGL, itself). Amplitudes are in the display units of :mod:`app.units` (mm axially, rad in
torsion), stiffnesses in kN/mm or N·m/rad, frequencies in Hz.

Two layers: *element builders* (``loop_overlay``, ``sweep_overlay``, …; those of the model against
measured data in :mod:`app.misfit_plots`) turn curves (dicts of arrays from :mod:`app.curves`)
into elements made of :mod:`app.elements`; *design functions* (``explorer_plots``,
``slices_plots``, …) compute the curves of a design and return finished layouts.
"""

from __future__ import annotations

import holoviews as hv
import numpy as np

from core import Design
from core.data import MeasuredStiffness
from core.parameters import ROTATIONS, TRANSLATIONS

from . import curves
from .elements import (
    MODE_COLORS,
    OPERATING_COLOR,
    SWEEP_PALETTES,
    band_area,
    band_label,
    canvas,
    curve,
    dimensions,
    marker,
    overlay,
    png_name,
    ranged,
    scatter,
    sized,
    styled,
    sweep_label,
)
from .misfit_plots import diagnosis_overlays, residual_overlays
from .units import ROTATION, TRANSLATION

# the public plotting API: the design functions the README and examples/plotting_api.ipynb call,
# and the dimensions they draw on; the element builders serve the app's tabs
__all__ = ["branch_plots", "card_plots", "diagnosis_plots", "dimensions", "explorer_plots",
           "residual_plots", "slices_plots"]

BRANCH_COLORS = {"elastic": "#1f77b4", "viscoelastic": "#2ca02c", "friction": "#d62728"}
REFERENCE_STYLE = {"color": "#444444", "line_dash": "dashed", "line_width": 2}
MEASURED_STYLE = {"color": "#222222", "alpha": 0.6, "size": 5}
SLICE_COLORS = {1: "#1f77b4", 2: "#ff7f0e", 3: "#2ca02c", "continuum": "#9467bd"}
SLICE_NAMES = {1: "1 slice (eqs 17/18)", 2: "2 slices", 3: "3 slices", "continuum": "continuum"}
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


# ---- what-ifs ------------------------------------------------------------------------------------


def sensitivity_bars(bars: hv.Bars, title: str, color: str, png: str) -> hv.Bars:
    """Sensitivities as a bar chart, largest first (:mod:`core.whatif.sensitivity`)."""
    return bars.opts(title=title, color=color, responsive=True, height=260, framewise=True, tools=["hover"],
                     hooks=[canvas, png_name(png)], fontsize={"title": "13px"}, xrotation=0, show_legend=False)


# ---- the explorer's plots ------------------------------------------------------------------------


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


def sweep_overlay(quantity: str, against: str, sweep_items: list, dims: dict, *, operating: dict,
                  at: float, reference: dict | None = None, measured: dict | None = None,
                  band: tuple | None = None, band_name: str = "") -> hv.Overlay:
    """|K| or the loss factor against ``against`` ("frequency" or "amplitude"): the sweeps
    (:func:`sweep_curves`), the tolerance band of the operating curve (``band``: low, high), the
    curve through the operating point (``operating``, a one-row sweep), a reference design's
    (dashed), measured points and the marker at ``at``."""
    xdim, ydim = dims[against], dims[quantity]
    x_of = (lambda s: s["frequency_hz"]) if against == "frequency" else (lambda s: s["amplitude"])
    items = list(sweep_items)
    if band is not None:
        items.append(band_area(x_of(operating), *band, xdim, ydim, band_name, OPERATING_COLOR))
    if reference is not None:
        items.append(curve(x_of(reference), reference[quantity][0], xdim, ydim, "reference", **REFERENCE_STYLE))
    items.append(curve(x_of(operating), operating[quantity][0], xdim, ydim, "operating point",
                       color=OPERATING_COLOR, line_width=3))
    if measured is not None:
        items.append(scatter(x_of(measured), measured[quantity], xdim, ydim, "measured", **MEASURED_STYLE))
    items.append(marker(at, xdim))
    return overlay(items, TITLES[(quantity, against)], f"bushing-{quantity}-vs-{against}",
                   logx=against == "amplitude")


def explorer_labels(data: curves.ExplorerData) -> dict:
    """The legend entries of the sweeps: equivalent strains against frequency, frequencies
    against amplitude."""
    return {"frequency": [strain_label(r) for r in curves.SWEEP_STRAINS],
            "amplitude": [sweep_label(v, "Hz") for v in data.sweeps["amplitude"]["frequency_hz"]]}


def on_ranges(items: list, dims: dict, quantity: str, against: str) -> list:
    """A plot's sweep curves on the ranges of ``dims``: ``items`` themselves where they are on them,
    else new curves of the same data. Every element of a plot carries its ranges: one without
    would cost HoloViews a look at its data on every update (measured: about 5 ms per change)."""
    if all(tuple(el.kdims[0].range) == tuple(dims[against].range)
           and tuple(el.vdims[0].range) == tuple(dims[quantity].range) for el in items):
        return items
    return [el.clone(kdims=[dims[against]], vdims=[dims[quantity]]) for el in items]


def explorer_overlays(data: curves.ExplorerData, dims: dict | None = None, sweep_items: dict | None = None) -> dict:
    """The five plots of ``data`` (:func:`app.curves.explorer_data`): ``"loop"`` and one per (quantity,
    against) of :data:`TITLES`. ``dims`` are the dimensions to draw on (a live view passes its
    own, so that its plots keep their axes); the plots carry the data's ranges on clones of them
    (:func:`app.elements.ranged`), ``dims`` are left as they are. ``sweep_items`` may give the
    sweep curves of each plot, already built (a live view keeps them while only the operating
    point moves); those on other ranges are put on the plot's (new curves with the same data).
    ``sweep_items`` itself is not changed (a live view keeps its own on the ranges,
    :func:`on_ranges`)."""
    dims = ranged(dims if dims is not None else dimensions(data.mode), data.ranges)
    out = {"loop": loop_overlay(data.loop, dims, reference=data.reference_loop, measured=data.measured_loop)}
    labels = explorer_labels(data)
    for (quantity, against) in TITLES:
        items = (sweep_items or {}).get((quantity, against))
        if items is None:
            items = sweep_curves(quantity, against, data.sweeps[against], dims, labels[against])
        else:
            items = on_ranges(items, dims, quantity, against)
        out[(quantity, against)] = sweep_overlay(
            quantity, against, items, dims, operating=data.operating[against],
            at=data.frequency_hz if against == "frequency" else data.amplitude,
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


# ---- slices, branches, loop shape ----------------------------------------------------------------


def slices_overlays(data: dict, dims: dict, at: float) -> dict:
    """Paper A's comparison (:func:`app.curves.slice_comparison`) as three plots against
    amplitude: |K|, its difference from the single modulus in %, and the loss factor."""
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


def branch_overlays(data: dict, dims: dict, at: float) -> dict:
    """Re K and the loss factor against amplitude as stacked areas, branch by branch
    (:func:`app.curves.branch_breakdown`)."""
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


# ---- the bushing card ------------------------------------------------------------------------

def card_dimensions() -> dict[str, hv.Dimension]:
    """The card's axes: translations and rotations apart (their units differ)."""
    return {
        "displacement": hv.Dimension("card_displacement", label="Displacement amplitude",
                                     unit=TRANSLATION.amplitude.display),
        "angle": hv.Dimension("card_angle", label="Angle amplitude", unit=ROTATION.amplitude.display),
        "k_translation": hv.Dimension("card_k_translation", label="|K|", unit=TRANSLATION.stiffness.display),
        "k_rotation": hv.Dimension("card_k_rotation", label="|K|", unit=ROTATION.stiffness.display),
        "loss": hv.Dimension("card_loss", label="Loss factor"),
    }


def card_overlays(data: dict, dims: dict, at: dict) -> dict:
    """The card (:func:`app.curves.card_sweeps`) as four plots: |K| and the loss factor of the
    translations against displacement, of the rotations against angle; ``at`` the card's
    displacement and angle (display units)."""
    out = {}
    for which, modes, xdim, ydim, title in (
            ("translation", TRANSLATIONS, dims["displacement"], dims["k_translation"],
             "|K| along and across the axis"),
            ("rotation", ROTATIONS, dims["angle"], dims["k_rotation"], "|K| turning and tilting")):
        for quantity, y_dim, name in (("magnitude", ydim, which), ("loss_factor", dims["loss"], f"{which}_loss")):
            items = [band_area(data[m]["amplitude"], *data[m][f"{quantity}_band"], xdim, y_dim, f"{m} band",
                               MODE_COLORS[m]) for m in modes if f"{quantity}_band" in data[m]]
            items += [curve(data[m]["amplitude"], data[m][quantity], xdim, y_dim, m, color=MODE_COLORS[m],
                            line_width=2) for m in modes]
            items.append(marker(at[which], xdim))
            label = title if quantity == "magnitude" else f"Loss factor, {title[4:]}"
            out[name] = overlay(items, label, f"bushing-card-{name.replace('_', '-')}", logx=True, height=260)
    return out


def card_plots(design: Design, frequency_hz: float = 10.0, displacement: float = 1e-4, angle: float = 0.01, *,
               width: int | None = 800) -> hv.Layout:
    """The bushing card's four plots: every direction of ``design`` at one frequency.

    Parameters
    ----------
    design : Design
        The bushing, in SI units, in any mode: the card takes it into every mode.
    frequency_hz : float, default 10.0
        The frequency in Hz.
    displacement : float, default 1e-4
        The card's displacement amplitude (the marker), in m (SI, drawn in mm).
    angle : float, default 0.01
        The card's angle amplitude (the marker), in rad.
    width : int or None, default 800
        The width of each plot in pixels; None: as wide as its container.

    Returns
    -------
    holoviews.Layout
        Four plots in two columns: |K| of the translations (kN/mm) against displacement (mm)
        and of the rotations (N·m/rad) against angle (rad), and their loss factors
        (dimensionless).
    """
    data = curves.card_sweeps(design, frequency_hz)
    at = {"translation": TRANSLATION.amplitude.to_display(displacement),
          "rotation": ROTATION.amplitude.to_display(angle)}
    return sized(hv.Layout(list(card_overlays(data, card_dimensions(), at).values())).cols(2), width)


