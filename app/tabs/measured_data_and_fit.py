"""The measured-data tab: load stiffness and loop files, see them over the model, fit the five
material parameters, take the fitted design into the explorer. Thin: the state (the data) and the fit state
(:mod:`app.fit_state`) do the work."""

from __future__ import annotations

import io
import logging

import numpy as np
import panel as pn
import param

from core import PAPER_B
from core.numbers import format_number, format_signed, format_value
from core.parameters import BY_NAME, MATERIAL
from core.synthetic import paper_b_example

from .. import curves, units
from ..curves import padded
from ..fit_state import FIT_DEPENDS, FitState
from ..inputs import tip
from ..live import LivePlot, one_change, update_or_keep
from ..plotting.measured_data_and_fit import data_overlays, prediction_overlay, residual_overlays
from ..plotting.style import amplitude_key, ranged
from ..shapes import shape_pane
from ..state import ExplorerState, measured_amplitudes
from ..uploads import csv_dropper, on_files, on_upload, verdict_html
from ..views import PlotView
from ..work import PageClosed, in_thread, page_open

RESIDUALS = (("magnitude", "frequency"), ("loss", "frequency"), ("magnitude", "amplitude"), ("loss", "amplitude"))
DATA = ("magnitude", "loss")  # the data-over-model plots, drawn before the residuals

# what the tab shows until data are loaded (instead of empty plots)
HOW_TO = """**No measured data loaded yet.** To fit this bushing's material:

1. Drop a **stiffness CSV** above: one row per point, `frequency_hz,amplitude,magnitude,loss_factor` (Hz, m or rad,
   N/m or N·m/rad; or `stiffness_real,stiffness_imag`, an optional `mode` column; docs/files.md, About tab).
2. Optionally a **loop CSV**: `time_s,displacement,force` (s, m or rad, N or N·m).
3. Press **Fit the five material parameters**.

No file at hand? Press *Load the synthetic Paper B example*, or try the files in the repository's `examples/`
folder: `paper_b_stiffness.csv` with `paper_b_loop.csv` (Paper B preset, axial), `table1_torsion_stiffness.csv`
(Table 1 preset, torsion). A file whose numbers are in other units (mm, kN/mm, another direction) is refused with
the likely cause."""

log = logging.getLogger("bushing.app")


FITTED = " and ".join([", ".join(BY_NAME[p].symbol for p in MATERIAL[:-1]), BY_NAME[MATERIAL[-1]].symbol])


class MeasuredView(PlotView):
    """Upload, fit and residuals."""

    shows = ("design", "measured", "fit")

    fit = param.ClassSelector(class_=FitState, doc="The session's fit of the measured data.")

    def __init__(self, state: ExplorerState, fit: FitState, **params):
        super().__init__(state, fit=fit, **params)
        self.stiffness_file = csv_dropper(multiple=True)
        self.loop_file = csv_dropper()
        on_files(self.stiffness_file, state.load_measured_files)
        on_upload(self.loop_file, state.load_measured_loop)
        self.example = pn.widgets.Button(label="Load the synthetic Paper B example", color="light")
        self.example.on_click(self._load_example)
        self.clear = pn.widgets.Button(label="Clear the data", color="light")
        self.clear.on_click(lambda _e: state.clear_measured())
        # no description on hover: every side of the button has a control it would hide; the
        # intro says what it does
        self.fit_button = pn.widgets.Button(label="Fit the five material parameters", color="primary")
        self.fit_button.on_click(self._fit)
        # while a fit runs: where it is (issue #27 item 12), replaced by its result in one push
        self.fit_progress = pn.indicators.Progress(value=0, max=100, visible=False, sizing_mode="stretch_width",
                                                   height=12)
        self.fit_progress_text = pn.pane.HTML("", sizing_mode="stretch_width")
        fit.param.watch(self._on_fit_progress, ["running", "progress", "progress_message"])
        self.method = pn.widgets.RadioButtonGroup.from_param(fit.param.fit_method, description=tip(fit.param.fit_method.doc, "top_right", 300))
        self.fit_on = pn.widgets.TextInput.from_param(fit.param.fit_on, description=fit.param.fit_on.doc,
                                                      placeholder="e.g. mode=axial,amplitude=0.1 (amplitudes in mm or rad)", max_length=500,
                                                      sizing_mode="stretch_width")
        self.sweep = pn.widgets.Select(label="Sweep amplitude (two-step)", options={}, sizing_mode="stretch_width",
                                       description=fit.param.sweep_amplitude.doc)
        self.sweep.param.watch(lambda e: setattr(fit, "sweep_amplitude", e.new), "value")
        self.use = pn.widgets.Button(label="Use the fitted design in the explorer", color="success",
                                     disabled=True)
        self.use.on_click(lambda _e: fit.use_fit())
        self.download = pn.widgets.FileDownload(callback=self._fitted_json, filename="bushing-fitted.json",
                                                label="Fitted design file (JSON)", disabled=True,
                                                sizing_mode="stretch_width")
        self.message = pn.pane.HTML("", sizing_mode="stretch_width")
        self.how_to = pn.pane.Markdown(HOW_TO, sizing_mode="stretch_width", css_classes=["measured-how-to"])
        self.summary = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.results = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.prediction = pn.pane.HoloViews(None, sizing_mode="stretch_width", linked_axes=False)
        # shown and hidden through its box: Panel 1.9 passes a HoloViews pane's own layout changes
        # (``visible``) on to the Bokeh pane inside it, with its ``design``, which a figure does not
        # take (AttributeError, and the change lost)
        self.prediction_box = pn.Column(self.prediction, visible=False, sizing_mode="stretch_width")
        self.residuals: LivePlot | None = None
        self.curve_key = pn.pane.HTML("", sizing_mode="stretch_width")  # which colour is which amplitude
        self.plots_box: pn.Column | None = None  # the plots, hidden (with the fit's controls) without data
        self._show_message()
        self._show_prediction()
        self.draw()

    @param.depends("state.data_message", "state.data_note", watch=True)
    def _show_message(self):
        """What was wrong with the last file (or fit), if anything."""
        m, note = self.state.data_message, self.state.data_note
        self.message.object = verdict_html(m, note)

    @param.depends(*FIT_DEPENDS, watch=True)
    def _show_prediction(self):
        """A fit on a subset against every measured row: a function of the fit and the data only
        (not of the design shown), so drawn when either changes."""
        data = curves.prediction_misfit(self.fit.fit_result, self.state.measured)
        self.prediction_box.visible = data is not None
        self.prediction.object = None if data is None else prediction_overlay(data)

    def frame(self, quantity: str, against: str):
        """What a residual plot shows now (``quantity`` "magnitude" or "loss")."""
        return self.residuals.current[len(DATA) + RESIDUALS.index((quantity, against))]

    def _load_example(self, _event):
        data, loop = paper_b_example(PAPER_B)
        self.state.load_measured(data.to_csv(), "paper_b_stiffness.csv")
        self.state.load_measured_loop(loop.to_csv(), "paper_b_loop.csv")

    async def _fit(self, _event):
        """The fit in a worker thread (the server stays responsive), where it is shown as it goes
        (:func:`app.work.in_thread`); its result (or why there is none) replaces the progress in
        one push. A page closed meanwhile gets nothing more; data changed meanwhile get no fit
        of the old data."""
        fit, s = self.fit, self.state
        if fit.running:
            return
        data = (s.measured, s.measured_loop)
        fit.param.update(running=True, progress=0.0, progress_message="starting")
        try:
            outcome = await in_thread(fit.try_fit, self._show_fit_progress, pn.state.curdoc)
        except PageClosed:
            return  # nothing is written to a closed page's document, not even "running" ended
        except Exception as exc:  # noqa: BLE001 - never a traceback in the page; one line in the log
            log.warning("fit failed: %s: %s", type(exc).__name__, exc)
            outcome = f"The fit failed ({type(exc).__name__}): {exc}"
        if any(a is not b for a, b in zip((s.measured, s.measured_loop), data)) and not isinstance(outcome, str):
            outcome = "The data changed during the fit: press Fit again to fit the data loaded now"
        with one_change():
            fit.param.update(running=False, progress=1.0)
            fit.store_fit(outcome)

    def _show_fit_progress(self, fraction: float, message: str):
        self.fit.param.update(progress=fraction, progress_message=message)

    def _on_fit_progress(self, *_events):
        """The progress line and the Fit button as the fit's state says: the button disabled
        (and spinning) and the line shown while a fit runs."""
        f = self.fit
        self.fit_progress.visible = f.running
        self.fit_progress.value = round(100 * f.progress)
        self.fit_progress_text.object = (f'<i class="fit-progress">Fitting: {f.progress_message}…</i>'
                                         if f.running else "")
        self.fit_button.loading = f.running
        self.fit_button.disabled = f.running or (self.state.measured is None and self.state.measured_loop is None)

    def _fitted_json(self):
        r = self.fit.fit_result
        return io.StringIO(r.to_json() if r is not None else "")

    def _update(self):
        s = self.state
        mode = s.design.mode
        unit = units.amplitude_unit(mode)
        points = curves.measured_points(s.measured, mode)
        r = self.fit.fit_result
        shown = s.design if r is None else r.design  # after a fit, the residuals are the fitted design's
        residuals = None if s.measured is None else curves.measured_residuals(shown, s.measured)
        groups = curves.measured_groups(s.measured, s.design, None if r is None else r.design)
        lines = []
        if s.measured is not None:
            d = s.measured
            modes = "" if d.mode is None else f" in {', '.join(sorted(set(d.mode)))}"
            if points is None:
                lines.append(f"**Stiffness**: {len(d)} points{modes}; none in the explorer's mode "
                             f"({s.design.mode}): switch the mode to see them. The fit uses every mode.")
            else:
                shown = "" if d.mode is None else f" ({int((d.mode == s.design.mode).sum())} {s.design.mode} shown)"
                lines.append(
                    f"**Stiffness**: {len(d)} points{modes}{shown}, {format_number(d.frequency_hz.min(), 'frequency')}–"
                    f"{format_value(d.frequency_hz.max(), 'Hz', 'frequency')}, amplitudes {format_number(points['amplitude'].min(), 'amplitude')}–"
                    f"{format_value(points['amplitude'].max(), unit, 'amplitude')}; gap of the "
                    f"{'current' if r is None else 'fitted'} design: "
                    f"**{residuals['gap']:.4f}**"
                    + (f" (drawn as {len(points['frequency_hz'])} bin means; fits bin them too)"
                       if len(points["frequency_hz"]) < len(d.of_mode(s.design.mode)) else ""))
        if s.measured_loop is not None:
            f, amp, _ = s.measured_loop.harmonic()
            lines.append(f"**Loop**: {s.measured_loop.time_s.size} samples at {format_value(f, 'Hz', 'frequency')}, amplitude "
                         f"{format_value(units.display_amplitude(amp, mode), unit, 'amplitude')}")
        if lines and r is not None:
            lines.append("The plots below show the **fitted** design (solid) and the start (dashed); the residuals "
                         "are the fitted design's.")
        self.summary.object = "\n\n".join(lines)
        empty = s.measured is None and s.measured_loop is None
        # its words go with the summary; hidden with the plots shown (a change of layout costs the
        # page a third of a second of re-layout, which the summary does not wait for)
        self.how_to.object = HOW_TO if empty else ""
        self.fit_button.disabled = empty or self.fit.running
        if self.plots_box is None:
            self._draw(points, residuals, groups, empty)
        else:  # the text first (one message), the plots in the next: a first upload's new glyphs take the
            # browser seconds to build, and the verdict and summary do not wait for them
            doc = pn.state.curdoc  # a page closed meanwhile gets nothing more (app.work.page_open)
            pn.state.execute(lambda: page_open(doc) and update_or_keep(
                "MeasuredView kept its last plots", lambda: self._draw(points, residuals, groups, empty)),
                schedule=True)
        options = {format_value(units.display_amplitude(a, mode), unit): a for a in measured_amplitudes(s.measured)}
        if options != self.sweep.options:
            self.sweep.options = options
        self.sweep.visible = self.fit.fit_method == "two-step"
        self.use.disabled = self.download.disabled = r is None
        self.results.object = self._results_table(r) if r is not None else ""

    def _draw(self, points, residuals, groups, empty: bool):
        dims = self.dims_for(self.state.design.mode)
        if points is not None:  # plots of the same quantity share the axis: one range (one clone) for both
            ranges = {"residual_magnitude": padded([residuals["magnitude_residual_pct"]]),
                      "residual_loss": padded([residuals["loss_factor_residual"]])}
            for i, quantity in enumerate(("magnitude", "loss_factor")):  # the data and every model in view
                ranges[quantity] = padded([v for g in groups for k in ("data", "start", "fitted") if k in g
                                           for v in (g[k][i],)])
            dims = ranged(dims, ranges)
        data = data_overlays(groups, dims)
        overlays = residual_overlays(points, residuals, dims)
        items = [data[k] for k in DATA] + [overlays[k] for k in RESIDUALS]
        self.residuals = LivePlot.shown(self.residuals, items)
        self.curve_key.object = amplitude_key(groups, units.amplitude_unit(self.state.design.mode))
        if self.plots_box is None:
            self.plots_box = pn.Column(self.curve_key, self.residuals.grid(2), sizing_mode="stretch_width")
        self.plots_box.visible = not empty
        self.how_to.visible = empty

    @staticmethod
    def _results_table(r):
        vague = set(r.undetermined)
        rows = ["| parameter | fitted | ± standard error | 95 % interval (profile) |", "|---|---|---|---|"]
        for p in MATERIAL:
            unit = BY_NAME[p].unit
            value, err = unit.to_display(getattr(r.design.material, p)), unit.to_display(r.standard_errors[p])
            err = "–" if p in vague or not np.isfinite(err) else format_number(err, "error")
            ends = ["not bounded" if e is None else format_number(unit.to_display(e), 3) for e in r.intervals.get(p, ())]
            interval = " – ".join(ends) + (" **not determined**" if p in vague else "") or "–"
            rows.append(f"| {BY_NAME[p].symbol} ({unit.display}) | {format_number(value, 'parameter')} | {err} | {interval} |")
        gap = f"{r.gap:.4f}" if np.isfinite(r.gap) else "–"
        loop = f", loop RMS misfit {r.loop_rms:.4f}" if r.loop_rms is not None else ""
        corr = ["| | " + " | ".join(BY_NAME[p].symbol for p in MATERIAL) + " |",
                "|---" * (len(MATERIAL) + 1) + "|"]
        for a in MATERIAL:
            corr.append(f"| {BY_NAME[a].symbol} | " + " | ".join(
                format_signed(r.correlation[a][b]) for b in MATERIAL) + " |")
        flat = [BY_NAME[p].symbol for p in MATERIAL if not np.isfinite(r.standard_errors[p])]
        if flat:  # the linearised errors cannot be formed along a direction the data do not fix
            corr.append(f"\n– : no linearised standard error or correlation for {', '.join(flat)}: the data fix no "
                        "combination of them to first order (the misfit is flat along one); the profile "
                        "intervals above say what the data bound.")
        warnings = "".join(f"\n\n⚠ {w}" for w in r.warnings)
        by_mode = ("\n\nGap per mode: " + ", ".join(f"{m} **{g:.4f}**" for m, g in r.gap_by_mode.items())
                   if r.gap_by_mode else "")
        prediction = ""
        if r.prediction:
            p = r.prediction
            held = f"; the rows left out are predicted with a gap of **{p['gap_held_out']:.4f}**" if "gap_held_out" in p else ""
            prediction = (f"\n\n**Fitted on {p['fit_on']}** ({p['points_fitted']} points){held}:\n\n"
                          "| mode | amplitude | points | fitted | gap |\n|---|---|---|---|---|\n"
                          + "\n".join(f"| {g['mode']} | {format_value(units.display_amplitude(g['amplitude'], g['mode']), units.amplitude_unit(g['mode']), 'amplitude')} | {g['points']} | "
                                      f"{'yes' if g['fitted'] else 'predicted'} | {g['gap']:.4f} |" for g in p["groups"]))
        return (f"### Fitted ({r.method})\n\nGap (relative RMS misfit of complex stiffness): **{gap}**{loop}; "
                f"{r.points} points, {r.starts} starts.{by_mode}{prediction}{warnings}\n\n" + "\n".join(rows)
                + "\n\n**Correlation between parameters**\n\n" + "\n".join(corr))

    def __panel__(self):
        return pn.Column(
            pn.pane.Markdown(
                "Load measured dynamic stiffness (and, if you have one, a quasi-static loop) as CSV "
                "files (drop a file on its area or browse for it, up to 20 MB; the formats are in the About tab), or the "
                "synthetic example. The points appear over the model in the Explorer tab; the "
                f"residuals (model − measured) are below. **Fit** identifies {FITTED} (a global fit from "
                "several starting points, the current design's first) with standard errors and 95 % intervals, and says which parameters the data cannot determine; "
                "then take the fitted design into the explorer or save it.",
                sizing_mode="stretch_width"),
            pn.Row(pn.Column("**Stiffness CSV** (one or several)", self.stiffness_file, sizing_mode="stretch_width"),
                   pn.Column("**Loop CSV** (optional)", self.loop_file, sizing_mode="stretch_width"),
                   sizing_mode="stretch_width"),
            pn.Row(self.example, self.clear),
            shape_pane(self.state),
            self.message,
            self.how_to,
            self.summary,
            pn.Row(self.method, self.sweep, self.fit_on),
            pn.Row(self.fit_button, self.use),
            self.fit_progress,
            self.fit_progress_text,
            self.download,
            self.results,
            self.prediction_box,
            self.plots_box,
            sizing_mode="stretch_width",
        )
