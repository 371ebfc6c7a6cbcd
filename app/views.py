"""Panel views of an :class:`~app.state.ExplorerState`: thin presentation, no physics.

Flow: widgets → the state → (cached) core → data → figures (:mod:`app.figures`) → panes. A
change of the state refreshes each view's figures once, in one message.
"""

from __future__ import annotations

import io
import logging
import math
import typing

import numpy as np
import panel as pn
from bokeh.models import CustomJSTickFormatter

from core.bushing import STRUCTURAL_EFFECTS
from core.design import dumps_design

from . import plots
from .figures import AutoRange, Axis, Figure
from .state import AMPLITUDE_DISPLAY, DESIGN_FIELDS, FORCE_DISPLAY, STIFFNESS_DISPLAY, ExplorerState

log = logging.getLogger("bushing.app")

# ---- inputs --------------------------------------------------------------------------------


class FloatInput(pn.widgets.FloatInput):
    """Panel's FloatInput without the 50 ms debounce on its value: every edit answers at once
    (Panel marks such properties as priority changes, as its Tabulator does for its data)."""

    _priority_changes: typing.ClassVar[list[str]] = ["value"]


class FloatSlider(pn.widgets.FloatSlider):
    """Panel's FloatSlider without the 50 ms debounce on its value (see :class:`FloatInput`)."""

    _priority_changes: typing.ClassVar[list[str]] = ["value"]


class LogSlider(pn.viewable.Viewer):
    """A slider over log10 of a positive state parameter that shows the value and its unit."""

    def __init__(self, state: ExplorerState, name: str, bounds, unit, **params):
        super().__init__(**params)
        self._state, self._name, self._bounds, self._unit = state, name, bounds, unit
        p = state.param[name]
        lo, hi = bounds()
        self.slider = FloatSlider(
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
        v = self._moved_to(event.new)
        if v is not None:
            self.slider.value = v

    def _moved_to(self, value):
        """Where the slider must go to show a value set elsewhere (a tap, a link, a preset), or
        None: not back to the 4-digit rounding of its own value, which would send every move
        back to the browser."""
        v = self._clip(math.log10(value))
        lo, hi = self._bounds()
        inside = math.log10(lo) <= self.slider.value <= math.log10(hi)
        return v if abs(v - self.slider.value) > self.slider.step / 2 or not inside else None

    def _rescale(self, _event):
        """New bounds (and unit) for a new design; Panel sends only what changed."""
        lo, hi = self._bounds()
        changes = {"start": math.log10(lo), "end": math.log10(hi), "label": self._label()}
        v = self._moved_to(getattr(self._state, self._name))
        if v is not None:
            changes["value"] = v
        self.slider.param.update(**changes)

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
            name: FloatInput.from_param(
                state.param[name], description=state.param[name].doc, step=steps.get(name, 0.5),
                sizing_mode="stretch_width", label=state.param[name].label,
            )
            for name in DESIGN_FIELDS
        }
        for name in ("freq_min", "freq_max"):
            self.widgets[name] = FloatInput.from_param(
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


def _axes(mode):
    """The plotted quantities, with the units of the mode."""
    amp_unit = AMPLITUDE_DISPLAY[mode][0]
    return {
        "frequency": Axis("frequency_hz", "Frequency", "Hz"),
        "amplitude": Axis("amplitude", "Amplitude", amp_unit),
        "magnitude": Axis("magnitude", "|K|", STIFFNESS_DISPLAY[mode][0]),
        "loss_factor": Axis("loss_factor", "Loss factor"),
        "displacement": Axis("displacement", "Displacement" if mode == "axial" else "Angle", amp_unit),
        "force": Axis("force", "Force" if mode == "axial" else "Moment", FORCE_DISPLAY[mode][0]),
        "difference": Axis("difference", "Difference", "%"),
        "real": Axis("real", "Re K", STIFFNESS_DISPLAY[mode][0]),
    }


def update_or_keep(what: str, update) -> None:
    """Run ``update`` holding the document (its changes go as one message). It never raises:
    an unexpected error keeps what is shown and is logged in one line, with ``what`` was kept."""
    try:
        with pn.io.hold():
            update()
    except Exception as exc:  # noqa: BLE001 - keep the last view, say what happened
        log.warning("%s: %s: %s", what, type(exc).__name__, exc)


class PlotView(pn.viewable.Viewer):
    """Figures refreshed together, in one message, when the state parameters they show change.
    A refresh never raises: an unexpected error is logged in one line and the last plots stay."""

    WATCH: tuple = ()

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        self.figures: dict = {}
        self._mode = None
        self._shown = True
        self._stale = False

    def _start(self):
        self.state.param.watch(self._on_change, list(self.WATCH))
        self.refresh()

    def _on_change(self, *_events):
        if self._shown:
            self.refresh()
        else:
            self._stale = True  # a hidden tab catches up when shown

    def show(self, shown: bool):
        """Tell the view whether its tab is on screen."""
        self._shown = shown
        if shown and self._stale:
            self._stale = False
            self.refresh()

    def refresh(self):
        update_or_keep(f"{type(self).__name__} kept its last plots", self._refresh)

    def _refresh(self):
        mode = self.state.design.mode
        if mode != self._mode:
            self._mode = mode
            self._set_axes(_axes(mode))
        self._update()

    def _set_axes(self, axes):
        raise NotImplementedError

    def _update(self):
        raise NotImplementedError

    def _tap_amplitude(self, x):
        if x is not None and np.isfinite(x) and x > 0:
            lo, hi = self.state.amplitude_bounds
            self.state.amplitude = float(np.clip(float(f"{x:.4g}"), lo, hi))

    def _tap_frequency(self, x):
        if x is not None and np.isfinite(x) and x > 0:
            self.state.frequency_hz = float(np.clip(float(f"{x:.4g}"), 0.1, 1000.0))


class ExplorerPlots(PlotView):
    """Loop, |K| and loss factor against frequency and amplitude, linked by the operating
    point: a tap on a frequency axis sets the frequency, on an amplitude axis the amplitude."""

    WATCH = ("design", "freq_min", "freq_max", "errors", "frequency_hz", "amplitude", "reference",
             "measured", "measured_loop")
    def __init__(self, state: ExplorerState, **params):
        super().__init__(state, **params)
        axes = _axes(state.design.mode)
        shared = {name: AutoRange() for name in ("frequency", "amplitude", "magnitude", "loss_factor")}
        self.loop = Figure("Hysteresis loop at the operating point", axes["displacement"], axes["force"],
                           height=330, png="bushing-hysteresis-loop", legend="inside")
        for name, color in plots.BRANCH_COLORS.items():
            self.loop.line(name, name, color=color, line_width=1.5)
        self.loop.line("reference", "reference", **plots.REFERENCE_STYLE)
        self.loop.line("total", "total", color="black", line_width=2.5)
        self.loop.points("measured", "measured", size=4, color="#222222", alpha=0.5)
        titles = {
            ("magnitude", "frequency"): "|K| against frequency",
            ("loss_factor", "frequency"): "Loss factor against frequency",
            ("magnitude", "amplitude"): "|K| against amplitude",
            ("loss_factor", "amplitude"): "Loss factor against amplitude",
        }
        for (quantity, axis), title in titles.items():
            fig = Figure(title, axes[axis], axes[quantity], x_log=axis == "amplitude",
                         x_range=shared[axis], y_range=shared[quantity], marker=True,
                         png=f"bushing-{quantity}-vs-{axis}")
            palette = plots.SWEEP_PALETTES["amplitude" if axis == "frequency" else "frequency"]
            n = len(state.sweep_amplitudes() if axis == "frequency" else state.sweep_frequencies())
            fig.lines("sweeps", [""] * n, palette, line_width=1.3)
            fig.line("reference", "reference", **plots.REFERENCE_STYLE)
            fig.line("operating", "operating point", color=plots.OPERATING_COLOR, line_width=3)
            fig.points("measured", "measured", size=5, color="#222222", alpha=0.6, marker="circle")
            fig.on_tap(self._tap_frequency if axis == "frequency" else self._tap_amplitude)
            self.figures[(quantity, axis)] = fig
        self.summary = pn.pane.HTML("", sizing_mode="stretch_width", css_classes=["operating-point"],
                                    margin=(0, 10))
        self._start()

    def _set_axes(self, axes):
        self.loop.set_axes(axes["displacement"], axes["force"])
        for (quantity, axis), fig in self.figures.items():
            fig.set_axes(axes[axis], axes[quantity])

    def _update(self):
        s = self.state
        lp = s.hysteresis_loop()
        for name in (*plots.BRANCH_COLORS, "total"):
            key = "force" if name == "total" else f"force_{name}"
            self.loop.set(name, x=lp["displacement"], y=lp[key])
        ref = s.reference if s.reference is not None and s.reference.mode == s.design.mode else None
        if ref is not None:
            rl = s.hysteresis_loop(ref)
            self.loop.set("reference", x=rl["displacement"], y=rl["force"])
        else:
            self.loop.clear("reference")
        ml = s.measured_loop_points()
        if ml is not None:
            self.loop.set("measured", x=ml["displacement"], y=ml["force"])
        else:
            self.loop.clear("measured")
        measured = s.measured_points()
        sweeps = {"frequency": s.frequency_sweep(), "amplitude": s.amplitude_sweep()}
        operating = {"frequency": s.frequency_sweep(amplitudes=s.amplitude),
                     "amplitude": s.amplitude_sweep(frequencies=s.frequency_hz)}
        reference = ({"frequency": s.frequency_sweep(ref, amplitudes=s.amplitude),
                      "amplitude": s.amplitude_sweep(ref, frequencies=s.frequency_hz)} if ref else None)
        for (quantity, axis), fig in self.figures.items():
            data = sweeps[axis]
            xs = data["frequency_hz"] if axis == "frequency" else data["amplitude"]
            keys = data["amplitude"] if axis == "frequency" else data["frequency_hz"]
            unit = s.amplitude_unit if axis == "frequency" else "Hz"
            fig.set_lines("sweeps", xs, data[quantity], [plots.sweep_label(k, unit) for k in keys])
            op = operating[axis]
            fig.set("operating", x=xs, y=op[quantity][0])
            if reference:
                fig.set("reference", x=xs, y=reference[axis][quantity][0])
            else:
                fig.clear("reference")
            fig.set_marker(s.frequency_hz if axis == "frequency" else s.amplitude)
            if measured is not None:
                fig.set("measured", x=measured["frequency_hz" if axis == "frequency" else "amplitude"],
                        y=measured[quantity])
            else:
                fig.clear("measured")
        point = s.operating_point()
        self.summary.object = (
            f'<span class="op-summary"><b>Operating point</b>: <span class="op-point">{s.amplitude:.3g} '
            f"{s.amplitude_unit}, {s.frequency_hz:.3g} Hz</span> &nbsp;→&nbsp; |K| = "
            f"<b>{point['magnitude']:.4g} {s.stiffness_unit}</b>, loss factor <b>{point['loss_factor']:.4f}</b></span>"
        )

    def __panel__(self):
        def pane(fig, height=300):
            return pn.pane.Bokeh(fig.fig, sizing_mode="stretch_width", height=height)

        f = self.figures
        return pn.Column(
            self.summary,
            pane(self.loop, 330),
            pn.Row(pane(f[("magnitude", "frequency")]), pane(f[("magnitude", "amplitude")]), sizing_mode="stretch_width"),
            pn.Row(pane(f[("loss_factor", "frequency")]), pane(f[("loss_factor", "amplitude")]), sizing_mode="stretch_width"),
            sizing_mode="stretch_width",
        )


class SlicesView(PlotView):
    """Paper A: one equivalent modulus against 2 and 3 slices and the continuum."""

    WATCH = ("design", "errors", "frequency_hz", "amplitude")
    NAMES: typing.ClassVar = {1: "1 slice (eqs 17/18)", 2: "2 slices", 3: "3 slices", "continuum": "continuum"}

    def __init__(self, state: ExplorerState, **params):
        super().__init__(state, **params)
        axes = _axes(state.design.mode)
        shared_x = AutoRange()
        specs = {
            "magnitude": ("|K|: single modulus, slices and continuum", axes["magnitude"], (1, 2, 3, "continuum")),
            "magnitude_diff_pct": ("|K| difference from the single modulus (%)", axes["difference"], (2, 3, "continuum")),
            "loss_factor": ("Loss factor", axes["loss_factor"], (1, 2, 3, "continuum")),
        }
        for which, (title, y, models) in specs.items():
            fig = Figure(title, axes["amplitude"], y, x_log=True, x_range=shared_x, marker=True,
                         png=f"bushing-slices-{which}", height=280)
            for m in models:
                fig.line(str(m), self.NAMES[m], color=plots.SLICE_COLORS[m], line_width=2)
            fig.on_tap(self._tap_amplitude)
            self.figures[which] = fig
        self.table = pn.pane.Markdown("", sizing_mode="stretch_width")
        self._start()

    def _set_axes(self, axes):
        ys = {"magnitude": axes["magnitude"], "magnitude_diff_pct": axes["difference"], "loss_factor": axes["loss_factor"]}
        for which, fig in self.figures.items():
            fig.set_axes(axes["amplitude"], ys[which])

    def _update(self):
        data = self.state.slice_comparison()
        for which, fig in self.figures.items():
            for m in fig.sources:
                key = "continuum" if m == "continuum" else int(m)
                if key in data[which]:
                    fig.set(m, x=data["amplitude"], y=data[which][key])
                else:
                    fig.clear(m)
            fig.set_marker(self.state.amplitude)
        self.table.object = self.summary(data)

    def summary(self, data):
        xs, unit = data["amplitude"], self.state.amplitude_unit
        rows = ["| model | largest \\|K\\| difference | largest loss-factor difference |", "|---|---|---|"]
        for s in (2, 3, "continuum"):
            if s in data["magnitude_diff_pct"]:
                dm, de = data["magnitude_diff_pct"][s], data["loss_factor_diff_pct"][s]
                im, ie = int(np.argmax(np.abs(dm))), int(np.argmax(np.abs(de)))
                rows.append(f"| {self.NAMES[s]} | {dm[im]:+.2f} % at {xs[im]:.3g} {unit} "
                            f"| {de[ie]:+.2f} % at {xs[ie]:.3g} {unit} |")
        missing = [self.NAMES[s] for s in (2, 3, "continuum") if s not in data["magnitude"]]
        if missing:
            rows.append(f"\n_Not shown, the iteration did not converge: {', '.join(missing)}._")
        return "\n".join(rows)

    def __panel__(self):
        return pn.Column(
            pn.pane.Markdown(
                "Paper A splits the rubber into concentric slices of equal thickness, each with "
                "its own equivalent strain; the continuum takes infinitely many. The single "
                "equivalent modulus (eqs 17/18) is close when the differences below are small. "
                "All at the loop frequency; tap a plot to move the amplitude.", sizing_mode="stretch_width"),
            self.table,
            *(pn.pane.Bokeh(f.fig, sizing_mode="stretch_width", height=280) for f in self.figures.values()),
            sizing_mode="stretch_width",
        )


class TeachingView(PlotView):
    """The Fletcher–Gent effect branch by branch, and the loop changing as amplitude sweeps."""

    WATCH = ("design", "errors", "frequency_hz", "amplitude")
    FRAMES = 48

    def __init__(self, state: ExplorerState, **params):
        super().__init__(state, **params)
        axes = _axes(state.design.mode)
        shared_x = AutoRange()
        self.player = pn.widgets.Player(
            label="Amplitude sweep", start=0, end=self.FRAMES - 1, value=self.FRAMES // 2,
            loop_policy="loop", interval=150, show_value=False, show_loop_controls=False,
            sizing_mode="stretch_width",
        )
        for which, title, y in (("real", "Re K, branch by branch (stacked)", axes["real"]),
                                ("loss", "Loss factor, branch by branch (stacked)", axes["loss_factor"])):
            fig = Figure(title, axes["amplitude"], y, x_log=True, x_range=shared_x, marker=True,
                         png=f"bushing-branches-{which}", legend="inside", hover=False)
            for name, color in plots.BRANCH_COLORS.items():
                fig.band(name, name, color=color, fill_alpha=0.55)
            fig.on_tap(self._tap_amplitude)
            self.figures[which] = fig
        rel = (Axis("x_rel", "Drive / peak drive"), Axis("f_rel", "Force / peak force"))
        self.loop = Figure("Loop shape during the amplitude sweep", *rel, height=420,
                           png="bushing-loop-shape", legend="inside", x_range=(-1.05, 1.05),
                           y_range=(-1.1, 1.1))
        self.loop.line("total", "total", color="black", line_width=2.5)
        for name, color in plots.BRANCH_COLORS.items():
            self.loop.line(name, name, color=color, line_width=1.5)
        self.frame_label = pn.pane.HTML("", css_classes=["loop-frame"], margin=(0, 10))
        self.player.param.watch(lambda _e: self._frame(), "value")
        self._start()

    def _set_axes(self, axes):
        self.figures["real"].set_axes(axes["amplitude"], axes["real"])
        self.figures["loss"].set_axes(axes["amplitude"], axes["loss_factor"])

    def _update(self):
        d = self.state.branch_breakdown()
        for which, fig in self.figures.items():
            base = np.zeros_like(d["amplitude"])
            for name in plots.BRANCH_COLORS:
                top = base + d[which][name]
                fig.set(name, x=d["amplitude"], y1=base, y2=top)
                base = top
            fig.set_marker(self.state.amplitude)
        self._frame()

    def _frame(self):
        update_or_keep("TeachingView kept its last frame", self._draw_frame)

    def _draw_frame(self):
        x = np.geomspace(*self.state.amplitude_bounds, self.FRAMES)[self.player.value]
        data = self.state.hysteresis_loop(amplitude=x)
        xn = data["displacement"] / np.max(np.abs(data["displacement"]))
        peak = np.max(np.abs(data["force"]))
        self.loop.set("total", x=xn, y=data["force"] / peak)
        for name in plots.BRANCH_COLORS:
            self.loop.set(name, x=xn, y=data[f"force_{name}"] / peak)
        self.frame_label.object = (f'<span class="frame-point">Loop shape at <b>{x:.3g} '
                                   f"{self.state.amplitude_unit}</b>, {self.state.frequency_hz:.3g} Hz</span>")

    def __panel__(self):
        return pn.Column(
            pn.pane.Markdown(TEACHING_TEXT, sizing_mode="stretch_width"),
            pn.Row(
                pn.Column(*(pn.pane.Bokeh(f.fig, sizing_mode="stretch_width", height=300)
                            for f in self.figures.values()), sizing_mode="stretch_width"),
                pn.Column(self.player, self.frame_label,
                          pn.pane.Bokeh(self.loop.fig, sizing_mode="stretch_width", height=420),
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


def pct(value: float) -> str:
    """A signed percentage to 2 decimals, without a "-0.00" from round-off."""
    return f"{0.0 if abs(value) < 0.005 else value:+.2f} %"


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
            f"| \\|K\\| ({unit}) | {m_now:.4g} | {m_ref:.4g} | {pct(m_d)} |\n"
            f"| loss factor | {e_now:.4f} | {e_ref:.4f} | {pct(e_d)} |\n\n"
            f"Largest difference over the frequency sweep: \\|K\\| {pct(c['largest_over_frequency']['magnitude'])}, "
            f"loss factor {pct(c['largest_over_frequency']['loss_factor'])}; over the amplitude sweep: "
            f"\\|K\\| {pct(c['largest_over_amplitude']['magnitude'])}, loss factor {pct(c['largest_over_amplitude']['loss_factor'])}."
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
    """One line above the tabs: the design's name, or what is wrong with the input. A pane whose
    text changes in place (no re-layout)."""

    def render(errors, design):
        if errors:
            fields = ", ".join(state.param[n].label for n in errors if n in state.param)
            return (
                '<div class="input-errors" style="background:#fff3cd;border:1px solid #ffe69c;'
                'padding:8px 12px;border-radius:6px;color:#664d03">'
                f"Some inputs are not valid ({fields}): see the messages beside them. "
                "The plots show the last valid design.</div>"
            )
        effects = ", ".join(design.effect_parameters) if design.effects else ""
        name = design.name or "Custom design"
        text = f"<b>{name}</b>, {design.mode}" + (f"; effects: {effects}" if effects else "")
        structural = [e for e in design.effect_parameters if e in STRUCTURAL_EFFECTS]
        if structural:
            text += (f" ({', '.join(structural)} act on the stiffness plots; the loop, slices and "
                     "branches show the material model)")
        return text

    return pn.pane.HTML(pn.bind(render, state.param.errors, state.param.design),
                        sizing_mode="stretch_width", margin=(4, 10))


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
