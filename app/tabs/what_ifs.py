"""The "What-ifs" tab: tolerance bands (drawn on the explorer's stiffness plots and the card),
sensitivities at the operating point, and designs found from target stiffnesses."""

from __future__ import annotations

import io

import holoviews as hv
import panel as pn
import param

from core.card import CARD_MODES
from core.numbers import format_change, format_number, format_value
from core.parameters import BY_NAME, GEOMETRY, MODE, NAMES
from core.whatif.sensitivity import elasticities, sentence
from core.whatif.target import Words
from core.whatif.tolerance import ToleranceError

from .. import curves, units
from ..bands import band_tolerances, banded, tolerance_refusal
from ..fit_state import FitState
from ..inputs import FIELD_ERROR_STYLES, field_error_html
from ..live import LivePlot, one_change
from ..number_field import NumberField
from ..plotting.what_ifs import sensitivity_bars
from ..shapes import shape_pane
from ..state import ExplorerState
from ..targets_form import TargetsForm
from ..views import PlotView

A, _B, L, MU = (BY_NAME[n] for n in (*GEOMETRY, "shear_modulus"))
# a found design's columns: its geometry and µ (what a search changes), each with its quantity's digits
FOUND_COLUMNS = {**{n: "size" for n in GEOMETRY}, MU.name: "modulus"}


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


# the tolerances' fields (± %, from 0 to 89 as a link's are: app.bands.parse_tolerances)
ToleranceFields = type("ToleranceFields", (param.Parameterized,), {
    "__doc__": "Each design parameter's tolerance, ± %.",
    **{n: param.Number(0.0, bounds=(0.0, 89.0), label=f"{BY_NAME[n].label} ± %") for n in NAMES}})


class WhatIfView(PlotView):
    """Tolerances, sensitivities, targets."""

    shows = ("design", "frequency", "amplitude", "sweep range", "bands")  # the bars, and the bands' status

    fit = param.ClassSelector(class_=FitState, doc="The session's fit (its covariance may make the bands).")

    def __init__(self, state: ExplorerState, fit: FitState, **params):
        self._showing = False
        super().__init__(state, fit=fit, **params)
        self.tolerances = ToleranceFields(**self._shown_tolerances())
        self.tolerance_inputs = {n: NumberField(self.tolerances, n, unit="%", quantity="percent", width=170)
                                 for n in NAMES}
        self.tolerances.param.watch(lambda *events: self._set_tolerance(events[-1].name, events[-1].new), list(NAMES))
        # beside each tolerance: why the design cannot take it (app.bands.tolerance_refusal)
        self.tolerance_errors = {n: pn.pane.HTML("", margin=(0, 10, 4, 10), styles=FIELD_ERROR_STYLES,
                                                 sizing_mode="stretch_width") for n in NAMES}
        s = state.param
        # FlexBox, not Row: the controls wrap onto a second line in a narrow window (a Row ran
        # past the window's edge at 1280 px and cut the last checkbox's label)
        self.band_controls = pn.FlexBox(
            pn.widgets.Checkbox.from_param(s.band_on, margin=(28, 10), width=330, css_classes=["band-switch"]),
            pn.widgets.Select.from_param(s.band_distribution, width=120),
            NumberField(state, "band_samples", width=100),
            NumberField(state, "band_seed", width=100),
            pn.widgets.Checkbox.from_param(s.band_from_fit, margin=(28, 10)),
            align_items="flex-start", sizing_mode="stretch_width")
        self.band_status = pn.pane.HTML("", sizing_mode="stretch_width")
        self.sentence = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.bars: LivePlot | None = None
        self.form = TargetsForm(state)
        self.form.param.watch(self._show_search, ["found", "message", "running", "progress_message"])
        self.form_fields = self._form_fields()
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

    def _form_fields(self) -> dict[str, NumberField]:
        """The design form's typed fields, each with its unit (the |K| target's follows the mode)."""
        form, mode = self.form, lambda: self.state.design.mode
        units_of = {"target_magnitude": lambda: units.stiffness_unit(mode()), "target_tolerance_pct": "%",
                    "b_max_mm": _B.unit.display, "length_max_mm": L.unit.display,
                    "thickness_min_mm": _B.unit.display, "mu_min_mpa": MU.unit.display,
                    "mu_max_mpa": MU.unit.display}
        quantity = {"target_magnitude": "stiffness", "target_tolerance_pct": "percent", "loss_factor_min": "loss_factor",
                    "ratio_min": "ratio"}
        widths = {"target_tolerance_pct": 120, "thickness_min_mm": 170}
        fields = {n: NumberField(form, n, unit=units_of.get(n, ""), quantity=quantity.get(n, "size"),
                                 low_open=n not in ("target_tolerance_pct", "loss_factor_min", "thickness_min_mm"), width=widths.get(n, 150))
                  for n in ("target_magnitude", "target_tolerance_pct", "loss_factor_min", "ratio_min", "b_max_mm",
                            "length_max_mm", "thickness_min_mm", "mu_min_mpa", "mu_max_mpa")}
        self.state.param.watch(lambda _e: fields["target_magnitude"].relabel(), "design")
        return fields

    # ---- tolerances ------------------------------------------------------------------------------

    def _shown_tolerances(self) -> dict[str, float]:
        try:
            return self.state.tolerance_pct
        except ToleranceError:  # a link's text that is no list of tolerances: its message says so
            return {}

    def _set_tolerance(self, name: str, value):
        if self._showing:
            return
        values = {n: getattr(self.tolerances, n) or 0.0 for n in NAMES}
        values[name] = float(value or 0.0)
        self.state.tolerance_pct = values

    @param.depends("state.tolerance_text", watch=True)
    def _show_tolerances(self):
        """A link (or the back button) sets the tolerances: the inputs show them."""
        values = self._shown_tolerances()
        self._showing = True  # the inputs follow the state here, not the other way round
        try:
            self.tolerances.param.update({n: values.get(n, 0.0) for n in NAMES})
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
                _, reason = banded(tolerances, lambda tol: curves.card_bands(design, f, tol))
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
        self.sentence.object = (f"At {format_value(s.frequency_hz, 'Hz', 'frequency')} and "
                                f"{format_value(s.amplitude, units.amplitude_unit(s.design.mode), 'amplitude')}: "
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
        lines = [f"**{found.words(WORDS)}** ({found.seconds:.2f} s)"]
        rows = self.form.rows()
        if rows:
            targets = found.problem.targets
            header = [f"{BY_NAME[n].symbol} ({BY_NAME[n].unit.display})" for n in FOUND_COLUMNS]
            lines += ["", "| | " + " | ".join(header + [f"target {j}" for j in range(1, len(targets) + 1)]) + " |",
                      "|---" * (1 + len(header) + len(targets)) + "|"]
            for i, sol in enumerate(rows, 1):
                got = " | ".join(shown_measure(t, v) for t, v in zip(targets, sol.achieved))
                name = f"{i}" if found.solutions else "closest"
                lines.append(f"| {name} | {found_values(sol.design, ' | ')} | {got} |")
            lines += [""] + [f"Target {j}: {target_words(t)}." for j, t in enumerate(targets, 1)]
        self.result.object = "\n".join(lines)
        self.solutions.options = {f"{i}: {found_values(s.design, ', ', GEOMETRY, symbols=True)} {A.unit.display}": i - 1
                                  for i, s in enumerate(rows, 1)}
        self.solutions.visible = self.use.visible = bool(rows)
        self.use.label = "Take it into the explorer" if found.solutions else "Take the closest into the explorer"

    def __panel__(self):
        f = self.form_fields
        tol_grid = pn.GridBox(*(pn.Column(field, self.tolerance_errors[n], margin=0, sizing_mode="stretch_width")
                                for n, field in self.tolerance_inputs.items()), ncols=4, sizing_mode="stretch_width")
        form = pn.Column(
            pn.FlexBox(f["target_magnitude"], f["target_tolerance_pct"], f["loss_factor_min"], f["ratio_min"],
                       sizing_mode="stretch_width"),
            pn.FlexBox(f["b_max_mm"], f["length_max_mm"], f["thickness_min_mm"],
                       pn.widgets.Checkbox.from_param(self.form.param.hold_inner, margin=(28, 10)),
                       sizing_mode="stretch_width"),
            pn.FlexBox(f["mu_min_mpa"], f["mu_max_mpa"],
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
        text = format_number(p.unit.to_display(design.value(p.name)), FOUND_COLUMNS[n])
        cells.append(f"{p.symbol} {text}" if symbols else text)
    return sep.join(cells)


def shown_measure(target, value: float) -> str:
    """What a found design achieves for ``target``, in display units: |K| in its mode's unit,
    a loss factor or a ratio as a number."""
    if target.quantity == "magnitude" and not target.is_ratio:
        mode = target.modes[0]
        return format_value(units.display_stiffness(value, mode), units.stiffness_unit(mode), "stiffness")
    return format_value(value, "", "ratio" if target.is_ratio else "loss_factor")


def target_words(target) -> str:
    """A target in the display units of the form (``axial |K| = 4.5 kN/mm ± 1 % at 10 Hz, 0.1 mm``):
    :meth:`core.whatif.target.Target.describe` with the form's units and the one formatter."""
    t = target

    def shown(v):
        if t.is_ratio or t.quantity == "loss_factor":
            return format_value(v, "", "ratio" if t.is_ratio else "loss_factor")
        return format_value(units.display_stiffness(v, t.modes[0]), MODE[t.modes[0]].stiffness.display, "stiffness")

    return t.describe(shown, lambda x, m: format_value(units.display_amplitude(x, m), units.amplitude_unit(m), "amplitude"),
                      lambda f: format_value(f, "Hz", "frequency"))


def limit_words(item: str) -> str:
    """A limit a found design sits on, as the core words it (``outer_radius ≤ 0.04``, SI), in the
    form's words and display unit (``b ≤ 40 mm``, ``b − a ≥ 2 mm``); anything else as it is."""
    name, _, rest = item.partition(" ")
    op, _, value = rest.partition(" ")
    try:
        number = float(value)
    except ValueError:
        return item
    if _variable(name) is None:
        return item
    symbol, unit = _variable(name)
    return f"{symbol} {op} {format_value(unit.to_display(number), unit.display, FOUND_COLUMNS.get(name, 'size'))}"


def variable_name(name: str) -> str:
    """A searched variable as the form names it (:func:`_variable`)."""
    return _variable(name)[0]


def _variable(name: str):
    """A searched variable or a limited parameter as the form names it, with its unit: a design
    parameter by its symbol (``b``, ``µ``), the rubber's thickness t as ``b − a`` in b's unit;
    None for any other name."""
    if name == "thickness":
        return f"{_B.symbol} − {A.symbol}", _B.unit
    p = BY_NAME.get(name)
    return None if p is None else (p.symbol, p.unit)


# the statement of a search in the form's words and units, by the one formatter
WORDS = Words(target_words, shown_measure, limit_words, format_change, variable_name)
