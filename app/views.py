"""Panel views of an :class:`~app.state.ExplorerState`: thin presentation, no physics.

Flow: widgets → the state → (cached) core → HoloViews elements → panes. Each plot is an
overlay of DynamicMaps, one element type per map, over functions of the state.
"""

from __future__ import annotations

import functools
import io
import json
import logging
import math

import holoviews as hv
import numpy as np
import panel as pn
import param
from bokeh.models import CustomJSTickFormatter, SaveTool
from holoviews import streams

from core.design import dumps_design

from . import plots
from .state import DESIGN_FIELDS, PRESETS, ExplorerState

log = logging.getLogger("bushing.app")

PLOT_OPTS = {
    "responsive": True,
    "min_height": 260,
    "tools": ["hover", "tap"],
    "active_tools": ["tap", "wheel_zoom"],
    "framewise": True,
    "show_grid": True,
}


def png_name(filename: str):
    """A HoloViews hook that names the PNG of the plot's save tool (no filename prompt)."""

    def hook(plot, _element):
        for tool in plot.state.toolbar.tools:
            if isinstance(tool, SaveTool):
                tool.filename = filename

    return hook


def guarded(fn):
    """A plot callback that never raises: on an unexpected error it logs one line (no
    traceback) and shows the last good element."""
    last = {}

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            out = fn(*args, **kwargs)
        except Exception as exc:  # noqa: BLE001 - keep the last good plot, say what happened
            log.warning("%s kept its last plot: %s: %s", fn.__name__, type(exc).__name__, exc)
            if "element" in last:
                return last["element"]
            raise
        last["element"] = out
        return out

    return wrapper


# ---- inputs --------------------------------------------------------------------------------


class LogSlider(pn.viewable.Viewer):
    """A slider over log10 of a positive state parameter that shows the value and its unit."""

    def __init__(self, state: ExplorerState, name: str, bounds, unit, **params):
        super().__init__(**params)
        self._state, self._name, self._bounds, self._unit = state, name, bounds, unit
        p = state.param[name]
        lo, hi = bounds()
        self.slider = pn.widgets.FloatSlider(
            label=self._label(),
            start=math.log10(lo),
            end=math.log10(hi),
            step=0.005,
            value=self._clip(math.log10(getattr(state, name))),
            format=self._formatter(),
            sizing_mode="stretch_width",
        )
        self.help = pn.widgets.TooltipIcon(value=p.doc, width=20, margin=(28, 6, 0, 0))
        self.slider.param.watch(self._from_slider, "value")
        state.param.watch(self._from_state, name)
        state.param.watch(self._rescale, "design")

    def _label(self):
        return f"{self._state.param[self._name].label} ({self._unit()})"

    def _formatter(self):
        return CustomJSTickFormatter(code="return Number(Math.pow(10, tick).toPrecision(3)).toString()")

    def _clip(self, v):
        lo, hi = self._bounds()
        return min(max(v, math.log10(lo)), math.log10(hi))

    def _from_slider(self, event):
        value = float(f"{10 ** event.new:.4g}")
        if not math.isclose(value, getattr(self._state, self._name), rel_tol=1e-3):
            setattr(self._state, self._name, value)

    def _from_state(self, event):
        v = self._clip(math.log10(event.new))
        if abs(v - self.slider.value) > 1e-9:
            self.slider.value = v

    def _rescale(self, _event):
        lo, hi = self._bounds()
        self.slider.param.update(
            start=math.log10(lo), end=math.log10(hi), label=self._label(),
            value=self._clip(math.log10(getattr(self._state, self._name))),
        )

    def __panel__(self):
        return pn.Row(self.slider, self.help, sizing_mode="stretch_width")


def error_text(state: ExplorerState, name: str):
    """The message beside a widget: what is wrong with its value, or nothing."""

    def render(errors):
        msg = errors.get(name)
        return f'<div class="field-error" data-field="{name}">⚠ {msg}</div>' if msg else ""

    return pn.pane.HTML(pn.bind(render, state.param.errors), margin=(0, 10, 4, 10),
                        styles={"color": "#b03a2e", "font-size": "0.9em"}, sizing_mode="stretch_width")


class DesignInputs(pn.viewable.Viewer):
    """Mode, geometry, material, operating point and sweep range, each with unit and help."""

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        steps = {"fractional_order": 0.05, "friction_strain_half": 5e-4}
        self.widgets = {
            name: pn.widgets.FloatInput.from_param(
                state.param[name], description=state.param[name].doc, step=steps.get(name, 0.5),
                sizing_mode="stretch_width", label=state.param[name].label,
            )
            for name in DESIGN_FIELDS
        }
        for name in ("freq_min", "freq_max"):
            self.widgets[name] = pn.widgets.FloatInput.from_param(
                state.param[name], description=state.param[name].doc, step=1.0,
                sizing_mode="stretch_width", label=state.param[name].label,
            )
        self.preset = pn.widgets.Select.from_param(
            state.param.preset, description=state.param.preset.doc, sizing_mode="stretch_width",
        )
        self.mode = pn.widgets.RadioButtonGroup.from_param(
            state.param.mode, description=state.param.mode.doc, color="primary",
            variant="outline", sizing_mode="stretch_width",
        )
        self.amplitude = LogSlider(state, "amplitude", lambda: state.amplitude_bounds, lambda: state.amplitude_unit)
        self.frequency = LogSlider(state, "frequency_hz", lambda: (0.1, 1000.0), lambda: "Hz")

    def _field(self, name):
        return pn.Column(self.widgets[name], error_text(self.state, name), margin=0, sizing_mode="stretch_width")

    def __panel__(self):
        geometry = [self._field(n) for n in ("inner_radius_mm", "outer_radius_mm", "length_mm")]
        material = [self._field(n) for n in list(DESIGN_FIELDS)[3:]]
        return pn.Column(
            self.preset,
            self.mode,
            pn.pane.Markdown("**Operating point**", margin=(8, 10, 0, 10)),
            self.amplitude,
            self.frequency,
            pn.Card(*geometry, title="Geometry", collapsed=False, sizing_mode="stretch_width"),
            pn.Card(*material, title="Material", collapsed=False, sizing_mode="stretch_width"),
            pn.Card(self._field("freq_min"), self._field("freq_max"), title="Frequency sweep",
                    sizing_mode="stretch_width"),
            sizing_mode="stretch_width",
        )


# ---- plots ---------------------------------------------------------------------------------


class ExplorerPlots(pn.viewable.Viewer):
    """Loop, |K| and loss factor against frequency and amplitude, linked by the operating
    point: a tap on a frequency axis sets the frequency, on an amplitude axis the amplitude."""

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        s = state.param
        design_deps = {"design": s.design, "fmin": s.freq_min, "fmax": s.freq_max, "errors": s.errors}
        op = {"f": s.frequency_hz, "x": s.amplitude}
        ref = {"reference": s.reference}

        self.loop = (
            hv.DynamicMap(pn.bind(self._loop_branches, **design_deps, **op))
            * hv.DynamicMap(pn.bind(self._loop_reference, **design_deps, **op, **ref))
            * hv.DynamicMap(pn.bind(self._loop_total, **design_deps, **op))
        ).opts(
            hv.opts.Curve(responsive=True, min_height=300, framewise=True, show_grid=True, tools=["hover"], line_width=1.5),
            hv.opts.Overlay(legend_position="top_left", hooks=[png_name("bushing-hysteresis-loop")]),
        )

        titles = {
            ("magnitude", "frequency"): "|K| against frequency",
            ("loss_factor", "frequency"): "Loss factor against frequency",
            ("magnitude", "amplitude"): "|K| against amplitude",
            ("loss_factor", "amplitude"): "Loss factor against amplitude",
        }
        self.panels, self.taps = {}, []
        for quantity in ("magnitude", "loss_factor"):
            for axis in ("frequency", "amplitude"):
                logx = axis == "amplitude"
                operating = hv.DynamicMap(
                    pn.bind(self._operating_curve, quantity=quantity, axis=axis, **design_deps, **op)
                ).opts(hv.opts.Curve(**PLOT_OPTS, logx=logx))
                # a linked stream attaches to a map of single elements, not to an overlay
                tap = streams.Tap(source=operating, x=None, y=None)
                tap.add_subscriber(functools.partial(self._on_tap, axis))
                self.taps.append(tap)
                self.panels[(quantity, axis)] = (
                    hv.DynamicMap(pn.bind(self._sweep, quantity=quantity, axis=axis, **design_deps, **op))
                    * hv.DynamicMap(pn.bind(self._reference_curve, quantity=quantity, axis=axis, **design_deps, **op, **ref))
                    * operating
                    * hv.DynamicMap(pn.bind(self._marker, axis=axis, **op))
                ).opts(
                    hv.opts.Curve(**PLOT_OPTS, logx=logx),
                    hv.opts.VLine(color=plots.OPERATING_COLOR, line_width=1.5, line_dash="dotted"),
                    hv.opts.NdOverlay(legend_position="right"),
                    hv.opts.Overlay(title=titles[(quantity, axis)], logx=logx,
                                    hooks=[png_name(f"bushing-{quantity}-vs-{axis}")]),
                )

    # data → elements (each callback one element type)

    @guarded
    def _loop_total(self, design, fmin, fmax, errors, f, x):
        return plots.loop_total(self.state.hysteresis_loop(), design.mode).opts(
            color="black", line_width=2.5,
            title=f"Hysteresis loop at {x:.3g} {self.state.amplitude_unit}, {f:.3g} Hz",
        )

    @guarded
    def _loop_branches(self, design, fmin, fmax, errors, f, x):
        return plots.loop_branches(self.state.hysteresis_loop(), design.mode)

    @guarded
    def _loop_reference(self, design, fmin, fmax, errors, f, x, reference):
        mode = design.mode
        if reference is None or reference.mode != mode:
            return plots.loop_total({"displacement": [], "force": []}, mode, label="")
        return plots.loop_total(self.state.hysteresis_loop(reference), mode, label="reference").opts(**plots.REFERENCE_STYLE)

    def _sweep_data(self, axis, design=None):
        if axis == "frequency":
            return self.state.frequency_sweep(design)
        return self.state.amplitude_sweep(design)

    def _dims(self, quantity, axis, mode):
        xdim = plots.FREQUENCY if axis == "frequency" else plots.amplitude_dim(mode)
        ydim = plots.magnitude_dim(mode) if quantity == "magnitude" else plots.LOSS
        return xdim, ydim

    @guarded
    def _sweep(self, quantity, axis, design, fmin, fmax, errors, f, x):
        data = self._sweep_data(axis)
        xdim, ydim = self._dims(quantity, axis, design.mode)
        if axis == "frequency":
            keys, key_label, unit, xs = data["amplitude"], "amplitude", self.state.amplitude_unit, data["frequency_hz"]
        else:
            keys, key_label, unit, xs = data["frequency_hz"], "frequency", "Hz", data["amplitude"]
        return plots.sweep_overlay(xs, xdim, data[quantity], ydim, keys, key_label, unit).opts(
            hv.opts.Curve(line_width=1.3)
        )

    def _operating_data(self, axis, design):
        if axis == "frequency":
            d = self.state.frequency_sweep(design, amplitudes=self.state.amplitude)
            return d["frequency_hz"], d
        d = self.state.amplitude_sweep(design, frequencies=self.state.frequency_hz)
        return d["amplitude"], d

    @guarded
    def _operating_curve(self, quantity, axis, design, fmin, fmax, errors, f, x):
        xs, d = self._operating_data(axis, design)
        xdim, ydim = self._dims(quantity, axis, design.mode)
        label = f"at {x:.3g} {self.state.amplitude_unit}" if axis == "frequency" else f"at {f:.3g} Hz"
        return plots.operating_curve(xs, xdim, d[quantity][0], ydim, label).opts(color=plots.OPERATING_COLOR, line_width=3)

    @guarded
    def _reference_curve(self, quantity, axis, design, fmin, fmax, errors, f, x, reference):
        xdim, ydim = self._dims(quantity, axis, design.mode)
        if reference is None or reference.mode != design.mode:
            return plots.operating_curve([], xdim, [], ydim, "")
        xs, d = self._operating_data(axis, reference)
        return plots.operating_curve(xs, xdim, d[quantity][0], ydim, "reference").opts(**plots.REFERENCE_STYLE)

    @guarded
    def _marker(self, axis, f, x):
        return plots.marker(f if axis == "frequency" else x)

    def _on_tap(self, axis, x, y):
        if x is None or not np.isfinite(x):
            return
        if axis == "frequency":
            self.state.frequency_hz = float(np.clip(float(f"{x:.4g}"), 0.1, 1000.0))
        else:
            lo, hi = self.state.amplitude_bounds
            self.state.amplitude = float(np.clip(float(f"{x:.4g}"), lo, hi))

    def __panel__(self):
        def pane(key):  # separate panes: Panel links the axes of dimensions they share
            return pn.pane.HoloViews(self.panels[key], sizing_mode="stretch_width", height=300)

        return pn.Column(
            pn.pane.HoloViews(self.loop, sizing_mode="stretch_width", height=340, linked_axes=False),
            pn.Row(pane(("magnitude", "frequency")), pane(("magnitude", "amplitude")), sizing_mode="stretch_width"),
            pn.Row(pane(("loss_factor", "frequency")), pane(("loss_factor", "amplitude")), sizing_mode="stretch_width"),
            sizing_mode="stretch_width",
        )


class SlicesView(pn.viewable.Viewer):
    """Paper A: one equivalent modulus against 2 and 3 slices and the continuum."""

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        s = state.param
        deps = {"design": s.design, "f": s.frequency_hz, "errors": s.errors}
        opts = [hv.opts.Curve(**PLOT_OPTS, logx=True), hv.opts.NdOverlay(legend_position="right"),
                hv.opts.VLine(color=plots.OPERATING_COLOR, line_dash="dotted")]
        titles = {
            "magnitude": "|K|: single modulus, slices and continuum",
            "magnitude_diff_pct": "|K| difference from the single modulus (%)",
            "loss_factor": "Loss factor",
        }
        self.overlays = {}
        for which, title in titles.items():
            curves = hv.DynamicMap(pn.bind(self._curves, which=which, **deps)).opts(*opts)
            marker = hv.DynamicMap(pn.bind(plots.marker, s.amplitude)).opts(*opts)
            # a linked stream attaches to a map of single elements, not to an overlay
            streams.Tap(source=marker, x=None, y=None).add_subscriber(self._on_tap)
            self.overlays[which] = (curves * marker).opts(
                *opts, hv.opts.Overlay(title=title, logx=True, hooks=[png_name(f"bushing-slices-{which}")]))

    @guarded
    def _curves(self, which, design, f, errors):
        data = self.state.slice_comparison()
        mode = design.mode
        ydim = {
            "magnitude": plots.magnitude_dim(mode),
            "loss_factor": plots.LOSS,
            "magnitude_diff_pct": hv.Dimension("difference", label="Difference", unit="%"),
        }[which]
        return plots.slice_curves(data["amplitude"], mode, data[which], ydim)

    def _on_tap(self, x, y):
        if x is not None and np.isfinite(x):
            lo, hi = self.state.amplitude_bounds
            self.state.amplitude = float(np.clip(float(f"{x:.4g}"), lo, hi))

    def summary(self, design, f, x):
        data = self.state.slice_comparison()
        xs = data["amplitude"]
        rows = ["| model | largest \\|K\\| difference | largest loss-factor difference |", "|---|---|---|"]
        for s in (2, 3, "continuum"):
            if s in data["magnitude_diff_pct"]:
                dm, de = data["magnitude_diff_pct"][s], data["loss_factor_diff_pct"][s]
                im, ie = int(np.argmax(np.abs(dm))), int(np.argmax(np.abs(de)))
                rows.append(
                    f"| {s} {'slices' if s != 'continuum' else ''} | {dm[im]:+.2f} % at {xs[im]:.3g} {self.state.amplitude_unit} "
                    f"| {de[ie]:+.2f} % at {xs[ie]:.3g} {self.state.amplitude_unit} |"
                )
        return "\n".join(rows)

    def __panel__(self):
        s = self.state.param
        return pn.Column(
            pn.pane.Markdown(
                "Paper A splits the rubber into concentric slices of equal thickness, each with "
                "its own equivalent strain; the continuum takes infinitely many. The single "
                "equivalent modulus (eqs 17/18) is close when the differences below are small. "
                "All at the loop frequency.", sizing_mode="stretch_width"),
            pn.pane.Markdown(pn.bind(self.summary, s.design, s.frequency_hz, s.amplitude), sizing_mode="stretch_width"),
            pn.pane.HoloViews(self.overlays["magnitude"], sizing_mode="stretch_width", height=300),
            pn.pane.HoloViews(self.overlays["magnitude_diff_pct"], sizing_mode="stretch_width", height=260),
            pn.pane.HoloViews(self.overlays["loss_factor"], sizing_mode="stretch_width", height=260),
            sizing_mode="stretch_width",
        )


class TeachingView(pn.viewable.Viewer):
    """The Fletcher–Gent effect branch by branch, and the loop changing as amplitude sweeps."""

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        s = state.param
        deps = {"design": s.design, "f": s.frequency_hz, "errors": s.errors}
        self.frames = 48
        self.player = pn.widgets.Player(
            label="Amplitude sweep", start=0, end=self.frames - 1, value=self.frames // 2,
            loop_policy="loop", interval=150, show_value=False, show_loop_controls=False,
            sizing_mode="stretch_width",
        )
        marker = hv.DynamicMap(pn.bind(lambda x: plots.marker(x), x=s.amplitude))
        opts = [hv.opts.Area(**{k: v for k, v in PLOT_OPTS.items() if k not in ("tools", "active_tools")}, logx=True, fill_alpha=0.55, line_width=1),
                hv.opts.Overlay(legend_position="top_right"), hv.opts.VLine(color=plots.OPERATING_COLOR, line_dash="dotted")]
        self.real = (hv.DynamicMap(pn.bind(self._areas, which="real", **deps)) * marker).opts(
            *opts, hv.opts.Overlay(title="Re K, branch by branch (stacked)", logx=True,
                                   hooks=[png_name("bushing-branches-stiffness")]))
        self.loss = (hv.DynamicMap(pn.bind(self._areas, which="loss", **deps)) * marker).opts(
            *opts, hv.opts.Overlay(title="Loss factor, branch by branch (stacked)", logx=True,
                                   hooks=[png_name("bushing-branches-loss-factor")]))
        self.loop = hv.DynamicMap(pn.bind(self._loop_frame, frame=self.player.param.value, **deps)).opts(
            hv.opts.Curve(responsive=True, min_height=300, framewise=False, tools=["hover"]),
            hv.opts.NdOverlay(legend_position="top_left", xlim=(-1.05, 1.05), ylim=(-1.1, 1.1),
                              hooks=[png_name("bushing-loop-shape")]),
        )

    def _frame_amplitudes(self):
        return np.geomspace(*self.state.amplitude_bounds, self.frames)

    @guarded
    def _areas(self, which, design, f, errors):
        data = self.state.branch_breakdown()
        mode = design.mode
        ydim = plots.magnitude_dim(mode) if which == "real" else plots.LOSS
        if which == "real":
            ydim = hv.Dimension("real", label="Re K", unit=ydim.unit)
        return plots.stacked_areas(data["amplitude"], plots.amplitude_dim(mode), data[which], ydim)

    @guarded
    def _loop_frame(self, frame, design, f, errors):
        x = self._frame_amplitudes()[frame]
        data = self.state.hysteresis_loop(amplitude=x)
        return plots.normalised_loop(data).opts(
            hv.opts.NdOverlay(title=f"Loop shape at {x:.3g} {self.state.amplitude_unit}, {f:.3g} Hz"),
        )

    def __panel__(self):
        return pn.Column(
            pn.pane.Markdown(TEACHING_TEXT, sizing_mode="stretch_width"),
            pn.Row(
                pn.Column(pn.pane.HoloViews(self.real, sizing_mode="stretch_width", height=300),
                          pn.pane.HoloViews(self.loss, sizing_mode="stretch_width", height=300),
                          sizing_mode="stretch_width"),
                pn.Column(self.player, pn.pane.HoloViews(self.loop, sizing_mode="stretch_width", height=420),
                          sizing_mode="stretch_width"),
                sizing_mode="stretch_width",
            ),
            sizing_mode="stretch_width",
        )


TEACHING_TEXT = """
**Why filled rubber softens and dissipates more as the amplitude grows.** The stress is the sum of
three branches driven by the same strain. The **elastic** branch (blue) is a spring: it stores and
gives back. The **viscoelastic** branch (green) depends on the rate: it adds stiffness and a
constant share of loss at every amplitude. The **friction** branch (red) is the carbon-black
filler network: at small amplitude it is stiff and nearly elastic; as the amplitude passes ε½ it
slips, its stiffness falls away and it dissipates most, hence the loss factor's peak; at large
amplitude it saturates at σ_fmax and both its stiffness and its share of the loss fade. Press play
to watch the loop change shape: a thin ellipse at small amplitude, a fat friction loop near the
knee, a sheared parallelogram at large amplitude.
"""


class CompareView(pn.viewable.Viewer):
    """Pin the current design as a reference; show the differences in %."""

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        self.pin = pn.widgets.Button(label="Pin as reference", color="primary", description="Keep this design to compare the next ones with it (dashed curves).")
        self.clear = pn.widgets.Button(label="Clear reference", color="light")
        self.pin.on_click(lambda _e: state.pin_reference())
        self.clear.on_click(lambda _e: state.clear_reference())

    def table(self, reference, design, f, x, errors):
        c = self.state.comparison()
        if c is None:
            return "_No reference pinned: press **Pin as reference**, then change the design._"
        if reference.mode != design.mode:
            return "_The reference is in another mode; switch back to compare._"
        unit = self.state.stiffness_unit
        (m_now, m_ref, m_d), (e_now, e_ref, e_d) = c["operating"]["magnitude"], c["operating"]["loss_factor"]
        return (
            f"| at {f:.3g} Hz, {x:.3g} {self.state.amplitude_unit} | this design | reference | difference |\n|---|---|---|---|\n"
            f"| \\|K\\| ({unit}) | {m_now:.4g} | {m_ref:.4g} | {m_d:+.2f} % |\n"
            f"| loss factor | {e_now:.4f} | {e_ref:.4f} | {e_d:+.2f} % |\n\n"
            f"Largest difference over the frequency sweep: \\|K\\| {c['largest_over_frequency']['magnitude']:+.2f} %, "
            f"loss factor {c['largest_over_frequency']['loss_factor']:+.2f} %; over the amplitude sweep: "
            f"\\|K\\| {c['largest_over_amplitude']['magnitude']:+.2f} %, loss factor {c['largest_over_amplitude']['loss_factor']:+.2f} %."
        )

    def __panel__(self):
        s = self.state.param
        return pn.Column(
            pn.Row(self.pin, self.clear),
            pn.pane.Markdown(pn.bind(self.table, s.reference, s.design, s.frequency_hz, s.amplitude, s.errors),
                             sizing_mode="stretch_width", css_classes=["comparison"]),
            sizing_mode="stretch_width",
        )


class ExportView(pn.viewable.Viewer):
    """Download the design file and the stiffness table; PNGs from each plot's toolbar."""

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        self.design_file = pn.widgets.FileDownload(
            callback=self._design_json, filename="bushing-design.json", label="Design file (JSON)",
            color="default", sizing_mode="stretch_width",
        )
        self.table_file = pn.widgets.FileDownload(
            callback=self._table_csv, filename="bushing-stiffness.csv", label="Stiffness table (CSV)",
            color="default", sizing_mode="stretch_width",
        )

    def _design_json(self):
        return io.StringIO(dumps_design(self.state.design))

    def _table_csv(self):
        from core.cli import NUMBER_FORMAT

        table = self.state.stiffness_table()
        lines = [",".join(table)]
        lines += [",".join(NUMBER_FORMAT.format(v) for v in row) for row in zip(*table.values())]
        return io.StringIO("\n".join(lines) + "\n")

    def __panel__(self):
        return pn.Column(
            self.design_file,
            self.table_file,
            pn.pane.Markdown(
                "PNG: the save icon in each plot's toolbar. Share: the address bar holds the whole "
                "design; copy it.", sizing_mode="stretch_width", styles={"font-size": "0.9em"}),
            sizing_mode="stretch_width",
        )


def status_banner(state: ExplorerState):
    def render(errors, design):
        if errors:
            fields = ", ".join(state.param[n].label for n in errors if n in state.param)
            return pn.pane.Alert(
                f"Some inputs are not valid ({fields}): see the messages beside them. The plots "
                "show the last valid design.", alert_type="warning", sizing_mode="stretch_width",
                css_classes=["input-errors"],
            )
        effects = ", ".join(design.effect_parameters) if design.effects else ""
        text = f"**{design.name or 'Custom design'}**, {design.mode}" + (f"; effects: {effects}" if effects else "")
        return pn.pane.Markdown(text, sizing_mode="stretch_width", margin=(0, 10))

    return pn.panel(pn.bind(render, state.param.errors, state.param.design), sizing_mode="stretch_width")


URL_NAMES = {
    "mode": "mode",
    "inner_radius_mm": "a_mm",
    "outer_radius_mm": "b_mm",
    "length_mm": "L_mm",
    "shear_modulus_mpa": "mu_MPa",
    "fractional_coefficient_mpa": "m_MPa",
    "fractional_order": "alpha",
    "friction_stress_max_kpa": "sigma_kPa",
    "friction_strain_half": "eps_half",
    "amplitude": "amp",
    "frequency_hz": "f_Hz",
    "freq_min": "fmin_Hz",
    "freq_max": "fmax_Hz",
}


def presets_text():
    return ", ".join(PRESETS)


def design_summary_json(state):  # used by tests and the About tab
    return json.dumps(state.design.to_dict(), indent=2)
