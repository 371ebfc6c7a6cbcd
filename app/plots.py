"""The plotting API: HoloViews objects of a bushing design, its operating point and measured data.

Plain functions, the same the explorer draws with; they need no server and work in a notebook::

    import holoviews as hv
    from core import PAPER_B
    from app import plots

    layout = plots.explorer_plots(PAPER_B, frequency_hz=10.0, amplitude=0.1)   # hv.Layout
    hv.save(layout, "paper_b.html")

Every axis is an :class:`holoviews.Dimension` with its name, label and unit (:func:`dimensions`);
plots of the same quantity share the dimension, so a layout links their axes. Amplitudes are in
the display units of :mod:`app.units` (mm axially, rad in torsion), stiffnesses in kN/mm or
N·m/rad, frequencies in Hz.

Two layers: *element builders* (``loop_overlay``, ``sweep_overlay``, …) turn curves (dicts of
arrays from :mod:`app.curves`) into elements; *design functions* (``explorer_plots``,
``slices_plots``, …) compute the curves of a design and return finished layouts.

Each element is a clone of a styled template (:func:`_styled`): the options are attached once,
and a clone carries them, so a live plot that rebuilds its elements on every change does not
re-resolve its options.
"""

from __future__ import annotations

import functools

import holoviews as hv
import holoviews.plotting.bokeh
import numpy as np
from bokeh.models import SaveTool

from core import Design
from core.data import MeasuredStiffness

from . import curves, units

# Without a GPU, Chromium draws WebGL through SwiftShader on the CPU: measured in the explorer,
# the GPU process then spent about 110 ms per update (7 ms with canvas). HoloViews 1.23 asks for
# WebGL by default; these plots are small (at most a few thousand points), canvas is the right
# backend for them everywhere.
hv.renderer("bokeh").webgl = False

BRANCH_COLORS = {"elastic": "#1f77b4", "viscoelastic": "#2ca02c", "friction": "#d62728"}
OPERATING_COLOR = "#e6550d"
REFERENCE_STYLE = {"color": "#444444", "line_dash": "dashed", "line_width": 2}
MEASURED_STYLE = {"color": "#222222", "alpha": 0.6, "size": 5}
SLICE_COLORS = {1: "#1f77b4", 2: "#ff7f0e", 3: "#2ca02c", "continuum": "#9467bd"}
SLICE_NAMES = {1: "1 slice (eqs 17/18)", 2: "2 slices", 3: "3 slices", "continuum": "continuum"}
SWEEP_PALETTES = {  # light to dark as the swept value grows
    "amplitude": ["#9ecae1", "#6baed6", "#3182bd", "#08519c", "#08306b"],
    "frequency": ["#a1d99b", "#41ab5d", "#006d2c", "#00441b", "#002910"],
}
TITLES = {
    ("magnitude", "frequency"): "|K| against frequency",
    ("loss_factor", "frequency"): "Loss factor against frequency",
    ("magnitude", "amplitude"): "|K| against amplitude",
    ("loss_factor", "amplitude"): "Loss factor against amplitude",
}
LOOP_TITLE = "Hysteresis loop at the operating point"


def sweep_label(value, unit) -> str:
    return f"{value:.3g} {unit}"


def strain_label(ratio: float) -> str:
    """The legend of a frequency sweep: its equivalent strain as a multiple of ε½ (the same for
    every design, so a legend never changes while the design does)."""
    return "ε̂ = ε½" if ratio == 1 else f"ε̂ = {ratio:g} ε½"


# ---- dimensions --------------------------------------------------------------------------------


def dimensions(mode: str) -> dict[str, hv.Dimension]:
    """The plotted quantities of ``mode`` with their names, labels and units."""
    amp, stiff, force = units.amplitude_unit(mode), units.stiffness_unit(mode), units.force_unit(mode)
    return {
        "frequency": hv.Dimension("frequency_hz", label="Frequency", unit="Hz"),
        "amplitude": hv.Dimension("amplitude", label="Amplitude", unit=amp),
        "magnitude": hv.Dimension("magnitude", label="|K|", unit=stiff),
        "loss_factor": hv.Dimension("loss_factor", label="Loss factor"),
        "displacement": hv.Dimension("displacement", label=units.DRIVE[mode], unit=amp),
        "force": hv.Dimension("force", label=units.LOAD[mode], unit=force),
        "difference": hv.Dimension("difference", label="Difference", unit="%"),
        "real": hv.Dimension("real", label="Re K", unit=stiff),
        "branch_loss": hv.Dimension("branch_loss", label="Loss factor"),
        "drive_rel": hv.Dimension("drive_rel", label="Drive / peak drive"),
        "force_rel": hv.Dimension("force_rel", label="Force / peak force"),
        "residual_magnitude": hv.Dimension("residual_magnitude", label="|K| residual", unit="%"),
        "residual_loss": hv.Dimension("residual_loss", label="Loss-factor residual"),
        "stage": hv.Dimension("stage", label="Step"),
        "gap": hv.Dimension("gap", label="Gap"),
        "misfit_magnitude": hv.Dimension("misfit_magnitude", label="|K| misfit", unit="%"),
        "misfit_loss": hv.Dimension("misfit_loss", label="Loss-factor misfit"),
    }


# ---- styled templates ----------------------------------------------------------------------------


def legend_outside(plot, _element):
    """A hook that puts the plot's legend to the right of the frame, once.

    Why not ``legend_position="right"``: with a legend outside the frame, HoloViews 1.23 removes
    it from the plot and adds it again on every update (``OverlayPlot._process_legend``), which
    changes the plot's layout lists: the browser lays the plot out again and the server walks
    every model of the document (measured: about a third of the server's time per change, and
    most of Chromium's). Placed here once, HoloViews finds the legend where it is and leaves it."""
    fig = plot.state
    for legend in list(fig.center):
        if legend.__class__.__name__ == "Legend":
            fig.center.remove(legend)
            fig.add_layout(legend, "right")


@functools.cache
def png_name(name: str):
    """A hook naming the PNG that a plot's save tool writes (one function per name: the hooks
    are part of a template's key, see :func:`_styled`)."""

    def hook(plot, _element):
        for tool in plot.state.toolbar.tools:  # not state.select: that walks every model (measured: 9 ms)
            if isinstance(tool, SaveTool) and tool.filename != name:
                tool.filename = name

    hook.__name__ = f"png_{name}"
    return hook


@functools.cache
def _template(kind: str, key: tuple) -> hv.Element | hv.Overlay:
    element = {"Curve": hv.Curve, "Scatter": hv.Scatter, "Area": hv.Area, "VLine": hv.VLine,
               "HLine": hv.HLine, "Bars": hv.Bars, "Points": hv.Points, "Overlay": hv.Overlay}[kind]
    empty = 0.0 if kind in ("VLine", "HLine") else []
    return element(empty).opts(**{k: _thaw(v) for k, v in key})


def _freeze(value):
    """A hashable form of an option value (dicts and lists tagged, to be thawed back)."""
    if isinstance(value, dict):
        return ("<dict>", tuple(sorted((k, _freeze(v)) for k, v in value.items())))
    if isinstance(value, list):
        return ("<list>", tuple(_freeze(v) for v in value))
    return value


def _thaw(value):
    if isinstance(value, tuple) and len(value) == 2 and value[0] in ("<dict>", "<list>"):
        if value[0] == "<dict>":
            return {k: _thaw(v) for k, v in value[1]}
        return [_thaw(v) for v in value[1]]
    return value


def _styled(kind: str, data, **options):
    """An element of ``kind`` holding ``data``, cloned from a template that carries ``options``
    (one options entry per style, whatever the number of frames)."""
    options.setdefault("framewise", True)  # a norm option of each element: its axes follow its data
    if kind in ("Curve", "Scatter", "Area"):
        # a click on a legend entry mutes its glyph, drawn fully transparent: hidden. HoloViews
        # keeps a glyph muted through updates (it shows a hidden one again on every frame)
        options.setdefault("muted_alpha", 0.0)
    key = tuple(sorted((k, _freeze(v)) for k, v in options.items() if k not in ("kdims", "vdims", "label")))
    fields = {k: options[k] for k in ("kdims", "vdims", "label") if k in options}
    return _template(kind, key).clone(data, **fields)


def _curve(x, y, xdim, ydim, label, **style):
    style.setdefault("tools", ["hover"])
    return _styled("Curve", (np.asarray(x, dtype=float), np.asarray(y, dtype=float)),
                   kdims=[xdim], vdims=[ydim], label=label, **style)


def _points(x, y, xdim, ydim, label, **style):
    style.setdefault("tools", ["hover"])
    return _styled("Scatter", (np.asarray(x, dtype=float), np.asarray(y, dtype=float)),
                   kdims=[xdim], vdims=[ydim], label=label, **style)


def _overlay(items, title, png, *, logx=False, logy=False, legend="right", height=300):
    legend_opts = {"click_policy": "mute", "label_text_font_size": "11px", "spacing": 0, "padding": 4,
                   "margin": 4}
    hooks = [png_name(png)] + ([legend_outside] if legend == "right" else [])
    options = {"title": title, "responsive": True, "height": height, "logx": logx, "logy": logy,
               "framewise": True, "hooks": hooks, "legend_opts": legend_opts,
               "fontsize": {"title": "13px"}, "show_legend": legend is not None}
    if legend is not None:
        options["legend_position"] = "top_right" if legend == "right" else legend
    return _styled("Overlay", list(items), **options)


def band_area(x, low, high, xdim: hv.Dimension, ydim: hv.Dimension, label: str, color: str):
    """A tolerance band: the area between ``low`` and ``high``."""
    # its own label: HoloViews finds a dimension by its label, and two alike would both read the lower
    upper = hv.Dimension(f"{ydim.name}_upper", label=f"{ydim.label} (band top)", unit=ydim.unit)
    return _styled("Area", (np.asarray(x, dtype=float), np.asarray(low, dtype=float), np.asarray(high, dtype=float)),
                   kdims=[xdim], vdims=[ydim, upper], label=label, color=color, fill_alpha=0.22, line_alpha=0.0,
                   tools=["hover"])


def band_label(percentiles) -> str:
    low, high = percentiles
    return f"{low:g}–{high:g} % band"


def sensitivity_bars(bars: hv.Bars, title: str, color: str, png: str) -> hv.Bars:
    """Sensitivities as a bar chart, largest first (:mod:`core.whatif.sensitivity`)."""
    return bars.opts(title=title, color=color, responsive=True, height=260, framewise=True, tools=["hover"],
                     hooks=[png_name(png)], fontsize={"title": "13px"}, xrotation=0, show_legend=False)


def marker(x: float, dim: hv.Dimension):
    """The operating point: a dotted vertical line at ``x``."""
    return _styled("VLine", float(x), kdims=[dim, hv.Dimension("y")], color=OPERATING_COLOR,
                   line_dash="dotted", line_width=1.5)


# ---- the explorer's plots ------------------------------------------------------------------------


def loop_overlay(lp: dict, dims: dict, *, reference: dict | None = None, measured: dict | None = None,
                 title: str = LOOP_TITLE) -> hv.Overlay:
    """The hysteresis loop (:func:`app.curves.hysteresis_loop`) branch by branch, a reference
    loop (dashed) and measured points, on ``dims`` (:func:`dimensions`)."""
    x, f = dims["displacement"], dims["force"]
    items = [_curve(lp["displacement"], lp[f"force_{name}"], x, f, name, color=color, line_width=1.5)
             for name, color in BRANCH_COLORS.items()]
    if reference is not None:
        items.append(_curve(reference["displacement"], reference["force"], x, f, "reference", **REFERENCE_STYLE))
    items.append(_curve(lp["displacement"], lp["force"], x, f, "total", color="black", line_width=2.5))
    if measured is not None:
        items.append(_points(measured["displacement"], measured["force"], x, f, "measured", color="#222222",
                             alpha=0.5, size=4))
    return _overlay(items, title, "bushing-hysteresis-loop", legend="top_left", height=330)


def sweep_curves(quantity: str, against: str, sweep: dict, dims: dict, labels) -> list:
    """One curve per swept value: |K| or the loss factor against frequency (a row per
    amplitude) or against amplitude (a row per frequency)."""
    x = sweep["frequency_hz"] if against == "frequency" else sweep["amplitude"]
    palette = SWEEP_PALETTES["amplitude" if against == "frequency" else "frequency"]
    return [_curve(x, row, dims[against], dims[quantity], label, color=palette[i % len(palette)], line_width=1.3)
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
        items.append(_curve(x_of(reference), reference[quantity][0], xdim, ydim, "reference", **REFERENCE_STYLE))
    items.append(_curve(x_of(operating), operating[quantity][0], xdim, ydim, "operating point",
                        color=OPERATING_COLOR, line_width=3))
    if measured is not None:
        items.append(_points(x_of(measured), measured[quantity], xdim, ydim, "measured", **MEASURED_STYLE))
    items.append(marker(at, xdim))
    return _overlay(items, TITLES[(quantity, against)], f"bushing-{quantity}-vs-{against}",
                    logx=against == "amplitude")


def explorer_labels(data: curves.ExplorerData) -> dict:
    """The legend entries of the sweeps: equivalent strains against frequency, frequencies
    against amplitude."""
    return {"frequency": [strain_label(r) for r in curves.SWEEP_STRAINS],
            "amplitude": [sweep_label(v, "Hz") for v in data.sweeps["amplitude"]["frequency_hz"]]}


def explorer_overlays(data: curves.ExplorerData, dims: dict | None = None, sweep_items: dict | None = None) -> dict:
    """The five plots of ``data`` (:func:`app.curves.explorer_data`): ``"loop"`` and one per (quantity,
    against) of :data:`TITLES`. ``dims`` are the dimensions to draw on: their ranges are set to
    the data's (a live view passes its own, so that its plots keep their axes);
    ``sweep_items`` may give the sweep curves of each plot, already built (a live view keeps
    them while only the operating point moves)."""
    dims = dims if dims is not None else dimensions(data.mode)
    for name, rng in data.ranges.items():
        if rng is not None:
            dims[name].range = rng
    out = {"loop": loop_overlay(data.loop, dims, reference=data.reference_loop, measured=data.measured_loop)}
    labels = explorer_labels(data)
    for (quantity, against) in TITLES:
        items = (sweep_items or {}).get((quantity, against))
        if items is None:
            items = sweep_curves(quantity, against, data.sweeps[against], dims, labels[against])
        out[(quantity, against)] = sweep_overlay(
            quantity, against, items, dims, operating=data.operating[against],
            at=data.frequency_hz if against == "frequency" else data.amplitude,
            reference=data.references[against] if data.references else None, measured=data.measured,
            band=data.bands[against][quantity] if data.bands else None,
            band_name=band_label(data.bands["point"]["percentiles"]) if data.bands else "")
    return out


def sized(layout: hv.Layout, width: int | None) -> hv.Layout:
    """``layout`` with plots ``width`` pixels wide (for a notebook or a saved file), or as they
    are (filling the width of their container) for None."""
    if width is None:
        return layout
    return layout.map(lambda overlay: overlay.opts(responsive=False, width=width), [hv.Overlay])


def explorer_plots(design: Design, frequency_hz: float = 10.0, amplitude: float | None = None, *,
                   width: int | None = 600, **kwargs) -> hv.Layout:
    """The explorer's five plots of ``design`` at the operating point (``amplitude`` in mm or
    rad; by default mid-way through the Fletcher–Gent range): the loop, then |K| and the loss
    factor against frequency and amplitude, each ``width`` pixels wide (None: as wide as their
    container). ``kwargs`` as :func:`app.curves.explorer_data`."""
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
            items.append(_curve(data["amplitude"] if y is not None else [], y if y is not None else [],
                                dims["amplitude"], ydim, SLICE_NAMES[m], color=SLICE_COLORS[m], line_width=2))
        items.append(marker(at, dims["amplitude"]))
        out[which] = _overlay(items, title, f"bushing-slices-{which}", logx=True, height=280)
    return out


def slices_plots(design: Design, frequency_hz: float = 10.0, amplitude: float | None = None, n: int = 60, *,
                 width: int | None = 800) -> hv.Layout:
    """One equivalent modulus against 2 and 3 slices and the continuum, at ``frequency_hz``."""
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
            areas.append(_styled("Area", (data["amplitude"], top, base), kdims=[dims["amplitude"]],
                                 vdims=[ydim, hv.Dimension(f"{which}_base")], label=name, color=color,
                                 fill_alpha=0.55, line_alpha=0))
            base = top
        areas.append(marker(at, dims["amplitude"]))
        out[which] = _overlay(areas, title, f"bushing-branches-{which}", logx=True, legend="top_left")
    return out


def loop_shape_overlay(lp: dict, dims: dict, title: str = "Loop shape during the amplitude sweep") -> hv.Overlay:
    """A loop scaled to its peak drive and peak force, branch by branch: its shape alone."""
    x = lp["displacement"] / np.max(np.abs(lp["displacement"]))
    peak = np.max(np.abs(lp["force"]))
    xd, fd = dims["drive_rel"], dims["force_rel"]
    xd.range, fd.range = (-1.05, 1.05), (-1.1, 1.1)  # scaled to ±1: the same axes for every loop
    items = [_curve(x, lp["force"] / peak, xd, fd, "total", color="black", line_width=2.5)]
    items += [_curve(x, lp[f"force_{name}"] / peak, xd, fd, name, color=color, line_width=1.5)
              for name, color in BRANCH_COLORS.items()]
    return _overlay(items, title, "bushing-loop-shape", legend="top_left", height=420)


def branch_plots(design: Design, frequency_hz: float = 10.0, amplitude: float | None = None, n: int = 80, *,
                 width: int | None = 600) -> hv.Layout:
    """The Fletcher–Gent effect branch by branch at ``frequency_hz``, and the loop's shape at
    ``amplitude`` (display units)."""
    at = amplitude if amplitude is not None else float(curves.fletcher_gent_amplitudes(design)[2])
    dims = dimensions(design.mode)
    overlays = branch_overlays(curves.branch_breakdown(design, frequency_hz, curves.amplitude_grid(design, n)), dims, at)
    shape = loop_shape_overlay(curves.hysteresis_loop(design, frequency_hz, at), dims)
    return sized(hv.Layout([*overlays.values(), shape]).cols(1), width)


# ---- measured data and the diagnosis -------------------------------------------------------------


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
            out[(quantity, against)] = _overlay(
                [_points(x, y, dims[against], ydim, "residual", color=OPERATING_COLOR, alpha=0.7, size=6)],
                title, f"bushing-residual-{quantity}-vs-{against}", logx=against == "amplitude", legend=None,
                height=240)
    return out


def residual_plots(design: Design, measured: MeasuredStiffness, *, width: int | None = 500) -> hv.Layout:
    """The residuals of ``design`` against measured stiffness."""
    residuals = curves.measured_residuals(design, measured)
    overlays = residual_overlays(curves.measured_points(measured, design.mode), residuals, dimensions(design.mode))
    return sized(hv.Layout(list(overlays.values())).cols(2), width)


def gap_bars(stages: dict, dims: dict) -> hv.Overlay:
    """The gap after each step of a diagnosis as bars, with the noise level (dashed)."""
    bars = _styled("Bars", (list(stages["stage"]), np.asarray(stages["gap"], dtype=float)),
                   kdims=[dims["stage"]], vdims=[dims["gap"]], color="#3182bd", bar_width=0.6, tools=["hover"])
    items = [bars]
    if stages.get("noise") is not None:
        items.append(_styled("HLine", float(stages["noise"]), kdims=[hv.Dimension("x"), dims["gap"]],
                             color="#d62728", line_dash="dashed", line_width=2))
    return _overlay(items, "Gap (relative RMS misfit of complex stiffness) after each step", "bushing-diagnosis-gap",
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
            items.append(_curve(g["frequency_hz"], g["baseline"][i], dims["frequency"], ydim, f"{label} baseline",
                                color=color, line_dash="dashed", line_width=1.5))
            items.append(_curve(g["frequency_hz"], g["final"][i], dims["frequency"], ydim, f"{label} final",
                                color=color, line_width=2))
            items.append(_points(g["frequency_hz"], g["data"][i], dims["frequency"], ydim, f"{label} data",
                                 color=color, size=6, alpha=0.8))
        out[quantity] = _overlay(items, f"{ydim.label}: data, baseline and final model",
                                 f"bushing-diagnosis-{quantity}", legend=None, height=280)
    return out


MISFIT_PNG = {"magnitude_pct": "magnitude", "loss_factor": "loss"}


def misfit_map(m: dict, column: str, title: str, dims: dict, limit: float, png: str) -> hv.Overlay:
    """A misfit over the (frequency, amplitude) plane: one square per measured point, coloured
    on a diverging scale from −``limit`` to +``limit`` (red: model above the data)."""
    zdim = dims["misfit_magnitude" if column == "magnitude_pct" else "misfit_loss"]
    pts = _styled("Points", (np.asarray(m["frequency_hz"], dtype=float), np.asarray(m["amplitude"], dtype=float),
                             np.asarray(m[column], dtype=float)),
                  kdims=[dims["frequency"], dims["amplitude"]], vdims=[zdim], color=zdim.name, cmap="RdBu_r",
                  marker="square", size=11, colorbar=True, line_color="#777777", line_width=0.5,
                  clim=(-limit, limit), tools=["hover"])
    return _overlay([pts], title, png, logy=True, legend=None, height=260)


def diagnosis_overlays(diagnosis) -> dict:
    """The plots of a :class:`core.identify.diagnose.Diagnosis`: ``"gap"`` (one plot: the gap after each
    step), ``"curves"`` (|K| and the loss factor: data, baseline, final model) and ``"maps"``
    (the misfit before, then after: |K| and the loss factor each, on one colour scale per
    quantity); ``"groups"`` the curves' amplitude groups (:func:`app.curves.curve_groups`)."""
    dims = dimensions(diagnosis.final.design.mode)
    stages = curves.gap_stages(diagnosis)
    dims["gap"].range = (0.0, 1.1 * max(float(np.max(stages["gap"])), stages["noise"] or 0.0))
    groups = curves.curve_groups(diagnosis)
    for i, quantity in enumerate(("magnitude", "loss_factor")):  # the data and both models in view
        dims[quantity].range = curves.padded([v for g in groups for v in (g["data"][i], g["baseline"][i], g["final"][i])])
    base, final = curves.misfit_points(diagnosis, "baseline"), curves.misfit_points(diagnosis, "final")
    dims["amplitude"].range = curves.padded([final["amplitude"]], log=True)
    maps = []
    for which, m in (("baseline", base), ("final", final)):
        for column, name in (("magnitude_pct", "|K| misfit (%)"), ("loss_factor", "loss-factor misfit")):
            limit = float(np.max(np.abs(base[column]))) or 1.0  # one colour scale for before and after
            maps.append(misfit_map(m, column, f"{which.capitalize()}: {name}", dims, limit,
                                   f"bushing-misfit-{which}-{MISFIT_PNG[column]}"))
    return {"gap": [gap_bars(stages, dims)], "curves": list(diagnosis_curves(groups, dims).values()),
            "maps": maps, "groups": groups}


def diagnosis_plots(diagnosis, *, width: int | None = 560) -> hv.Layout:
    """A :class:`core.identify.diagnose.Diagnosis`: the gap after each step, the data against the
    baseline and the final model, and the misfit maps before and after."""
    overlays = diagnosis_overlays(diagnosis)
    return sized(hv.Layout(overlays["gap"] + overlays["curves"] + overlays["maps"]).cols(2), width)


# ---- the bushing card ------------------------------------------------------------------------

CARD_COLORS = {"axial": "#1f77b4", "radial": "#d62728", "torsion": "#2ca02c", "conical": "#9467bd"}


def card_dimensions() -> dict[str, hv.Dimension]:
    """The card's axes: translations and rotations apart (their units differ)."""
    return {
        "displacement": hv.Dimension("card_displacement", label="Displacement amplitude",
                                     unit=units.amplitude_unit("axial")),
        "angle": hv.Dimension("card_angle", label="Angle amplitude", unit=units.amplitude_unit("torsion")),
        "k_translation": hv.Dimension("card_k_translation", label="|K|", unit=units.stiffness_unit("axial")),
        "k_rotation": hv.Dimension("card_k_rotation", label="|K|", unit=units.stiffness_unit("torsion")),
        "loss": hv.Dimension("card_loss", label="Loss factor"),
    }


def card_overlays(data: dict, dims: dict, at: dict) -> dict:
    """The card (:func:`app.curves.card_sweeps`) as four plots: |K| and the loss factor of the
    translations against displacement, of the rotations against angle; ``at`` the card's
    displacement and angle (display units)."""
    out = {}
    for which, modes, xdim, ydim, title in (
            ("translation", ("axial", "radial"), dims["displacement"], dims["k_translation"],
             "|K| along and across the axis"),
            ("rotation", ("torsion", "conical"), dims["angle"], dims["k_rotation"], "|K| turning and tilting")):
        for quantity, y_dim, name in (("magnitude", ydim, which), ("loss_factor", dims["loss"], f"{which}_loss")):
            items = [band_area(data[m]["amplitude"], *data[m][f"{quantity}_band"], xdim, y_dim, f"{m} band",
                               CARD_COLORS[m]) for m in modes if f"{quantity}_band" in data[m]]
            items += [_curve(data[m]["amplitude"], data[m][quantity], xdim, y_dim, m, color=CARD_COLORS[m],
                             line_width=2) for m in modes]
            items.append(marker(at[which], xdim))
            label = title if quantity == "magnitude" else f"Loss factor, {title[4:]}"
            out[name] = _overlay(items, label, f"bushing-card-{name.replace('_', '-')}", logx=True, height=260)
    return out


def card_plots(design: Design, frequency_hz: float = 10.0, displacement: float = 1e-4, angle: float = 0.01, *,
               width: int | None = 800) -> hv.Layout:
    """The bushing card's four plots for ``design`` at ``frequency_hz``; the markers at the
    card's displacement (m) and angle (rad)."""
    data = curves.card_sweeps(design, frequency_hz)
    at = {"translation": units.display_amplitude(displacement, "axial"),
          "rotation": units.display_amplitude(angle, "torsion")}
    return sized(hv.Layout(list(card_overlays(data, card_dimensions(), at).values())).cols(2), width)


def prediction_overlay(data: dict) -> hv.Overlay:
    """A fit on a subset predicting the rest (:func:`app.curves.prediction_misfit`): the |K|
    misfit of every mode against frequency, fitted rows filled, predicted rows hollow."""
    xdim = dimensions("axial")["frequency"]  # the same in every mode
    ydim = hv.Dimension("prediction_misfit", label="|K|, model − measured", unit="%")
    items = []
    for mode, parts in data.items():
        color = CARD_COLORS.get(mode, OPERATING_COLOR)
        for which, fill in (("fitted", 0.8), ("predicted", 0.0)):
            part = parts[which]
            if len(part["frequency_hz"]):
                items.append(_points(part["frequency_hz"], part["misfit_pct"], xdim, ydim,
                                     f"{mode}, {which}", color=color, fill_alpha=fill, line_color=color, size=6))
    return _overlay(items, "Fitted and predicted rows, every mode: |K| misfit", "bushing-prediction", height=300)
