"""The link that holds a session: the URL names of the state's parameters (the whole design and
operating point; a design parameter's name in it is its ``url_key`` in :mod:`core.parameters`),
how their values are written and read, and :class:`UrlLink`, which keeps a session's state and
its address bar together with no copy of either.

The link holds what the page shows: the design the plots draw (its fields in display units, its
mode and shape, its ``name`` and ``effects``), the pinned reference (the same keys after
``ref.``), the operating point, the sweep range and the tolerance bands. A value a link gives
that breaks a rule is never applied silently: it gets a message naming the key, the value and
the rule, and the address bar goes on showing what the page shows (the kept value).
"""

from __future__ import annotations

import json
import math
from urllib.parse import parse_qsl, urlencode

import param
from panel.util import parse_query

from core import PAPER_B, Design, DesignError
from core.effects import validate_effects
from core.numbers import format_number, link_number
from core.parameters import PARAMETERS
from core.rules import RuleError, decimal

from .curves import amplitude_bounds
from .fields import DESIGN_FIELDS, design_from_fields, display_values
from .state import ExplorerState
from .units import amplitude_unit

URL_NAMES = {
    "mode": "mode",
    "finite_length": "finite",
    **{p.field: p.url_key for p in PARAMETERS},
    "amplitude": "amp",
    "frequency_hz": "f_Hz",
    "freq_min": "fmin_Hz",
    "freq_max": "fmax_Hz",
    "tolerance_text": "tol",
    "band_on": "bands",
}
DESIGN_KEYS = ("mode", "finite", *(p.url_key for p in PARAMETERS), "effects", "name")  # a design's keys
REFERENCE = "ref."  # the pinned reference's keys: a design's keys after this
NAME_LENGTH = 120  # a design's name in a link: at most this many characters (a longer one is cut)
# the state's changes reach the address bar this long (ms) after the last of them: a slider
# drag is one URL write and one history entry, not one per step
URL_DELAY_MS = 300


def url_value(value) -> str:
    """A value as the link writes it: text as it is, a number to :data:`core.numbers.LINK_DIGITS`
    significant digits (:func:`core.numbers.link_number`: ``2.41046``, ``0.1``, ``40``), anything
    else as JSON (``true``, ``null`` for none). The one place a link's values are formatted."""
    if isinstance(value, str):
        return value
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return link_number(value)
    return json.dumps(value)


# ---- a design in a link ------------------------------------------------------------------------


def effects_text(effects: dict) -> str:
    """A design's effects as a link writes them, with the design file's ids, parameter names and
    SI values: ``viscous.viscosity:1200,inertia@axial.mass:0.25,nonuniform_strain``."""
    items = []
    for eid, params in effects.items():
        items += [f"{eid}.{name}:{url_value(v)}" for name, v in params.items()] or [eid]
    return ",".join(items)


def parse_effects(text: str) -> dict[str, dict[str, float]]:
    """The effects of a link's ``effects`` text (:func:`effects_text`), held to the design file's
    rules (:func:`core.effects.validate_effects`); else a DesignError naming the key."""
    effects: dict[str, dict[str, float]] = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        left, colon, value = item.partition(":")
        eid, _, name = left.partition(".")
        params = effects.setdefault(eid, {})
        if not colon and not name:
            continue  # an effect without parameters
        key = f"effects.{eid}.{name}"
        if name in params:
            raise DesignError(key, "given twice", "duplicate_key")
        params[name] = decimal(value, key, DesignError)
    return validate_effects(effects)


def design_query(design: Design) -> dict[str, str]:
    """A design's keys of a link (:data:`DESIGN_KEYS`): the fields in display units, mode,
    shape, effects and name (none unset)."""
    out = {"mode": design.mode, "finite": url_value(design.shape == "finite")}
    out.update({DESIGN_FIELDS[f].url_key: url_value(v) for f, v in display_values(design).items() if v is not None})
    if design.effects:
        out["effects"] = effects_text(design.portable_effects)
    if design.name:
        out["name"] = design.name[:NAME_LENGTH]
    return out


def design_from_query(query: dict[str, str], where: str = "") -> Design:
    """The design a link's keys give (:func:`design_query`, each key after ``where``), by the
    input panel's rules; else a DesignError naming the first key that breaks one."""
    fields = {}
    for name, p in DESIGN_FIELDS.items():
        text = query.get(p.url_key, "")
        fields[name] = None if (p.optional and not text) else decimal(text, where + p.url_key, DesignError)
    effects = parse_effects(query.get("effects", ""))
    mode = query.get("mode", PAPER_B.mode)
    try:
        shape = "finite" if json.loads(query.get("finite", "false")) is True else None
    except ValueError:
        shape = None
    try:
        design, errors = design_from_fields(fields, PAPER_B, mode, shape, effects)
    except DesignError as exc:
        raise DesignError(where + exc.key, exc.rule, exc.code) from None
    if design is None:
        field, message = next(iter(errors.items()))
        key = DESIGN_FIELDS[field].url_key if field in DESIGN_FIELDS else "mode"
        raise DesignError(where + key, message[0].lower() + message[1:].rstrip("."))
    name = query.get("name", "")[:NAME_LENGTH] or None
    return design.replace(name=name)


# ---- the state in a link -----------------------------------------------------------------------


def url_query(state: ExplorerState) -> dict[str, str]:
    """The link of what the page shows: the design the plots draw (the last valid one: a field
    whose value breaks a rule shows its message, and the link keeps the value drawn), the
    operating point, the sweep range drawn, the bands, and the pinned reference after ``ref.``."""
    out = {**{URL_NAMES[n]: url_value(getattr(state, n)) for n in ("amplitude", "frequency_hz")},
           "fmin_Hz": url_value(state.freq_range[0]), "fmax_Hz": url_value(state.freq_range[1]),
           "tol": state.tolerance_text, "bands": url_value(state.band_on),
           **design_query(state.design)}
    if state.reference is not None:
        out.update({REFERENCE + k: v for k, v in design_query(state.reference).items()})
    return out


def owned(key: str) -> bool:
    """Whether a URL key is the link's (else it is kept as it is)."""
    return key in URL_NAMES.values() or key in DESIGN_KEYS or key.startswith(REFERENCE)


def link_values(search: str) -> dict:
    """The state's values a URL's query (``?a_mm=18&…``) gives, by state parameter name: numbers
    as numbers (display units, as the fields show them), true/false (any case) as booleans, the
    tolerance text as it is, ``null`` as a blank number field; other keys and blank values none.
    A value of the wrong kind is kept as it came, for :func:`refusal` to refuse."""
    text = search.removeprefix("?")
    raw, typed = dict(parse_qsl(text)), parse_query("?" + text)
    out = {}
    for name, key in URL_NAMES.items():
        if key not in raw:
            continue
        kind = ExplorerState.param[name]
        if isinstance(kind, param.String):
            out[name] = raw[key]
        elif isinstance(kind, param.Number) and raw[key] == "null":
            out[name] = None
        elif key in typed:  # Panel leaves out a value that looks like JSON and is none
            out[name] = typed[key]
    return out


def refusal(name: str, value) -> str | None:
    """Why the state cannot take a link's value for its parameter ``name`` (the rule, in plain
    words), or None. A design field's rules are the input panel's: its value is taken and judged
    there, beside the field."""
    p = ExplorerState.param[name]
    if isinstance(p, param.Selector):
        return None if value in p.objects else f"must be one of {', '.join(map(str, p.objects))}"
    if isinstance(p, param.Boolean):
        return None if isinstance(value, bool) else "must be true or false"
    if isinstance(p, param.Number):
        if value is None and p.allow_None:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return "is not a number"
        if name in DESIGN_FIELDS or name in ("freq_min", "freq_max"):
            return None
        if not math.isfinite(value):
            return "is not a finite number"
        if name == "amplitude":
            return None  # the design's amplitude axis judges it (apply_link)
        low, high = p.bounds or (None, None)
        if (low is not None and value < low) or (high is not None and value > high):
            return f"must lie between {low:g} and {high:g}" if high is not None else f"must be above {low:g}"
    return None


def said(key: str, value, rule: str, kept) -> str:
    """A link's refused value in words: the key, the value, the rule, what is kept."""
    return f"The link's {key}={value!r} {rule}; kept {kept}."


def apply_link(state: ExplorerState, search: str):
    """Apply a URL's query to the state: every value that differs from the state's, together,
    each refused one kept out with its message (:meth:`ExplorerState.apply_url_values`); the
    amplitude then held to the drive amplitude axis of the design it gives; the design's name,
    effects and the pinned reference as the link has them."""
    raw = dict(parse_qsl(search.removeprefix("?")))
    values = link_values(search)
    refused, good = {}, {}
    for name, value in values.items():
        rule = refusal(name, value)
        if rule is not None:
            refused[name] = said(URL_NAMES[name], value, rule, _kept(state, name))
        elif not _same(value, getattr(state, name)):
            good[name] = value
    amplitude = good.pop("amplitude", None)
    effects_shown = state.design.portable_effects
    text = raw.get("effects", "")
    if text != effects_text(effects_shown):
        try:
            effects = parse_effects(text)
            Design(good.get("mode", state.mode), state.design.geometry, state.design.material, effects=effects)
            good["effects"] = effects
        except RuleError as exc:
            refused["effects"] = said("effects", text, _plain(exc), effects_text(effects_shown) or "none")
    state.apply_url_values(good, {})
    if amplitude is not None:
        low, high = amplitude_bounds(state.design)
        if low <= amplitude <= high:
            state.amplitude = amplitude
        else:
            unit = amplitude_unit(state.design.mode)
            refused["amplitude"] = said("amp", amplitude, f"is outside this bushing's amplitude axis "
                                        f"({format_number(low, 3)}–{format_number(high, 3)} {unit})", f"{state.amplitude:g} {unit}")
    if raw.get("name") and not state.errors and raw["name"][:NAME_LENGTH] != state.design.name:
        state.name_design(raw["name"][:NAME_LENGTH])
    reference = {k.removeprefix(REFERENCE): v for k, v in raw.items() if k.startswith(REFERENCE)}
    shown = None if state.reference is None else design_query(state.reference)
    if not reference and shown is not None:
        state.reference = None
    elif reference and reference != shown:
        try:
            state.reference = design_from_query(reference, REFERENCE)
        except RuleError as exc:
            kept = "none" if state.reference is None else "the pinned one"
            refused["reference"] = said(exc.key or "ref", reference.get(exc.key.removeprefix(REFERENCE), ""),
                                        _plain(exc), kept)
    state.apply_url_values({}, refused)


def _plain(exc: RuleError) -> str:
    """A rule's words without the key (the message names it)."""
    return exc.rule


def _kept(state: ExplorerState, name: str) -> str:
    value = getattr(state, name)
    return url_value(value) if not isinstance(value, str) else repr(value)


def _same(a, b) -> bool:
    """Whether a link's value ``a`` is the state's ``b`` (False is no 0, "2" no 2; numbers to the
    link's digits: a state value with more digits than a link writes is not changed by its own link)."""
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    if isinstance(a, float) and isinstance(b, float):  # as the link writes them (its digits)
        return link_number(a) == link_number(b)
    return isinstance(a, bool) == isinstance(b, bool) and a == b


class UrlLink:
    """A session's state in its address bar (a Panel ``Location``), with no copy of either.

    Opened, the URL's values are applied and the whole state written back at once. Then the
    state's changes are written after a pause of ``delay_ms`` (each change restarts it: a slider
    drag is one write, one history entry), and a URL the browser sets (the back button) is
    applied. The URL this link wrote last is not applied again: it shows what the page shows,
    which may be a field's last valid value while the field shows the user's invalid one. Keys
    of the URL that are no state's are kept."""

    def __init__(self, state: ExplorerState, location, doc=None, delay_ms: int = URL_DELAY_MS):
        self.state, self.location, self.doc, self.delay_ms = state, location, doc, delay_ms
        self._next = None  # the document's timeout that will write the URL
        self._written = None  # the query this link wrote last
        apply_link(state, location.search)
        self.write()
        location.param.watch(self._opened, "search")
        state.param.watch(self._changed, [*URL_NAMES, "design", "freq_range", "reference"])

    def _opened(self, event):
        """A URL the browser sets (the page's own at its start, the back button): applied, and
        the URL then written from the state (a refused value leaves the address bar)."""
        if event.new != self._written:
            apply_link(self.state, event.new)
            self._changed()

    def _changed(self, *_events):
        """A change: the URL written ``delay_ms`` after the change has been handled, unless
        another comes first. The wait starts on the event loop's next turn, after the whole
        change (its plots included): started at the change, a change handled more slowly than
        the wait (a loaded machine) let the URL be written between two changes that came
        together, one history entry each."""
        if self.doc is None:  # no session (a script): at once
            self.write()
            return
        self._cancel()
        self._next = self.doc.add_next_tick_callback(self._arm)

    def _arm(self):
        self._next = self.doc.add_timeout_callback(self.write, self.delay_ms)

    def _cancel(self):
        if self._next is None:
            return
        try:  # Bokeh removes a session callback of either kind by this one call
            self.doc.remove_timeout_callback(self._next)
        except ValueError:
            pass  # it has just run
        self._next = None

    def write(self):
        """Put the state's linked values in the URL now (an unchanged URL is no change)."""
        self._next = None
        kept = {k: v for k, v in parse_qsl(self.location.search.removeprefix("?"), keep_blank_values=True)
                if not owned(k)}
        self._written = "?" + urlencode({**kept, **url_query(self.state)}, safe=":,@")
        self.location.search = self._written
