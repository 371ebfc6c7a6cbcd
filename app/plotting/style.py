"""The elements every plot is made of: the plotted quantities' dimensions, and HoloViews curves,
points, areas, markers and overlays, each a clone of a styled template.

Each element is a clone of a styled template (:func:`styled`): the options are attached once,
and a clone carries them, so a live plot that rebuilds its elements on every change does not
re-resolve its options. The figures are built from them in :mod:`app.plots` (the public
plotting API) and :mod:`app.plotting.measured_data_and_fit` (model against measured data).
"""

from __future__ import annotations

import functools

import holoviews as hv
import holoviews.plotting.bokeh
import numpy as np
from bokeh.models import CustomJSTicker, CustomJSTickFormatter, SaveTool
from holoviews.core.util import dimension_sanitizer

from core.numbers import TICK_JS, format_value
from core.parameters import MODES
from core.parameters import mode as mode_of

OPERATING_COLOR = "#e6550d"
# one colour per mode (the card, the fit's predicted rows)
MODE_COLORS = dict(zip(MODES, ("#1f77b4", "#2ca02c", "#d62728", "#9467bd")))
SWEEP_PALETTES = {  # light to dark as the swept value grows
    "amplitude": ["#9ecae1", "#6baed6", "#3182bd", "#08519c", "#08306b"],
    "frequency": ["#a1d99b", "#41ab5d", "#006d2c", "#00441b", "#002910"],
}


def sweep_label(value, unit) -> str:
    return format_value(value, unit, 3)


def amplitude_key(groups: list, unit: str) -> str:
    """The key of :func:`amplitude_curves`' colours, one amplitude each (``groups`` as
    :func:`app.curves.amplitude_groups`, the amplitudes in ``unit``), as a line of HTML; empty
    without groups. The plots carry no legend of their own: five amplitudes times data and models
    would cover the curves."""
    palette = SWEEP_PALETTES["amplitude"]
    if not groups:
        return ""
    return "Amplitudes: " + " ".join(
        f'<span style="color:{palette[i % len(palette)]};font-weight:bold">■ {sweep_label(g["amplitude"], unit)}</span>'
        for i, g in enumerate(groups))


BRANCH_COLORS = {"elastic": "#1f77b4", "viscoelastic": "#2ca02c", "friction": "#d62728"}


REFERENCE_STYLE = {"color": "#444444", "line_dash": "dashed", "line_width": 2}

MEASURED_STYLE = {"color": "#222222", "alpha": 0.6, "size": 5}


# ---- dimensions --------------------------------------------------------------------------------


def dimensions(mode: str) -> dict[str, hv.Dimension]:
    """The plotted quantities of ``mode`` with their names, labels and units.

    Parameters
    ----------
    mode : str
        One of :data:`core.parameters.MODES`.

    Returns
    -------
    dict of str to holoviews.Dimension
        A fresh dimension per quantity, in the display units of :mod:`core.parameters`:
        frequency in Hz; amplitude and drive in mm (axial, radial) or rad (torsion, conical);
        |K| and Re K in kN/mm or N·m/rad; force in N or N·m; differences and |K| residuals
        in %; loss factors, gaps and scaled drive and force dimensionless.
    """
    m = mode_of(mode)
    amp, stiff, force = m.amplitude.display, m.stiffness.display, m.force.display
    return {
        "frequency": hv.Dimension("frequency_hz", label="Frequency", unit="Hz"),
        "amplitude": hv.Dimension("amplitude", label="Amplitude", unit=amp),
        "magnitude": hv.Dimension("magnitude", label="|K|", unit=stiff),
        "loss_factor": hv.Dimension("loss_factor", label="Loss factor"),
        "displacement": hv.Dimension("displacement", label=m.drive, unit=amp),
        "force": hv.Dimension("force", label=m.load, unit=force),
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


def ranged(dims: dict[str, hv.Dimension], ranges: dict) -> dict[str, hv.Dimension]:
    """``dims`` with the axis ranges of ``ranges`` (name → (start, end), or None for the data's):
    a new dict, each ranged dimension a clone. The dimensions given are never changed: an
    element built on them earlier keeps its axes (a plot's elements share one clone, so plots of
    the same quantity drawn with it still share their axis range)."""
    out = dict(dims)
    for name, rng in ranges.items():
        if rng is not None and tuple(dims[name].range) != tuple(rng):
            out[name] = dims[name].clone(range=tuple(rng))
    return out


@functools.cache
def _shared_dimensions(mode: str) -> dict[str, hv.Dimension]:
    return dimensions(mode)


@functools.lru_cache(maxsize=256)
def axis_dimension(mode: str, name: str, rng: tuple | None = None) -> hv.Dimension:
    """The dimension ``name`` of ``mode`` (:func:`dimensions`) with the axis range ``rng`` (None:
    the data's), one shared object per (mode, name, range), never changed: for elements cached by
    value (:func:`app.plotting.explorer.sweep_layer`), which need no dimensions of their own."""
    dim = _shared_dimensions(mode)[name]
    return dim if rng is None else dim.clone(range=tuple(rng))


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


def canvas(plot, _element):
    """A hook drawing the plot on an HTML canvas, whatever the renderer's ``webgl`` says.

    Without a GPU, Chromium draws WebGL through SwiftShader on the CPU: measured in the explorer,
    the GPU process then spent about 110 ms per update (7 ms with canvas). HoloViews 1.23 asks for
    WebGL by default; these plots are small (at most a few thousand points), canvas is the right
    backend for them everywhere. A hook of each plot rather than ``hv.renderer("bokeh").webgl``,
    which would change every plot of a notebook that imports the plotting API."""
    if plot.state.output_backend != "canvas":
        plot.state.output_backend = "canvas"


def ticks(plot, _element):
    """A hook writing every numeric axis' tick labels by the one number rule
    (:data:`core.numbers.TICK_JS`: ``0.00015``, ``15×10⁻⁶``, never ``1.500e-4``), once per axis:
    a formatter of its own per plot (a Bokeh model belongs to one document)."""
    fig = plot.state
    for axis in (*fig.xaxis, *fig.yaxis):
        if not isinstance(axis.formatter, CustomJSTickFormatter) and hasattr(axis, "ticker") and \
                type(axis).__name__ in ("LinearAxis", "LogAxis"):
            axis.formatter = CustomJSTickFormatter(code=TICK_JS)


# log-axis ticks labelled in every part of the range: Bokeh's LogTicker, on a range of less than
# two decades, ticks it linearly (0.1, 0.2, 0.3 on 0.013–0.35 mm: the lower decade unlabelled)
LOG_TICKS_JS = """
const lo = Math.min(cb_data.start, cb_data.end), hi = Math.max(cb_data.start, cb_data.end);
if (!(lo > 0) || !(hi > lo) || !isFinite(hi)) return [];
const decades = Math.log10(hi / lo);
const tick = (m, e) => Number((m * Math.pow(10, e)).toPrecision(12));
const within = (mantissas) => {
  const out = [];
  for (let e = Math.floor(Math.log10(lo)); e <= Math.ceil(Math.log10(hi)); e++)
    for (const m of mantissas) { const v = tick(m, e); if (v >= lo && v <= hi) out.push(v); }
  return out;
};
for (const mantissas of (decades > 5 ? [[1]] : decades > 2.5 ? [[1], [1, 3]] : decades > 1 ? [[1, 2, 5]]
                         : [[1, 2, 5], [1, 2, 3, 4, 5, 6, 7, 8, 9]])) {
  const ticks = within(mantissas);
  if (ticks.length >= 3 || (mantissas.length === 9 && ticks.length >= 2)) return ticks;
}
// under a factor of ~2 (a zoom): a linear 1-2-5 step
const step0 = (hi - lo) / 4, p = Math.pow(10, Math.floor(Math.log10(step0)));
const step = [1, 2, 5, 10].map(m => m * p).find(s => s >= step0);
const out = [];
for (let v = Math.ceil(lo / step) * step; v <= hi; v += step) out.push(Number(v.toPrecision(12)));
return out;
"""
LOG_MINOR_JS = """
const lo = Math.min(cb_data.start, cb_data.end), hi = Math.max(cb_data.start, cb_data.end);
if (!(lo > 0) || !(hi > lo) || !isFinite(hi) || Math.log10(hi / lo) > 5) return [];
const out = [];
for (let e = Math.floor(Math.log10(lo)); e <= Math.ceil(Math.log10(hi)); e++)
  for (let m = 1; m < 10; m++) { const v = Number((m * Math.pow(10, e)).toPrecision(12)); if (v >= lo && v <= hi) out.push(v); }
return out;
"""


def log_ticks(plot, _element):
    """A hook labelling each log axis (x or y) in every part of its range (:data:`LOG_TICKS_JS`:
    powers of ten over many decades, 1-2-5 over one or two, 1…9 within one); its labels are
    :func:`ticks`'. Bokeh's own log ticker labels only powers of ten and their multiples it
    picks: a misfit map's amplitudes from 0.013 to 0.35 mm had labels at 0.1–0.4 mm only."""
    for axis in [*plot.state.xaxis, *plot.state.yaxis]:
        if type(axis).__name__ == "LogAxis" and not isinstance(axis.ticker, CustomJSTicker):
            axis.ticker = CustomJSTicker(major_code=LOG_TICKS_JS, minor_code=LOG_MINOR_JS)


@functools.cache
def png_name(name: str):
    """A hook naming the PNG that a plot's save tool writes (one function per name: the hooks
    are part of a template's key, see :func:`styled`)."""

    def hook(plot, _element):
        for tool in plot.state.toolbar.tools:  # not state.select: that walks every model (measured: 9 ms)
            if isinstance(tool, SaveTool) and tool.filename != name:
                tool.filename = name

    hook.__name__ = f"png_{name}"
    return hook


@functools.cache
def template(kind: str, key: tuple) -> hv.Element | hv.Overlay:
    element = {"Curve": hv.Curve, "Scatter": hv.Scatter, "Area": hv.Area, "VLine": hv.VLine,
               "HLine": hv.HLine, "Bars": hv.Bars, "Points": hv.Points, "Overlay": hv.Overlay}[kind]
    empty = 0.0 if kind in ("VLine", "HLine") else []
    made = element(empty).opts(**{k: _thaw(v) for k, v in key})
    _STYLES[made.id] = (kind, tuple((k, _unlabelled(v) if k == "hover_tooltips" else v) for k, v in key))
    return made


# a template's options id → its kind and options, the hover tooltips' labels left out (see style_key)
_STYLES: dict[int, tuple] = {}


def _unlabelled(tooltips):
    """A frozen tooltip list (:func:`_freeze`) without its labels: the fields it reads."""
    items = tooltips[1] if isinstance(tooltips, tuple) and tooltips[:1] == ("<list>",) else tooltips
    return tuple(tip[1] if isinstance(tip, tuple) and len(tip) == 2 else tip for tip in items)


def style_key(element) -> tuple | int | None:
    """What ``element`` is drawn with, but for the words of its hover tooltips (the labels of its
    dimensions, with their units: they change with the mode, the fields they read do not): two
    elements with one style key are drawn alike, their tooltips' labels aside. An element not
    made by :func:`styled`: its options' id."""
    return _STYLES.get(element.id, element.id)


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


# the elements made of columns, and how they hold them: as a dict of arrays. HoloViews would try a
# pandas DataFrame first; measured here, a 200-point curve is then made in 0.76 ms instead of
# 0.52 ms and read back (dimension_values) in 0.21 ms instead of 0.16 ms, on every change
TABULAR = ("Curve", "Scatter", "Area")
TABULAR_DATA = ["dictionary"]


def styled(kind: str, data, **options):
    """An element of ``kind`` holding ``data``, cloned from a template that carries ``options``
    (one options entry per style, whatever the number of frames)."""
    options.setdefault("framewise", True)  # a norm option of each element: its axes follow its data
    if kind in ("Curve", "Scatter", "Area"):
        # a click on a legend entry mutes its glyph, drawn fully transparent: hidden. HoloViews
        # keeps a glyph muted through updates (it shows a hidden one again on every frame)
        options.setdefault("muted_alpha", 0.0)
    key = tuple(sorted((k, _freeze(v)) for k, v in options.items() if k not in ("kdims", "vdims", "label")))
    fields = {k: options[k] for k in ("kdims", "vdims", "label") if k in options}
    if kind in TABULAR:
        fields["datatype"] = TABULAR_DATA
    return template(kind, key).clone(data, **fields)


# the first line of every hover tooltip: the hovered glyph's legend label (its renderer's name,
# set by :func:`hover_names`), so that a tooltip says which of the plot's curves it reads
CURVE_TIP = ("curve", "$name")


def hover_names(plot, element):
    """A hook naming the element's glyph renderer after its legend label (the tooltips'
    ``$name``, :data:`CURVE_TIP`), once."""
    renderer = plot.handles.get("glyph_renderer")
    if renderer is not None and renderer.name != element.label:
        renderer.name = element.label


def _hovered(style: dict, *dims: hv.Dimension) -> dict:
    """``style`` with a hover tool whose tooltips name the curve, then read its ``dims`` (label
    and unit): one tooltip list per set of dimensions, so an overlay merges its curves' tools."""
    style.setdefault("tools", ["hover"])
    if "hover" in style["tools"]:
        style.setdefault("hover_tooltips", [CURVE_TIP, *((d.pprint_label, f"@{{{dimension_sanitizer(d.name)}}}")
                                                         for d in dims)])
        style["hooks"] = [*style.get("hooks", []), hover_names]
    return style


def curve(x, y, xdim, ydim, label, **style):
    _hovered(style, xdim, ydim)
    return styled("Curve", (np.asarray(x, dtype=float), np.asarray(y, dtype=float)),
                  kdims=[xdim], vdims=[ydim], label=label, **style)


def scatter(x, y, xdim, ydim, label, **style):
    _hovered(style, xdim, ydim)
    return styled("Scatter", (np.asarray(x, dtype=float), np.asarray(y, dtype=float)),
                  kdims=[xdim], vdims=[ydim], label=label, **style)


def overlay(items, title, png, *, logx=False, logy=False, legend="right", height=300):
    legend_opts = {"click_policy": "mute", "label_text_font_size": "11px", "spacing": 0, "padding": 4,
                   "margin": 4}
    hooks = [canvas, ticks, png_name(png)] + ([legend_outside] if legend == "right" else []) + ([log_ticks] if logx or logy else [])
    options = {"title": title, "responsive": True, "height": height, "logx": logx, "logy": logy,
               "framewise": True, "hooks": hooks, "legend_opts": legend_opts,
               "fontsize": {"title": "13px"}, "show_legend": legend is not None}
    if legend is not None:
        options["legend_position"] = "top_right" if legend == "right" else legend
    return styled("Overlay", list(items), **options)


@functools.cache
def _band_top(name: str, label: str, unit: str | None) -> hv.Dimension:
    """The dimension of a band's top edge (one per quantity, never changed)."""
    return hv.Dimension(f"{name}_upper", label=f"{label} (band top)", unit=unit)


MARKER_Y = hv.Dimension("y")  # a marker's vertical extent (never changed, never drawn on an axis)


def band_area(x, low, high, xdim: hv.Dimension, ydim: hv.Dimension, label: str, color: str):
    """A tolerance band: the area between ``low`` and ``high``."""
    # its own label: HoloViews finds a dimension by its label, and two alike would both read the lower
    upper = _band_top(ydim.name, ydim.label, ydim.unit)
    return styled("Area", (np.asarray(x, dtype=float), np.asarray(low, dtype=float), np.asarray(high, dtype=float)),
                  kdims=[xdim], vdims=[ydim, upper], label=label, color=color, fill_alpha=0.22, line_alpha=0.0,
                  **_hovered({}, xdim, ydim, upper))


def band_label(percentiles) -> str:
    low, high = percentiles
    return f"{low:g}–{high:g} % band"


def marker(x: float, dim: hv.Dimension):
    """The operating point: a dotted vertical line at ``x``."""
    return styled("VLine", float(x), kdims=[dim, MARKER_Y], color=OPERATING_COLOR,
                  line_dash="dotted", line_width=1.5)


def sized(layout: hv.Layout, width: int | None) -> hv.Layout:
    """``layout`` with plots ``width`` pixels wide (for a notebook or a saved file), or as they
    are (filling the width of their container) for None."""
    if width is None:
        return layout
    return layout.map(lambda plot: plot.opts(responsive=False, width=width), [hv.Overlay])



def amplitude_curves(groups: list, dims: dict, models: tuple, title: str, png: str) -> dict:
    """Measured points and models against frequency, one colour per amplitude (the data as dots,
    each model a line at the same amplitude), for |K| and the loss factor. ``groups`` as
    :func:`app.curves.amplitude_groups`; ``models``: (key in a group, label, line style) each."""
    palette = SWEEP_PALETTES["amplitude"]
    out = {}
    for i, (quantity, ydim) in enumerate((("magnitude", dims["magnitude"]), ("loss", dims["loss_factor"]))):
        items = []
        for n, g in enumerate(groups):
            color = palette[n % len(palette)]
            label = sweep_label(g["amplitude"], dims["amplitude"].unit)
            for key, name, style in models:
                if key in g:
                    items.append(curve(g["frequency_hz"], g[key][i], dims["frequency"], ydim, f"{label} {name}",
                                       color=color, **style))
            items.append(scatter(g["frequency_hz"], g["data"][i], dims["frequency"], ydim, f"{label} data",
                                 color=color, size=6, alpha=0.8))
        if not items:  # no data: an empty plot (the view hides it)
            items.append(scatter([], [], dims["frequency"], ydim, "data", color=palette[0], size=6))
        out[quantity] = overlay(items, f"{ydim.label}: {title}", f"{png}-{quantity}", legend=None, height=280)
    return out
