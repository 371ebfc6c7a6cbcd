"""The "What-ifs" tab: tolerance bands (drawn on the explorer's stiffness plots and the card),
sensitivities at the operating point, and designs found from target stiffnesses."""

from __future__ import annotations

import io

import holoviews as hv
import panel as pn
import param

from core.card import CARD_MODES
from core.parameters import BY_NAME, GEOMETRY, NAMES
from core.whatif.sensitivity import elasticities, sentence
from core.whatif.tolerance import ToleranceError

from .. import curves, units
from ..bands import band_tolerances, banded, tolerance_refusal
from ..fit_state import FitState
from ..inputs import FIELD_ERROR_STYLES, FloatInput, IntInput, field_error_html
from ..live import LivePlot, one_change
from ..plotting.what_ifs import sensitivity_bars
from ..shapes import card_basis, shape_pane
from ..state import ExplorerState
from ..targets_form import TargetsForm
from ..views import PlotView

A, _B, L, MU = (BY_NAME[n] for n in (*GEOMETRY, "shear_modulus"))
# a found design's columns: its geometry and µ (what a search changes), each to its digits
FOUND_COLUMNS = {**{n: ".3f" for n in GEOMETRY}, L.name: ".2f", MU.name: ".4g"}


TOLERANCE_TEXT = """
**Tolerance bands.** Give each parameter's tolerance (± % of its value) and switch the bands on:
every stiffness plot of the Explorer (and the Every direction tab) shows the 5–95 % band of the
operating curve. The band is a Monte Carlo with the stated number of samples and seed, so the
same inputs give the same band. Beside it is the first-order spread (from the derivatives),
which should agree where the tolerances are small. The material may instead come from the last
fit's standard errors and correlations.
"""
SENSITIVITY_TEXT = """
**Sensitivities at the operating point.** Bar length ∂ln|K|/∂ln p: a +1 % change of the parameter
moves |K| by that many per cent. For the loss factor, ∂η/∂ln p: a +1 % change moves η by a
hundredth of it. Both charts list the parameters in the same order; the bars follow the
operating point.
"""
DESIGN_TEXT = """
**Design from targets.** Ask for |K| (and, optionally, a least loss factor and a radial/axial
ratio) at the operating point of the Explorer. Set the limits. The search looks for the designs
nearest the current one that meet every target, or it says why none can. Blank fields are not
targets. The same search runs from the command line (`bushing design TARGETS.json`); download
the targets file to repeat it there.
"""


class WhatIfView(PlotView):
    """Tolerances, sensitivities, targets."""

    shows = ("design", "frequency", "amplitude", "sweep range", "bands")  # the bars, and the bands' status

    fit = param.ClassSelector(class_=FitState, doc="The session's fit (its covariance may make the bands).")

    def __init__(self, state: ExplorerState, fit: FitState, **params):
        self._showing = False
        super().__init__(state, fit=fit, **params)
        self.tolerance_inputs = {
            n: FloatInput(label=f"{BY_NAME[n].label} ± %", value=self._shown_tolerances().get(n, 0.0), start=0.0,
                                     end=89.0, step=0.5, width=170)
            for n in NAMES}
        for name, widget in self.tolerance_inputs.items():
            widget.param.watch(lambda e, n=name: self._set_tolerance(n, e.new), "value")
        # beside each tolerance: why the design cannot take it (app.bands.tolerance_refusal)
        self.tolerance_errors = {n: pn.pane.HTML("", margin=(0, 10, 4, 10), styles=FIELD_ERROR_STYLES,
                                                 sizing_mode="stretch_width") for n in NAMES}
        s = state.param
        # FlexBox, not Row: the controls wrap onto a second line in a narrow window (a Row ran
        # past the window's edge at 1280 px and cut the last checkbox's label)
        self.band_controls = pn.FlexBox(
            pn.widgets.Checkbox.from_param(s.band_on, margin=(28, 10), width=330, css_classes=["band-switch"]),
            pn.widgets.Select.from_param(s.band_distribution, width=120),
            IntInput.from_param(s.band_samples, width=100),
            IntInput.from_param(s.band_seed, width=100),
            pn.widgets.Checkbox.from_param(s.band_from_fit, margin=(28, 10)),
            align_items="flex-start", sizing_mode="stretch_width")
        self.band_status = pn.pane.HTML("", sizing_mode="stretch_width")
        self.sentence = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.bars: LivePlot | None = None
        self.form = TargetsForm(state)
        self.form.param.watch(self._show_search, ["found", "message", "running", "progress_message"])
        self.find = pn.widgets.Button(label="Find designs", color="primary", width=160)
        self.find.on_click(self._run)
        self.searching = pn.pane.HTML("", css_classes=["search-progress"], margin=(0, 10))
        self.solutions = pn.widgets.Select(label="Solution", options={}, width=420, visible=False)
        self.use = pn.widgets.Button(label="Take it into the explorer", color="success", visible=False)
        self.use.on_click(lambda _e: self.form.use_solution(self.solutions.value))
        self.result = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.targets_file = pn.widgets.FileDownload(callback=self._targets_file, filename="bushing-targets.json",
                                                    label="Targets file (JSON)", width=200)
        self.draw()

    # ---- tolerances ------------------------------------------------------------------------------

    def _shown_tolerances(self) -> dict[str, float]:
        try:
            return self.state.tolerance_pct
        except ToleranceError:  # a link's text that is no list of tolerances: its message says so
            return {}

    def _set_tolerance(self, name: str, value):
        if self._showing:
            return
        values = {n: w.value or 0.0 for n, w in self.tolerance_inputs.items()}
        values[name] = float(value or 0.0)
        self.state.tolerance_pct = values

    @param.depends("state.tolerance_text", watch=True)
    def _show_tolerances(self):
        """A link (or the back button) sets the tolerances: the inputs show them."""
        values = self._shown_tolerances()
        self._showing = True  # the inputs follow the state here, not the other way round
        try:
            for name, widget in self.tolerance_inputs.items():
                widget.value = values.get(name, 0.0)
        finally:
            self._showing = False

    def _show_band(self):
        """The bands' status, from the values (:func:`app.bands.band_tolerances`; the
        explorer's and the card's bands, cached, say why a band cannot be computed)."""
        s = self.state
        fit = self.fit.fit_result
        refused, message = tolerance_refusal(self._shown_tolerances(), s.design)
        for name, pane in self.tolerance_errors.items():
            pane.object = field_error_html(f"tolerance:{name}", message if name in refused else "")
        tolerances = band_tolerances(**s.band_inputs(), fit_result=fit)
        design, f, x = s.design, s.frequency_hz, s.amplitude
        _, reason = banded(tolerances, lambda tol: curves.operating_bands(design, f, x, s.freq_range, tol))
        if not reason:
            try:
                _, reason = banded(tolerances, lambda tol: curves.card_bands(card_basis(design), f, tol))
            except ValueError:  # no card for this design: its tab says so
                pass
        if s.band_on and reason:
            if refused and reason == message:  # said beside the field
                reason = "a tolerance the design cannot take (said beside it, above)"
            self.band_status.object = f'<span style="color:#8a5300">No band: {reason}</span>'
        elif s.band_on:
            self.band_status.object = "Bands are drawn on the Explorer's stiffness plots and in Every direction."
        else:
            self.band_status.object = ""
        if s.band_from_fit and fit is None:
            self.band_status.object = ('<span style="color:#8a5300">No fit yet: fit measured data first '
                                       "(Measured data and fit).</span>")

    # ---- sensitivities ---------------------------------------------------------------------------


    def sensitivities(self) -> dict:
        s = self.state
        return elasticities(s.design, s.frequency_hz, float(units.to_si_amplitude(s.amplitude, s.design.mode)))

    def _update(self):
        self._show_band()
        values = self.sensitivities()
        items = []
        for quantity, label, color in (("magnitude", "∂ln|K| / ∂ln p", "#1f5f8b"),
                                       ("loss_factor", "∂η / ∂ln p", "#2ca02c")):
            # both charts in the one parameter table's order: a parameter sits at one place in both
            bars = hv.Bars([(BY_NAME[n].symbol, values[n][quantity]) for n in NAMES if n in values], kdims=[hv.Dimension("parameter", label="Parameter")],
                           vdims=[hv.Dimension(f"sensitivity_{quantity}", label=label)])
            title = "|K|: % per +1 % of the parameter" if quantity == "magnitude" else \
                "Loss factor: change per unit ln p"
            items.append(sensitivity_bars(bars, title, color, f"bushing-sensitivity-{quantity.replace('_', '-')}"))
        self.bars = LivePlot.shown(self.bars, items)
        s = self.state
        self.sentence.object = (f"At {s.frequency_hz:.3g} Hz and {s.amplitude:.3g} {units.amplitude_unit(s.design.mode)}: "
                                f"{sentence(values)}")

    # ---- targets ---------------------------------------------------------------------------------

    def _targets_file(self):
        return io.StringIO(self.form.targets_text())

    async def _run(self, _event):
        """The search in a worker thread (:meth:`app.targets_form.TargetsForm.search`); its
        progress beside the button; the result replaces it in one push (:meth:`_show_search`)."""
        await self.form.search(pn.state.curdoc)

    def _show_search(self, *events):
        """The search's state: the button busy and where the search is while it runs, then its
        result, all in one message to the page."""
        form = self.form
        with one_change():
            self.find.loading = form.running
            self.searching.object = (f"<i>Searching: {form.progress_message}…</i>"
                                     if form.running and form.progress_message else "")
            if any(e.name in ("found", "message") for e in events):
                self._show_found()

    def _show_found(self, *_events):
        found = self.form.found
        if found is None:
            message = self.form.message
            self.result.object = f"**Cannot search**: {message}" if message else ""
            self.solutions.visible = self.use.visible = False
            return
        mode = found.problem.start.mode
        lines = [f"**{found.statement}** ({found.seconds:.2f} s)"]
        rows = self.form.rows()
        if rows:
            targets = found.problem.targets
            header = [f"{BY_NAME[n].symbol} ({BY_NAME[n].unit.display})" for n in FOUND_COLUMNS]
            lines += ["", "| | " + " | ".join(header + [f"target {j}" for j in range(1, len(targets) + 1)]) + " |",
                      "|---" * (1 + len(header) + len(targets)) + "|"]
            for i, sol in enumerate(rows, 1):
                got = " | ".join(f"{units.display_stiffness(v, mode):.4g} {units.stiffness_unit(mode)}"
                                 if t.quantity == "magnitude" and not t.is_ratio else f"{v:.4g}"
                                 for t, v in zip(targets, sol.achieved))
                name = f"{i}" if found.solutions else "closest"
                lines.append(f"| {name} | {found_values(sol.design, ' | ')} | {got} |")
            lines += [""] + [f"Target {j}: {t.describe()} (SI units)." for j, t in enumerate(targets, 1)]
        self.result.object = "\n".join(lines)
        self.solutions.options = {f"{i}: {found_values(s.design, ', ', GEOMETRY, symbols=True)} {A.unit.display}": i - 1
                                  for i, s in enumerate(rows, 1)}
        self.solutions.visible = self.use.visible = bool(rows)
        self.use.label = "Take it into the explorer" if found.solutions else "Take the closest into the explorer"

    def __panel__(self):
        w = FloatInput.from_param
        tol_grid = pn.GridBox(*(pn.Column(widget, self.tolerance_errors[n], margin=0, sizing_mode="stretch_width")
                                for n, widget in self.tolerance_inputs.items()), ncols=4, sizing_mode="stretch_width")
        form = pn.Column(
            pn.FlexBox(w(self.form.param.target_magnitude, width=150), w(self.form.param.target_tolerance_pct, width=120),
                       w(self.form.param.loss_factor_min, width=150), w(self.form.param.ratio_min, width=150),
                       sizing_mode="stretch_width"),
            pn.FlexBox(w(self.form.param.b_max_mm, width=150), w(self.form.param.length_max_mm, width=150),
                       w(self.form.param.thickness_min_mm, width=170),
                       pn.widgets.Checkbox.from_param(self.form.param.hold_inner, margin=(28, 10)),
                       sizing_mode="stretch_width"),
            pn.FlexBox(w(self.form.param.mu_min_mpa, width=150), w(self.form.param.mu_max_mpa, width=150),
                       pn.pane.HTML("<i>A µ range lets the compound vary too.</i>", margin=(28, 10)),
                       sizing_mode="stretch_width"),
            pn.Row(self.find, self.targets_file, self.searching),
            self.result, pn.Row(self.solutions, self.use), sizing_mode="stretch_width")
        return pn.Column(
            pn.pane.Markdown(TOLERANCE_TEXT, sizing_mode="stretch_width"), shape_pane(self.state, CARD_MODES), tol_grid, self.band_controls,
            self.band_status,
            pn.pane.Markdown(SENSITIVITY_TEXT, sizing_mode="stretch_width"), self.sentence, self.bars.grid(2),
            pn.pane.Markdown(DESIGN_TEXT, sizing_mode="stretch_width"), form,
            sizing_mode="stretch_width")



def found_values(design, sep: str, names=tuple(FOUND_COLUMNS), symbols: bool = False) -> str:
    """A found design's values of ``names`` in display units, each to its digits
    (:data:`FOUND_COLUMNS`), joined by ``sep``; each after its symbol with ``symbols``."""
    cells = []
    for n in names:
        p = BY_NAME[n]
        text = f"{p.unit.to_display(design.value(p.name)):{FOUND_COLUMNS[n]}}"
        cells.append(f"{p.symbol} {text}" if symbols else text)
    return sep.join(cells)
