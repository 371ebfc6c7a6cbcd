"""The input panel: design fields with their units, messages and help, the operating point's
sliders, and the status line above the tabs. Widgets write the state; the state validates."""

from __future__ import annotations

import html
import math

import panel as pn
from bokeh.models import CustomJSTickFormatter, Tooltip

from core.bushing import STRUCTURAL_EFFECTS, shape_factor
from core.io.design_file import loads_design_upload
from core.numbers import format_change
from core.parameters import DEFAULT_SHAPE
from core.rules import RuleError

from .curves import amplitude_bounds
from .fields import DESIGN_FIELDS, GEOMETRY_FIELDS, MATERIAL_FIELDS, OPTIONAL_FIELDS
from .number_field import NumberField, NumberText
from .state import PRESETS, ExplorerState
from .units import OPERATING_FREQUENCIES, amplitude_unit
from .uploads import design_dropper, on_upload


def tip(text: str, anchor: str = "top_center", width: int = 420) -> Tooltip:
    """A button's description, shown when the pointer rests on it, centred on ``anchor`` of the
    button (a Bokeh anchor: above it for ``top_*``, below for ``bottom_*``), at most ``width``
    pixels wide, placed where it hides no other button of its row and stays in the window:
    Panel's default, to its right, covered the next button of its row, and a long one ran past
    the window's edge (issue #27)."""
    return Tooltip(content=text, position=anchor, attachment="above" if anchor.startswith("top") else "below",
                   stylesheets=[f":host {{ white-space: initial; max-width: {width}px; }}"])


class FloatInput(pn.widgets.FloatInput):
    """Panel's FloatInput; in a served app without the 50 ms debounce on its value, every edit
    answering at once (:func:`app.patches.send_values_at_once`, installed by ``create_app``)."""


class IntInput(pn.widgets.IntInput):
    """Panel's IntInput; served, without the debounce on its value (see :class:`FloatInput`)."""


class FloatSlider(pn.widgets.FloatSlider):
    """Panel's FloatSlider; served, without the debounce on its value (see :class:`FloatInput`)."""


IMMEDIATE = (FloatInput, IntInput, FloatSlider, NumberText)  # the app's number widgets, for app.patches
# the hint of an optional field left empty (the bulk modulus): what an empty field means
OPTIONAL_HINT = "empty: nearly incompressible (5000 µ)"


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
        position = event.new
        if position is None or not math.isfinite(position):
            return  # not a position (a hostile page): nothing moves
        position = self._clip(position)  # within the slider, whatever the page sent
        value = float(f"{10 ** position:.4g}")
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


# the look of a message beside a field (every tab's)
FIELD_ERROR_STYLES = {"color": "#b03a2e", "font-size": "0.9em"}


def field_error_html(name: str, message: str) -> str:
    """The message beside field ``name`` (HTML), or nothing for no message."""
    return f'<div class="field-error" data-field="{name}">⚠ {message}</div>' if message else ""


def error_text(state: ExplorerState, name: str):
    """The message beside a widget: what is wrong with its value, or nothing."""

    def render(errors):
        return field_error_html(name, errors.get(name, ""))

    return pn.pane.HTML(pn.bind(render, state.param.errors), margin=(0, 10, 4, 10),
                        styles=FIELD_ERROR_STYLES, sizing_mode="stretch_width")


class DesignInputs(pn.viewable.Viewer):
    """Mode, geometry, material, operating point and sweep range, each with unit and help."""

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        self.fields = {
            name: NumberField(state, name, label=state.param[name].label, quantity="parameter",
                              blank=name in DESIGN_FIELDS and DESIGN_FIELDS[name].optional,
                              unit=DESIGN_FIELDS[name].unit.display if name in DESIGN_FIELDS else "Hz",
                              sizing_mode="stretch_width",
                              **({"placeholder": OPTIONAL_HINT} if name in DESIGN_FIELDS and DESIGN_FIELDS[name].optional
                                 else {}))
            for name in (*DESIGN_FIELDS, "freq_min", "freq_max")
        }
        self.widgets = self.fields  # kept name: a field's ``value`` is the state's
        self.preset = pn.widgets.Select(
            label=state.param.preset.label, options=[*PRESETS, CUSTOM], value=shown_preset(state.design),
            description=state.param.preset.doc + f" “{CUSTOM}”: the design is none of them.",
            sizing_mode="stretch_width",
        )
        self.preset.param.watch(self._pick_preset, "value")
        state.param.watch(lambda e: setattr(self.preset, "value", shown_preset(e.new)), "design")
        self.mode = pn.widgets.RadioButtonGroup.from_param(
            state.param.mode, description=tip(state.param.mode.doc, "bottom_center", 300), color="primary",
            variant="outline", sizing_mode="stretch_width",
        )
        self.finite_length = pn.widgets.Switch.from_param(state.param.finite_length, margin=(8, 4, 0, 10))
        self.shape_note = pn.pane.Markdown("", sizing_mode="stretch_width", margin=(0, 10),
                                           styles={"font-size": "0.9em"})
        state.param.watch(lambda *_e: self._shape_note(), ["design", "finite_length", "mode"])
        self._shape_note()
        self.amplitude = LogSlider(state, "amplitude", lambda: amplitude_bounds(state.design),
                                   lambda: amplitude_unit(state.design.mode))
        self.frequency = LogSlider(state, "frequency_hz", lambda: OPERATING_FREQUENCIES, lambda: "Hz")
        self.design_file = DesignFile(state)

    def _pick_preset(self, event):
        """A preset picked: the state loads it (again, if it was the last one picked)."""
        if event.new not in PRESETS or self.state.design == PRESETS[event.new]:
            return  # "Custom", or the select following the design
        if self.state.preset == event.new:
            self.state.param.trigger("preset")
        else:
            self.state.preset = event.new

    def _field(self, name):
        field = self.fields[name]
        return pn.Column(field.input, field.message, error_text(self.state, name), margin=0,
                         sizing_mode="stretch_width")

    def _shape_note(self):
        """How far the finite-length shape factor is from the long-bushing formula, for this
        design (axial and radial; torsion's agree; conical has no formula). The switch is off
        where the mode always uses the finite-length one."""
        self.finite_length.disabled = DEFAULT_SHAPE[self.state.mode] == "finite"
        self.shape_note.object = shape_comparison(self.state.design)

    def __panel__(self):
        geometry = [self._field(n) for n in GEOMETRY_FIELDS]
        material = [self._field(n) for n in (*MATERIAL_FIELDS, *OPTIONAL_FIELDS)]
        return pn.Column(
            self.preset,
            self.mode,
            error_text(self.state, "mode"),
            self.finite_length,
            self.shape_note,
            pn.pane.Markdown("**Operating point**", margin=(8, 10, 0, 10)),
            self.amplitude,
            error_text(self.state, "amplitude"),
            self.frequency,
            error_text(self.state, "frequency_hz"),
            pn.Card(*geometry, title="Geometry", collapsed=False, sizing_mode="stretch_width"),
            pn.Card(*material, title="Material", collapsed=False, sizing_mode="stretch_width"),
            pn.Card(self._field("freq_min"), self._field("freq_max"), title="Frequency sweep",
                    sizing_mode="stretch_width"),
            self.design_file,  # beside Export and share, which saves it: the inputs first at 720 px
            sizing_mode="stretch_width",
        )


CUSTOM = "Custom"  # the preset select's entry for a design that is none of the presets


def shown_preset(design) -> str:
    """The preset select's entry for ``design``: the preset's name if it is one, else :data:`CUSTOM`."""
    return next((name for name, preset in PRESETS.items() if design == preset), CUSTOM)


def shape_comparison(design) -> str:
    """One line: the finite-length S against the long formula for this design's mode."""
    g, mode = design.geometry, design.mode
    try:
        finite = shape_factor(g, mode, "finite")
        if mode == "conical":
            return f"Conical S = {finite:.4g} m³ (finite-element; no closed form holds for real lengths)."
        long = shape_factor(g, mode, "long")
    except ValueError as exc:
        return f"Finite-length S not available: {exc}"
    if mode == "torsion":
        return "Torsion: the closed form is exact at any length (the finite-element S agrees)."
    used = "finite-element" if design.shape_kind == "finite" else "long-bushing formula"
    return (f"Finite-length S is {finite / long:.3f} of the long-bushing formula "
            f"({format_change(finite / long - 1)}); in use: the {used}.")


def status_banner(state: ExplorerState):
    """One line above the tabs: the design's name, or what is wrong with the input. A pane whose
    text changes in place (no re-layout)."""

    def render(errors, design):
        if errors:
            items = "".join(f"<li><b>{html.escape(_label(state, n))}</b>: {html.escape(m)}</li>"
                            for n, m in errors.items())
            return (
                '<div class="input-errors" style="background:#fff3cd;border:1px solid #ffe69c;'
                'padding:8px 12px;border-radius:6px;color:#664d03">'
                "Some inputs are not valid; the plots show the last valid design, and the link "
                f'holds it:<ul style="margin:4px 0 0 0">{items}</ul></div>'
            )
        effects = ", ".join(design.effect_parameters) if design.effects else ""
        name = html.escape(design.name or "Custom design")
        text = f"<b>{name}</b>, {design.mode}" + (f"; effects: {effects}" if effects else "")
        structural = [e for e in design.effect_parameters if e in STRUCTURAL_EFFECTS]
        if structural:
            text += (f" ({', '.join(structural)} act on the stiffness plots; the loop, slices and "
                     "branches show the material model)")
        return text

    return pn.pane.HTML(pn.bind(render, state.param.errors, state.param.design),
                        sizing_mode="stretch_width", margin=(4, 10), css_classes=["design-status"])


def _label(state: ExplorerState, name: str) -> str:
    """A field's label (its state parameter's), or its name."""
    return state.param[name].label if name in state.param else name


class DesignFile(pn.viewable.Viewer):
    """Open a design file (docs/files.md, as Export writes it): a click on the drop area opens
    the file chooser. The design is read by the core's design reader (that of ``bushing``) and
    shown at the operating point the user had when it is in the same mode and the amplitude lies
    on its axis (else mid-range); a refused file is named with what is wrong, and the last
    design stays."""

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        self.dropper = design_dropper()
        self.message = pn.pane.HTML("", sizing_mode="stretch_width", margin=(0, 10, 4, 10),
                                    styles={"font-size": "0.9em"}, css_classes=["design-file-message"])
        on_upload(self.dropper, self.load)

    def load(self, content: bytes | str, filename: str) -> bool:
        """Show the design file ``content`` called ``filename``; say what happened."""
        try:
            design, _fit = loads_design_upload(content)
        except RuleError as exc:
            self.message.object = (f'<div class="field-error" style="color:#b03a2e">⚠ {html.escape(filename)} '
                                   f"not loaded: {html.escape(str(exc))}</div>")
            return False
        s = self.state
        low, high = amplitude_bounds(design)
        if design.mode == s.design.mode and low <= s.amplitude <= high:
            s.adopt(design)
        else:
            s.load_design(design)
        self.message.object = f"Loaded {html.escape(filename)}: {html.escape(design.name or 'a design')}."
        return True

    def __panel__(self):
        return pn.Column(pn.pane.Markdown("**Open a design file** (.json, as Export writes it)",
                                          margin=(4, 10, 0, 10)),
                         self.dropper, self.message, margin=0, sizing_mode="stretch_width",
                         css_classes=["design-file"])


# copies the page's address (the link of what it shows) and says so on the button; where the
# page is no secure context (http on another host) navigator.clipboard is missing: a selected
# text area and the copy command instead
COPY_JS = """
const url = window.location.href;
const said = (ok) => {
  button.label = ok ? 'Link copied ✓' : 'Not copied: copy the address bar';
  setTimeout(() => { button.label = 'Copy link'; }, 3000);
};
const fallback = () => {
  const area = document.createElement('textarea');
  area.value = url;
  document.body.appendChild(area);
  area.select();
  let ok = false;
  try { ok = document.execCommand('copy'); } catch (e) { ok = false; }
  area.remove();
  said(ok);
};
if (navigator.clipboard && window.isSecureContext) {
  navigator.clipboard.writeText(url).then(() => said(true), fallback);
} else {
  fallback();
}
"""


def copy_link_button() -> pn.widgets.Button:
    """A button that copies the page's link (the address bar: design, effects, reference,
    operating point, bands) to the clipboard, in the browser."""
    button = pn.widgets.Button(label="Copy link", color="primary", sizing_mode="stretch_width",
                               description="Copy the link of what the page shows; opened, it shows the same.")
    button.js_on_click(args={"button": button}, code=COPY_JS)
    return button
