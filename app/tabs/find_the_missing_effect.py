"""The "Find the missing effect" tab: a step-by-step walk through the discrepancy workflow
(:mod:`core.identify.diagnose`). Thin: :class:`~app.diagnosis_state.DiagnosisState` does the work."""

from __future__ import annotations

import io
import logging
from functools import partial

import numpy as np
import panel as pn

from core.card import CARD_MODES
from core.effects import EFFECTS, effect_title
from core.identify.diagnose import BIC_THRESHOLD
from core.material import ConvergenceError
from core.numbers import format_number, format_signed, format_value

from ..diagnosis_state import DiagnosisState
from ..inputs import tip
from ..live import LivePlot, one_change, update_or_keep
from ..plotting.find_the_missing_effect import diagnosis_overlays, pending_overlays
from ..plotting.style import amplitude_key
from ..shapes import shape_pane
from ..units import amplitude_unit
from ..uploads import csv_dropper, on_upload, verdict_html
from ..work import PageClosed, cancel, claim, in_thread, page_open, start_ahead

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



def _effect_card(eid: str) -> str:
    e = EFFECTS[eid]
    return f"**{e.title}** (`{eid}`). {e.physics} *Signature in data:* {e.signature}"


PLOT_GROUPS = ("gap", "curves", "maps")  # the report's plots, in the order the page shows them
PLOT_COLUMNS = {"gap": 1, "curves": 2, "maps": 2}
PLOT_COUNTS = {"gap": 1, "curves": 2, "maps": 4}  # plots per group
# the groups in a tab of the report not shown first: a click on *Diagnose* before they were made
# ready for the data makes them after the report is on the page, not while the work runs
# (measured with benchmarks/diagnose_browser.py: the four maps made meanwhile held a click at
# once 4.10 s against 2.55 s without them)
LATER_GROUPS = ("maps",)
REPORT_TABS = ("Data and models", "Where they disagree: misfit maps")
# from a report's message to the first of its later plots put in the page: the browser lays out
# and paints the report first (0.2-0.6 s, diagnose_browser.py). A plot sent sooner was handled
# before the report's frame: that frame came 0.58 s after its message instead of 0.21 s. Opening
# the tab puts them there at once.
LATER_AFTER_MS = 1000
# the plots made ready one at a time, in the page's order: (group, index in it)
PREPARE_STEPS = tuple((name, i) for name in PLOT_GROUPS for i in range(PLOT_COUNTS[name]))
# between two plots made ready (a served page): the event loop reads the page's messages
# meanwhile, so that a click on *Diagnose* waits for the plot being built, not for every plot
# (a next-tick chain let them all run before the click's message was read: 1.4 s; a group at a
# time, the click waited up to 0.9 s for the two curves)
PREPARE_GAP_MS = 30
PROGRESS_HEIGHT = 44  # px: the progress' box, beside the Diagnose button


class DiagnosisView(pn.viewable.Viewer):
    """Data → baseline → diagnosis → the final model in the explorer."""

    def __init__(self, state: DiagnosisState, **params):
        super().__init__(**params)
        self.state = state
        self.file = csv_dropper()
        on_upload(self.file, state.load_csv)
        self.use_measured = pn.widgets.Button(label="Use the data of “Measured data and fit”", color="light")
        self.use_measured.on_click(lambda _e: state.use_measured())
        self.mystery = pn.widgets.Button(label="Load a mystery data set (demo)", color="light",
                                         description=tip("Synthetic data with an effect hidden in it (or none); "
                                         "its bushing goes into the explorer. The truth is shown after the diagnosis.", "bottom_center"))
        self.mystery.on_click(lambda _e: state.load_mystery())
        # the descriptions above the choice of branches and below the button: each of the row's
        # controls visible while the pointer rests on the other
        self.baseline = pn.widgets.CheckButtonGroup.from_param(state.param.baseline, color="primary", variant="outline",
                                                               description=tip(state.param.baseline.doc, "top_right", 300))
        self.run = pn.widgets.Button(label="Diagnose", color="primary",
                                     description=tip("Fit the baseline and every candidate effect; name what is missing.",
                                                     "bottom_center"))
        self.run.on_click(self._click)
        # the progress (a bar and the step) in the text of one pane of a fixed height beside the
        # button: a widget shown and hidden, a button's state changed or the page's height changed
        # lays the whole page out again in the browser (30–100 ms each, Chromium's profiler), at
        # the click and again with the report; a text in a box of its own size does not
        self.progress_text = pn.pane.HTML("", sizing_mode="stretch_width", height=PROGRESS_HEIGHT,
                                          styles={"overflow": "hidden"})
        self.message = pn.pane.HTML("", sizing_mode="stretch_width")
        self.source = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.report = pn.pane.Markdown("", sizing_mode="stretch_width")
        # the report's buttons are shown with the report only (in _results): never disabled
        self.use = pn.widgets.Button(label="Use the final model in the explorer", color="success")
        self.use.on_click(lambda _e: state.use_final())
        self.reveal = pn.widgets.Button(label="Reveal the truth", color="warning", visible=False)
        self.reveal.on_click(lambda _e: setattr(state, "revealed", True))
        self.truth = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.curve_key = pn.pane.HTML("", sizing_mode="stretch_width")
        self.download_report = pn.widgets.FileDownload(
            callback=lambda: io.StringIO(state.report_json()), filename="bushing-diagnosis.json",
            label="Report (JSON)")
        self.download_predictions = pn.widgets.FileDownload(
            callback=lambda: io.StringIO(state.predictions_csv()), filename="bushing-predictions.csv",
            label="Predictions (CSV)")
        self.live: dict[str, LivePlot] = {}  # "gap", "curves", "maps": built with the first data
        self._prepared = 0  # how many data sets the plots were made ready for: a newer one stops an older
        self._ready: set[tuple[str, int]] = set()  # the plots made ready for the loaded data (PREPARE_STEPS)
        self._overlays: dict | None = None  # what they were made with (_pending)
        self._shown: dict[str, dict] = {}  # the overlays each group's LivePlot was last given
        self._ahead = None  # the diagnosis of the loaded data started ahead of the click (_on_data)
        # a place in the page for each plot, filled when the plot is first made (the grid never changes)
        self._slots = {name: [pn.Column(sizing_mode="stretch_width") for _ in range(PLOT_COUNTS[name])]
                       for name in PLOT_GROUPS}
        self._plot_holders = {name: pn.GridBox(*self._slots[name], ncols=PLOT_COLUMNS[name], sizing_mode="stretch_width")
                              for name in PLOT_GROUPS}
        # the curves and the maps in two tabs of the report: the maps' tab is laid out and painted
        # only when opened (its plots are made while it is hidden)
        self.report_tabs = pn.Tabs(
            (REPORT_TABS[0], pn.Column(
                "**Data (points) against the baseline (dashed) and the final model (solid)**",
                self.curve_key, self._plot_holders["curves"], sizing_mode="stretch_width")),
            (REPORT_TABS[1], pn.Column(
                "**Misfit over the (frequency, amplitude) plane**, model − data: the baseline above, the "
                "final model below, on the same colour scale", self._plot_holders["maps"],
                sizing_mode="stretch_width")),
            sizing_mode="stretch_width")
        self.report_tabs.param.watch(self._on_tab, "active")
        self._results = pn.Column(
            "### 3. What the diagnosis found",
            self.report,
            self._plot_holders["gap"],
            self.report_tabs,
            "### 4. Take it further",
            pn.Row(self.use, self.reveal, self.download_report, self.download_predictions),
            self.truth,
            visible=False, sizing_mode="stretch_width",
        )
        state.param.watch(self._refresh, ["data", "source", "message", "note", "result", "running", "mystery", "revealed"])
        state.param.watch(self._on_progress, ["progress", "progress_message"])
        state.param.watch(self._on_data, "data")
        self._refresh()

    # ---- events --------------------------------------------------------------------------------

    def _click(self, _event):
        """A click on *Diagnose*: its progress set as the click is handled (on a served page it is
        written then, at once, before anything else is done), then the work (:meth:`_diagnose`).
        A click while it runs is ignored."""
        if self._begin():
            pn.state.execute(self._diagnose)

    async def _run(self, _event=None):
        """:meth:`_click`, the work awaited (scripts, tests)."""
        if self._begin():
            await self._diagnose()

    def _begin(self) -> bool:
        """The progress set for a diagnosis; False if one runs already."""
        if self.state.running:
            return False
        self.state.param.update(running=True, message="", result=None, revealed=False, progress=0.0,
                                progress_message="fitting the baseline")
        return True

    async def _diagnose(self):
        """The diagnosis in a worker process (a thread in an unserved app), its steps shown as they
        come (:func:`app.work.in_thread`); the report and its plots replace the progress in one
        push. The plots of the report's first tab not yet made ready for the data (a click as soon
        as they are shown) are made on the server while the work runs, one at a time, the work
        started first: measured with ``benchmarks/diagnose_browser.py``, making them before the
        work (5d78637) added their 0.9 s of the server's CPU to the wait. Those of
        :data:`LATER_GROUPS` are made after the report is shown (:meth:`_plots`). A page closed
        meanwhile gets nothing more."""
        state, ahead, self._ahead = self.state, self._ahead, None
        unready = [partial(self._prepare, *step) for step in PREPARE_STEPS
                   if step not in self._ready and step[0] not in LATER_GROUPS]
        try:  # in a worker process when the server has them (app.work.use_processes)
            work = claim(ahead, state.task())  # the diagnosis started with the data, if it is this one
            result = await in_thread(work, self._show_progress, pn.state.curdoc, meanwhile=unready)
        except PageClosed:
            return  # nothing is written to a closed page's document, not even "running" ended
        except (ValueError, ConvergenceError) as exc:
            with one_change():
                state.param.update(message=str(exc), running=False)
        except Exception as exc:  # noqa: BLE001 - never a traceback in the page; one line in the log
            log.warning("diagnosis failed: %s: %s", type(exc).__name__, exc)
            with one_change():
                state.param.update(message=f"The diagnosis failed ({type(exc).__name__}): {exc}", running=False)
        else:
            with one_change():
                state.param.update(result=result, running=False, progress=1.0)

    def _show_progress(self, fraction: float, message: str):
        self.state.param.update(progress=fraction, progress_message=message)

    def _on_progress(self, *_events):
        s = self.state
        self.progress_text.object = (f'<progress class="diagnosis-bar" max="100" value="{round(100 * s.progress)}" '
                                     f'style="width: 100%; height: 0.7em; margin: 0"></progress><br>'
                                     f'<i class="diagnosis-progress" style="font-size: 0.9em">{s.progress_message}…</i>'
                                     if s.running else "")

    def _on_data(self, *_events):
        """New data: the report's plots are made ready for them once the data are on the page
        (:meth:`_prepare`; on a served page the data's message goes first, then one plot every
        :data:`PREPARE_GAP_MS`, so that a click on *Diagnose* waits for one plot at most; the
        plots left are made while the diagnosis runs: :meth:`_diagnose`).

        The diagnosis of the new data starts at once in an idle worker process, if the server has
        one (:func:`app.work.start_ahead`): the click takes it over if nothing it depends on
        changed meanwhile (the design, the baseline), else starts its own.

        Measured and left (2026-12-06): the plots made when the tab opens instead, in one shape
        for any data, made a click at once faster (2.43 s against 3.05 s) but the data's line
        slower (0.48-0.80 s against 0.17 s with the file handed over 1-4 s after the tab shows:
        the browser handles the plots' messages, in order, before the data's, and lays out a page
        that holds them; README, "Speed")."""
        cancel(self._ahead)
        self._ahead = None
        if self.state.data is not None and not self.state.running:
            try:
                self._ahead = start_ahead(self.state.task())
            except ValueError:
                pass  # the data cannot be diagnosed as they are: the click says why
        self._prepared += 1
        self._ready, self._overlays = set(), None
        generation = self._prepared

        def wanted() -> bool:  # until newer data, or a click (it makes the rest while its work runs: _diagnose)
            return generation == self._prepared and not self.state.running and self.state.result is None

        self._one_at_a_time([partial(self._prepare, *step) for step in PREPARE_STEPS], wanted)

    def _one_at_a_time(self, steps: list, wanted, first_ms: int = 0):
        """``steps`` run in turn while ``wanted()``: on a served page one every
        :data:`PREPARE_GAP_MS` (the first ``first_ms`` from now, or on the event loop's next turn),
        so that the loop reads the page's messages between two of them, and only while the page is
        open; else all at once."""
        doc = pn.state.curdoc
        if doc is None or doc.session_context is None:
            for step in steps:
                if wanted():
                    step()
            return

        def run(i: int):
            if i < len(steps) and wanted() and page_open(doc):
                steps[i]()
                doc.add_timeout_callback(partial(run, i + 1), PREPARE_GAP_MS)

        if first_ms:
            doc.add_timeout_callback(partial(run, 0), first_ms)
        else:
            doc.add_next_tick_callback(partial(run, 0))

    def _prepare(self, name: str, index: int):
        """The plot ``index`` of the group ``name`` of the report's plots made ready for the loaded
        data, once (the group's plots before it too)."""
        if (name, index) in self._ready:
            return
        if self._overlays is None:
            self._overlays = self._pending()
            if self._overlays is None:
                return
        update_or_keep("DiagnosisView prepared no plots", lambda: self._plot(name, self._overlays, index + 1))
        self._ready.update((name, i) for i in range(index + 1))

    def _pending(self) -> dict | None:
        """The report's plots with the shape a diagnosis of the loaded data will give them
        (:func:`app.plotting.find_the_missing_effect.pending_overlays`): the report then writes its
        numbers into them (:meth:`app.live.LivePlot.show`) instead of HoloViews building seven
        plots after the work (measured: ``benchmarks/diagnosis_report_cpu.py``). None without data."""
        s = self.state
        data = None if s.data is None else s.data.of_mode(s.explorer.design.mode)
        if data is None or len(data) == 0:
            return None
        return pending_overlays(data, s.explorer.design.mode)

    def _plots(self, overlays: dict):
        """``overlays`` (as :func:`app.plotting.find_the_missing_effect.report_overlays`) shown in
        the report's plots, built the first time. On a served page, the plots of
        :data:`LATER_GROUPS` not yet in the page are put there after this change has gone to the
        browser, :data:`LATER_AFTER_MS` after it or when their tab is opened, one every
        :data:`PREPARE_GAP_MS` (:meth:`_place_later`): the report's message and its first frame
        wait for none of them. Unserved, all at once."""
        for name in PLOT_GROUPS:
            self._plot(name, overlays, self._placed(name) if name in LATER_GROUPS else None)
        self._place_later(LATER_AFTER_MS if self.report_tabs.active == 0 else 0)

    def _placed(self, name: str) -> int:
        """How many plots of group ``name`` are in the page."""
        return sum(1 for slot in self._slots[name] if slot.objects)

    def _place_later(self, first_ms: int = 0):
        """The plots of :data:`LATER_GROUPS` not yet in the page put there one at a time
        (:meth:`_one_at_a_time`), while a report is shown."""
        steps = [partial(update_or_keep, "DiagnosisView placed no plot", partial(self._place, name, count))
                 for name in LATER_GROUPS for count in range(self._placed(name) + 1, PLOT_COUNTS[name] + 1)]
        if steps:
            self._one_at_a_time(steps, lambda: self.state.result is not None, first_ms)

    def _on_tab(self, event):
        """The maps' tab opened: those of its plots not yet in the page put there from now on."""
        if event.new != 0:
            self._place_later()

    def _plot(self, name: str, overlays: dict, count: int | None = None):
        """The group ``name`` of the report's plots showing ``overlays[name]``, its first ``count``
        plots (all if None) in their places on the page: each built by HoloViews when first put there."""
        live = self.live.get(name)
        if live is None:
            self.live[name] = live = LivePlot(overlays[name])
        elif self._shown.get(name) is not overlays:
            live.show(overlays[name])
        self._shown[name] = overlays
        self._place(name, count)

    def _place(self, name: str, count: int | None = None):
        """The first ``count`` plots (all if None) of group ``name`` in their places on the page."""
        for slot, pane in zip(self._slots[name][:count], self.live[name].panes):
            if not slot.objects:
                slot.objects = [pane]

    # ---- refresh -------------------------------------------------------------------------------

    def _refresh(self, *_events):
        update_or_keep("DiagnosisView kept its last view", self._update)

    def _update(self):
        s = self.state
        self.message.object = verdict_html(s.message, s.note, "diagnosis")
        if s.data is not None:
            d = s.data
            modes = d.modes(s.explorer.design.mode).astype(str)
            counts = {m: np.unique(d.amplitude[modes == m]).size for m in np.unique(modes)}
            per_mode = [f"{m} {int(np.sum(modes == m))} points at {n} amplitude{'s' if n != 1 else ''}"
                        for m, n in counts.items()]
            self.source.object = (f"**Data**: {s.source}: {len(d)} points, {format_number(d.frequency_hz.min(), 'frequency')}–"
                                  f"{format_value(d.frequency_hz.max(), 'Hz', 'frequency')}; {'; '.join(per_mode)}.")
        else:
            self.source.object = "_No data loaded yet._"
        self.run.disabled = s.data is None  # a click while it runs is ignored (_click)
        self._on_progress()
        r = s.result
        self._results.visible = r is not None
        self.reveal.visible = r is not None and s.mystery is not None and not s.revealed
        self.truth.object = s.truth() if (s.revealed and r is not None) else ""
        if r is None:
            self.report.object = ""
            return
        self.report.object = self._report_text(r)
        self._draw(s.shown())

    def _report_text(self, r) -> str:
        noise = f"{r.noise_gap:.4f}" if r.noise_gap is not None else "not estimable"
        branches = ", ".join(r.baseline.model.branches)
        lines = [
            f"**Baseline** ({branches}): gap **{r.baseline.gap:.4f}**; the noise alone gives about {noise}.",
            f"*Where it disagrees:* {r.where_baseline}",
        ]
        for n, step in enumerate(r.steps, 1):
            params = step.parameter_words(r.baseline.model.design.mode)
            partner = step.extra.get("found_with")
            together = f" (found together with {effect_title(partner)})" if partner else ""
            support = step.support_words()
            lines.append(f"**Step {n}: add {EFFECTS[step.effect].title}**{together}"
                         f"{' *' + support + '*' if step.mode else ''}: {params}. Evidence: BIC "
                         f"drop **{step.bic_drop:.1f}** (threshold {BIC_THRESHOLD:g}); gap "
                         f"{step.gap_before:.4f} → **{step.gap_after:.4f}**"
                         + (f"; {support}" if support and not step.mode else "") + ".")
            lines.append("> " + _effect_card(step.effect))
            others = sorted(((v, k) for k, v in step.candidates.items() if k != step.effect), reverse=True)[:3]
            if others:
                lines.append("Other candidates' BIC drops: " + ", ".join(f"{effect_title(k)} {format_signed(v, 1)}"
                                                                         for v, k in others) + ".")
        if not r.steps:
            lines.append("**Nothing added**: no effect of the library is supported by the data.")
        if r.modes:
            joint = ", ".join(f"{m} {g:.4f}" for m, g in r.modes["gap_joint_by_mode"].items())
            alone = ", ".join(f"{m} {g:.4f}" for m, g in r.modes["gap_alone_by_mode"].items())
            if r.modes_disagree:
                lines.append(f"**The modes disagree**: one material does not describe them together. Gap by "
                             f"mode {joint} jointly, {alone} with each mode fitted alone (BIC drop "
                             f"{r.modes['bic_drop']:.1f} for a material per mode). Check that every part is of "
                             f"one compound, and each rig's geometry and calibration.")
            else:
                lines.append(f"**The modes agree**: one material describes them all (gap by mode {joint}).")
            lines.append(f"*The plots show the {r.final.design.mode} rows; the report covers every mode.*")
        if r.unexplained:
            lines.append("**Unexplained**: a misfit above the noise remains that no effect of the library "
                         f"explains: {r.where_remaining}")
        else:
            lines.append(f"**What is left is noise**: final gap {r.final.gap:.4f}.")
        for warning in r.final.fit.warnings:
            lines.append(f"⚠ {warning}")
        if r.held_out:
            h = r.held_out
            lines.append(f"**On held-out data** ({h['left_out']}, each refitted without it): gap "
                         f"{h['gap_baseline']:.4f} for the baseline, **{h['gap_final']:.4f}** for the final model.")
        return "\n\n".join(lines)

    def _draw(self, r):
        overlays = diagnosis_overlays(r)
        self.curve_key.object = amplitude_key(overlays["groups"], amplitude_unit(r.final.design.mode))
        self._plots(overlays)

    def __panel__(self):
        return pn.Column(
            pn.pane.Markdown(INTRO, sizing_mode="stretch_width"),
            "### 1. Data",
            pn.Row(pn.Column("**Stiffness CSV**", self.file, sizing_mode="stretch_width"),
                   pn.Column(self.use_measured, self.mystery), sizing_mode="stretch_width"),
            self.source,
            shape_pane(self.state.explorer, CARD_MODES),
            self.message,
            "### 2. Baseline and diagnosis",
            pn.Row(self.baseline, self.run, self.progress_text, sizing_mode="stretch_width"),
            self._results,
            sizing_mode="stretch_width",
        )
