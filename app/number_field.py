"""The one typed-number field of the app: a text box bound to a number of a Parameterized (the
session's state, a tab's form), read by the one input rule (:func:`core.numbers.parse_number`,
its bounds worded by :func:`core.numbers.range_problem` in the field's unit) and written by the
one formatter (:func:`core.numbers.format_number`).

A text that is no number (``9o``, ``abc``, ``1,5``) or a number out of range never reaches the
value: the field keeps the typed text, and a message beside it says what was typed and which
value is kept. A value set elsewhere (a preset, a fit, a link) is shown formatted; a typed value
stays as it was typed (the value holds every digit typed).
"""

from __future__ import annotations

from collections.abc import Callable

import panel as pn
import param

from core.numbers import format_number, format_value, parse_number, range_problem
from core.rules import RuleError


class NumberText(pn.widgets.TextInput):
    """Panel's TextInput for a number; served, its ``value`` is processed at once (no debounce:
    :data:`app.inputs.IMMEDIATE`)."""


def field_message(name: str, text: str) -> str:
    """The HTML of a message beside field ``name`` (nothing for no message)."""
    return f'<div class="field-error" data-field="{name}">⚠ {text}</div>' if text else ""


class NumberField(pn.viewable.Viewer):
    """A typed number bound to ``obj.<name>`` (a param.Number or param.Integer).

    ``unit``: the field's unit (a str, or a callable giving it: the |K| target's follows the
    mode), named in the label and the messages; ``quantity``: its digits (:data:`core.numbers.DIGITS`);
    ``bounds``: (low, high) in the field's unit, None for none (default: the parameter's own);
    ``low_open``: the low bound itself is refused; ``blank``: a blank field sets None (a field
    that may be left empty), else a blank is refused like any non-number."""

    def __init__(self, obj: param.Parameterized, name: str, *, label: str | None = None,
                 unit: str | Callable[[], str] = "", quantity=None, bounds=None, low_open: bool = False,
                 blank: bool | None = None, **widget):
        super().__init__()
        p = obj.param[name]
        self.obj, self.pname, self.quantity, self.low_open = obj, name, quantity, low_open
        self._showing = False
        self._unit = unit if callable(unit) else (lambda: unit)
        self._label = label or p.label
        self.bounds = bounds if bounds is not None else (p.bounds or (None, None))
        self.integer = isinstance(p, param.Integer)
        self.blank = p.allow_None if blank is None else blank
        self.input = NumberText(label=self.label(), value=self.shown(getattr(obj, name)),
                                description=p.doc, css_classes=["number-field"], **widget)
        # as wide as the field: a fixed-width field stays fixed (a stretching message made the
        # field's column take a whole row of a FlexBox)
        size = {"width": widget["width"]} if widget.get("width") else {"sizing_mode": "stretch_width"}
        self.message = pn.pane.HTML("", margin=(0, 10, 4, 10), styles={"color": "#b03a2e", "font-size": "0.9em"},
                                    **size)
        self.input.param.watch(self._typed, "value")
        obj.param.watch(self._set_elsewhere, name)

    @property
    def value(self):
        """The bound value (set: as a program sets it, not through the text's rule)."""
        return getattr(self.obj, self.pname)

    @value.setter
    def value(self, value):
        setattr(self.obj, self.pname, value)

    def label(self) -> str:
        """The label with the field's unit: ``|K| target (kN/mm)``; a label that ends in its unit
        (``Shear modulus µ (MPa)``, ``µ ± %``) as it is."""
        unit = self._unit()
        named = not unit or unit == "–" or self._label.endswith((f"({unit})", f" {unit}"))
        return self._label if named else f"{self._label} ({unit})"

    def relabel(self):
        """Show the label again (its unit may have changed)."""
        self.input.label = self.label()

    def shown(self, value) -> str:
        return "" if value is None else (str(int(value)) if self.integer else format_number(value, self.quantity))

    def problem(self, text: str):
        """(value, None) for a text this field takes, or (None, what is wrong with it)."""
        if self.blank and not str(text).strip():
            return None, None
        try:
            value = parse_number(text)
        except RuleError as exc:
            return None, exc.rule[0].upper() + exc.rule[1:]
        unit = self._unit()
        if self.integer and value != int(value):
            return None, f"{format_value(value, unit, 6)} is not a whole number"
        low, high = self.bounds
        wrong = range_problem(value, low, high, unit, self.quantity, low_open=self.low_open)
        if wrong:
            return None, wrong
        return (int(value) if self.integer else value), None

    def _typed(self, event):
        if self._showing:
            return  # the field shows a value set elsewhere: not typed
        value, wrong = self.problem(event.new)
        if wrong:
            kept = getattr(self.obj, self.pname)
            keeps = "empty" if kept is None else format_value(kept, self._unit(), self.quantity)
            self.message.object = field_message(self.pname, f"{wrong}; the field keeps {keeps}.")
            return
        self.message.object = ""
        if value != getattr(self.obj, self.pname):
            setattr(self.obj, self.pname, value)

    def _set_elsewhere(self, event):
        """A value set elsewhere is shown (formatted), unless the text already gives it."""
        value, wrong = self.problem(self.input.value)
        if wrong or value != event.new:
            self._showing = True
            try:
                self.input.value = self.shown(event.new)
            finally:
                self._showing = False
            self.message.object = ""

    def __panel__(self):
        return pn.Column(self.input, self.message, margin=0, sizing_mode=self.input.sizing_mode)
