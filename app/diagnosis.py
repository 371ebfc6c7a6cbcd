"""The "Find the missing effect" tab: a step-by-step walk through the discrepancy workflow
(:mod:`core.diagnose`). Thin: :class:`~app.diagnosis_state.DiagnosisState` does the work."""

from __future__ import annotations

import asyncio
import io
import logging

import numpy as np
import panel as pn
from bokeh.models import FactorRange, LinearColorMapper, Span
from bokeh.palettes import RdBu11
from bokeh.plotting import figure

from core.diagnose import BIC_THRESHOLD
from core.effects import EFFECTS
from core.material import ConvergenceError

from . import plots
from .diagnosis_state import DiagnosisState
from .figures import Axis, Figure
from .state import AMPLITUDE_DISPLAY, STIFFNESS_DISPLAY
from .views import update_or_keep

log = logging.getLogger("bushing.app")

INTRO = """
**Where do model and measurement disagree, and what is missing?** Load measured dynamic stiffness
(or a *mystery* data set with an effect hidden in it), choose the branches of the starting model,
and run the diagnosis. It fits the baseline to the data (the geometry of the current design is
taken as known), says where the misfit is, then fits every effect of the library as an extension,
names the one the data support (by the Bayesian information criterion, with a threshold that does
not add effects to fit noise, and only if it explains most of the misfit), adds it, refits, and
repeats until what is left is noise, or says what remains unexplained.
"""

PROGRESS_POLL_S = 0.15


def _effect_card(eid: str) -> str:
    e = EFFECTS[eid]
    return f"**{e.title}** (`{eid}`). {e.physics} *Signature in data:* {e.signature}"


class DiagnosisView(pn.viewable.Viewer):
    """Data → baseline → diagnosis → the final model in the explorer."""

    def __init__(self, state: DiagnosisState, **params):
        super().__init__(**params)
        self.state = state
        explorer = state.explorer
        self.file = pn.widgets.FileInput(accept=".csv,text/csv", sizing_mode="stretch_width",
                                         description="Measured dynamic stiffness: frequency_hz, amplitude, "
                                         "magnitude, loss_factor (or stiffness_real, stiffness_imag), SI.")
        self.file.param.watch(self._on_file, "value")
        self.use_measured = pn.widgets.Button(label="Use the data of “Measured data and fit”", color="light")
        self.use_measured.on_click(lambda _e: state.use_measured())
        self.mystery = pn.widgets.Button(label="Load a mystery data set (demo)", color="light",
                                         description="Synthetic data with an effect hidden in it (or none); "
                                         "its bushing goes into the explorer. The truth is shown after the diagnosis.")
        self.mystery.on_click(lambda _e: state.load_mystery())
        self.baseline = pn.widgets.CheckButtonGroup.from_param(state.param.baseline, color="primary",
                                                               variant="outline")
        self.run = pn.widgets.Button(label="Diagnose", color="primary",
                                     description="Fit the baseline and every candidate effect; name what is missing.")
        self.run.on_click(self._run)
        self.progress = pn.indicators.Progress(value=0, max=100, visible=False, sizing_mode="stretch_width",
                                               bar_color="primary")
        self.progress_text = pn.pane.HTML("", sizing_mode="stretch_width")
        self.message = pn.pane.HTML("", sizing_mode="stretch_width")
        self.source = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.report = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.use = pn.widgets.Button(label="Use the final model in the explorer", color="success", disabled=True)
        self.use.on_click(lambda _e: state.use_final())
        self.reveal = pn.widgets.Button(label="Reveal the truth", color="warning", visible=False)
        self.reveal.on_click(lambda _e: setattr(state, "revealed", True))
        self.truth = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.curve_key = pn.pane.HTML("", sizing_mode="stretch_width")
        self.download_report = pn.widgets.FileDownload(
            callback=lambda: io.StringIO(state.report_json()), filename="bushing-diagnosis.json",
            label="Report (JSON)", disabled=True)
        self.download_predictions = pn.widgets.FileDownload(
            callback=lambda: io.StringIO(state.predictions_csv()), filename="bushing-predictions.csv",
            label="Predictions (CSV)", disabled=True)
        self._build_figures(explorer.design.mode)
        self._results = pn.Column(
            "### 3. What the diagnosis found",
            self.report,
            pn.Row(pn.pane.Bokeh(self.gap_fig, sizing_mode="stretch_width"), sizing_mode="stretch_width"),
            "**Data (points) against the baseline (dashed) and the final model (solid)**",
            self.curve_key,
            pn.Row(*(pn.pane.Bokeh(self.curve_figs[q].fig, sizing_mode="stretch_width") for q in ("magnitude", "loss")),
                   sizing_mode="stretch_width"),
            "**Misfit over the (frequency, amplitude) plane**, model − data: the baseline above, the final "
            "model below, on the same colour scale",
            pn.GridBox(*(pn.pane.Bokeh(self.maps[(w, q)].fig, sizing_mode="stretch_width")
                         for w in ("baseline", "final") for q in ("magnitude", "loss")),
                       ncols=2, sizing_mode="stretch_width"),
            "### 4. Take it further",
            pn.Row(self.use, self.reveal, self.download_report, self.download_predictions),
            self.truth,
            visible=False, sizing_mode="stretch_width",
        )
        state.param.watch(self._refresh, ["data", "source", "message", "result", "running", "mystery", "revealed"])
        state.param.watch(self._on_progress, ["progress", "progress_message"])
        explorer.param.watch(self._on_mode, "design")
        self._refresh()

    # ---- figures -------------------------------------------------------------------------------

    def _build_figures(self, mode: str):
        self._mode = mode
        self.gap_fig = figure(title="Gap (relative RMS misfit of complex stiffness) after each step",
                              x_range=FactorRange(factors=["baseline"]), height=230, sizing_mode="stretch_width",
                              tools="save", toolbar_location="right")
        self.gap_fig.toolbar.logo = None
        self.gap_fig.title.text_font_size = "13px"
        self.gap_fig.yaxis.axis_label = "gap"
        self.gap_fig.y_range.start = 0
        self.gap_source = self.gap_fig.vbar(x="stage", top="gap", width=0.6, color="#3182bd",
                                            source={"stage": [], "gap": []}).data_source
        self.noise_line = Span(location=0, dimension="width", line_color="#d62728", line_dash="dashed",
                               line_width=2, visible=False)
        self.gap_fig.add_layout(self.noise_line)
        freq = Axis("frequency_hz", "Frequency", "Hz")
        amp_unit = AMPLITUDE_DISPLAY[mode][0]
        k_unit = STIFFNESS_DISPLAY[mode][0]
        self.curve_figs = {}
        for quantity, y in (("magnitude", Axis("magnitude", "|K|", k_unit)), ("loss", Axis("loss_factor", "Loss factor"))):
            fig = Figure(f"{y.label}: data, baseline and final model", freq, y, legend=None, height=280,
                         png=f"bushing-diagnosis-{quantity}")
            fig.lines("baseline", [], plots.SWEEP_PALETTES["amplitude"], line_dash="dashed", line_width=1.5)
            fig.lines("final", [], plots.SWEEP_PALETTES["amplitude"], line_width=2)
            fig.coloured_points("data", size=6, alpha=0.8)
            self.curve_figs[quantity] = fig
        self.mappers = {"magnitude": LinearColorMapper(palette=RdBu11[::-1], low=-1, high=1),
                        "loss": LinearColorMapper(palette=RdBu11[::-1], low=-0.01, high=0.01)}
        self.maps = {}
        for which in ("baseline", "final"):
            for quantity, title in (("magnitude", "|K| misfit (%)"), ("loss", "loss-factor misfit")):
                fig = Figure(f"{which.capitalize()}: {title}", freq, Axis("amplitude", "Amplitude", amp_unit),
                             y_log=True, legend=None, height=260, png=f"bushing-misfit-{which}-{quantity}",
                             hover=False)
                fig.mapped_points("misfit", self.mappers[quantity], title, size=11, marker="square")
                self.maps[(which, quantity)] = fig

    def _set_mode(self, mode: str):
        """Axis units follow the mode (of the explorer's design, or of the diagnosed one)."""
        if mode == self._mode:
            return
        self._mode = mode
        for fig in self.maps.values():
            fig.set_axes(fig.x, Axis("amplitude", "Amplitude", AMPLITUDE_DISPLAY[mode][0]))
        magnitude = self.curve_figs["magnitude"]
        magnitude.set_axes(magnitude.x, Axis("magnitude", "|K|", STIFFNESS_DISPLAY[mode][0]))

    def _on_mode(self, event):
        if self.state.result is None:
            self._set_mode(event.new.mode)

    # ---- events --------------------------------------------------------------------------------

    def _on_file(self, event):
        if event.new:
            self.state.load_csv(event.new, self.file.filename or "stiffness file")

    async def _run(self, _event):
        state = self.state
        if state.running:
            return
        shared = [0.0, "starting"]  # written by the worker, read here on the event loop

        def progress(fraction, message):
            shared[:] = [fraction, message]

        state.param.update(running=True, message="", result=None, revealed=False, progress=0.0,
                           progress_message="fitting the baseline")
        task = asyncio.ensure_future(asyncio.to_thread(state.compute, progress))
        try:
            while not task.done():
                await asyncio.wait({task}, timeout=PROGRESS_POLL_S)
                state.param.update(progress=float(np.clip(shared[0], 0, 1)), progress_message=shared[1])
            result = task.result()
        except (ValueError, ConvergenceError) as exc:
            state.message = str(exc)
        except Exception as exc:  # noqa: BLE001 - never a traceback in the page; one line in the log
            log.warning("diagnosis failed: %s: %s", type(exc).__name__, exc)
            state.message = f"The diagnosis failed ({type(exc).__name__}): {exc}"
        else:
            state.result = result
        finally:
            state.running = False

    def _on_progress(self, *_events):
        self.progress.value = round(100 * self.state.progress)
        self.progress_text.object = f"<i>{self.state.progress_message}…</i>" if self.state.running else ""

    # ---- refresh -------------------------------------------------------------------------------

    def _refresh(self, *_events):
        update_or_keep("DiagnosisView kept its last view", self._update)

    def _update(self):
        s = self.state
        self.message.object = (f'<div class="diagnosis-error" style="color:#b03a2e">⚠ {s.message}</div>'
                               if s.message else "")
        if s.data is not None:
            d = s.data
            amps = np.unique(d.amplitude)
            self.source.object = (f"**Data**: {s.source}: {len(d)} points, {d.frequency_hz.min():.3g}–"
                                  f"{d.frequency_hz.max():.3g} Hz, {amps.size} amplitude(s).")
        else:
            self.source.object = "_No data loaded yet._"
        self.run.disabled = s.running or s.data is None
        self.run.loading = s.running
        self.progress.visible = s.running
        self._on_progress()
        r = s.result
        self._results.visible = r is not None
        self.use.disabled = self.download_report.disabled = self.download_predictions.disabled = r is None
        self.reveal.visible = r is not None and s.mystery is not None and not s.revealed
        self.truth.object = s.truth() if (s.revealed and r is not None) else ""
        if r is None:
            self.report.object = ""
            return
        self._set_mode(r.final.design.mode)
        self.report.object = self._report_text(r)
        self._draw(r)

    def _report_text(self, r) -> str:
        noise = f"{r.noise_gap:.4f}" if r.noise_gap is not None else "not estimable"
        branches = ", ".join(r.baseline.model.branches)
        lines = [
            f"**Baseline** ({branches}): gap **{r.baseline.gap:.4f}**; the noise alone gives about {noise}.",
            f"*Where it disagrees:* {r.where_baseline}",
        ]
        for n, step in enumerate(r.steps, 1):
            params = ", ".join(f"{k} = {v:.4g}" for k, v in step.parameters.items()) or "no parameters"
            partner = step.extra.get("found_with")
            together = f" (found together with {partner})" if partner else ""
            lines.append(f"**Step {n}: add {EFFECTS[step.effect].title}**{together}: {params}. Evidence: BIC "
                         f"drop **{step.bic_drop:.1f}** (threshold {BIC_THRESHOLD:g}); gap "
                         f"{step.gap_before:.4f} → **{step.gap_after:.4f}**.")
            lines.append("> " + _effect_card(step.effect))
            others = sorted(((v, k) for k, v in step.candidates.items() if k != step.effect), reverse=True)[:3]
            if others:
                lines.append("Other candidates' BIC drops: " + ", ".join(f"{k} {v:.1f}" for v, k in others) + ".")
        if not r.steps:
            lines.append("**Nothing added**: no effect of the library is supported by the data.")
        if r.unexplained:
            lines.append("**Unexplained**: a misfit above the noise remains that no effect of the library "
                         f"explains: {r.where_remaining}")
        else:
            lines.append(f"**What is left is noise**: final gap {r.final.gap:.4f}.")
        if r.held_out:
            h = r.held_out
            lines.append(f"**On held-out data** ({h['left_out']}, each refitted without it): gap "
                         f"{h['gap_baseline']:.4f} for the baseline, **{h['gap_final']:.4f}** for the final model.")
        return "\n\n".join(lines)

    def _draw(self, r):
        stages = self.state.gap_stages()
        self.gap_fig.x_range.factors = stages["stage"]
        self.gap_source.data = {"stage": stages["stage"], "gap": list(stages["gap"])}
        if stages["noise"] is not None:
            self.noise_line.location = float(stages["noise"])
            self.noise_line.visible = True
        curves = self.state.curves()["groups"]
        palette = plots.SWEEP_PALETTES["amplitude"]
        colours = [palette[i % len(palette)] for i in range(len(curves))]
        unit = AMPLITUDE_DISPLAY[r.final.design.mode][0]
        self.curve_key.object = "Amplitudes: " + " ".join(
            f'<span style="color:{c};font-weight:bold">■ {plots.sweep_label(g["amplitude"], unit)}</span>'
            for g, c in zip(curves, colours))
        for i, quantity in enumerate(("magnitude", "loss")):
            fig = self.curve_figs[quantity]
            for which in ("baseline", "final"):  # through the figure: its ranges take the curves in
                fig.set_lines(which, None, [g[which][i] for g in curves], each_x=[g["frequency_hz"] for g in curves])
            fig.set("data", x=np.concatenate([g["frequency_hz"] for g in curves]),
                    y=np.concatenate([g["data"][i] for g in curves]),
                    color=[c for g, c in zip(curves, colours) for _ in g["frequency_hz"]])
        base = self.state.misfit("baseline")
        final = self.state.misfit("final")
        for quantity, column in (("magnitude", "magnitude_pct"), ("loss", "loss_factor")):
            top = float(np.max(np.abs(base[column]))) or 1.0
            self.mappers[quantity].update(low=-top, high=top)
            for which, m in (("baseline", base), ("final", final)):
                self.maps[(which, quantity)].set("misfit", x=m["frequency_hz"], y=m["amplitude"], value=m[column])

    def __panel__(self):
        return pn.Column(
            pn.pane.Markdown(INTRO, sizing_mode="stretch_width"),
            "### 1. Data",
            pn.Row(pn.Column("**Stiffness CSV**", self.file, sizing_mode="stretch_width"),
                   pn.Column(self.use_measured, self.mystery), sizing_mode="stretch_width"),
            self.source,
            self.message,
            "### 2. Baseline and diagnosis",
            pn.Row(self.baseline, self.run),
            self.progress,
            self.progress_text,
            self._results,
            sizing_mode="stretch_width",
        )
