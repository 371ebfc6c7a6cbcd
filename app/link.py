"""The link that holds a session: the URL names of the state's parameters (the whole design and
operating point; a design parameter's name in it is its ``url_key`` in :mod:`core.parameters`),
how their values are written and read, and :class:`UrlLink`, which keeps a session's state and
its address bar together with no copy of either."""

from __future__ import annotations

import json
from urllib.parse import parse_qsl, urlencode

import param
from panel.util import parse_query

from core.numbers import link_number
from core.parameters import PARAMETERS

from .state import ExplorerState

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
# the state's changes reach the address bar this long (ms) after the last of them: a slider
# drag is one URL write and one history entry, not one per step
URL_DELAY_MS = 300


def url_query(state: ExplorerState) -> dict[str, str]:
    """The state's linked values as the link writes them, by URL name: text as it is, a number
    in the field's display unit to :data:`core.numbers.LINK_DIGITS` significant digits
    (:func:`core.numbers.link_number`: ``2.41046``, ``0.1``), anything else as JSON (``true``,
    ``null`` for a blank field)."""
    out = {}
    for name, key in URL_NAMES.items():
        value = getattr(state, name)
        if isinstance(value, str):
            out[key] = value
        elif isinstance(value, float):
            out[key] = link_number(value)
        else:
            out[key] = json.dumps(value)
    return out


def link_values(search: str) -> dict:
    """The state's values a URL's query (``?a_mm=18&…``) gives, by state parameter name: numbers
    as numbers (display units, as the fields show them), true/false (any case) as booleans, the
    tolerance text as it is, ``null`` as a blank number field; other keys and blank values none.
    A value of the wrong kind is kept as it came, for the state to refuse."""
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


def apply_link(state: ExplorerState, values: dict):
    """Set the state's values that differ from ``values`` (a link's): together, or one by one
    when one is refused, each refused value kept out with its message beside its field
    (:meth:`ExplorerState.apply_url_values`)."""
    changed = {n: v for n, v in values.items() if not _same(v, getattr(state, n))}
    if not changed:
        return
    try:
        state.param.update(changed)
    except Exception:  # noqa: BLE001 - one bad value: apply the others, say which
        state.apply_url_values(changed)


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
    applied. A URL written from the state reads back as the state's own values, which set
    nothing: no echo, so no guard is needed. Keys of the URL that are no state's are kept."""

    def __init__(self, state: ExplorerState, location, doc=None, delay_ms: int = URL_DELAY_MS):
        self.state, self.location, self.doc, self.delay_ms = state, location, doc, delay_ms
        self._next = None  # the document's timeout that will write the URL
        apply_link(state, link_values(location.search))
        self.write()
        location.param.watch(lambda event: apply_link(self.state, link_values(event.new)), "search")
        state.param.watch(self._changed, list(URL_NAMES))

    def _changed(self, *_events):
        if self.doc is None:  # no session (a script): at once
            self.write()
            return
        if self._next is not None:
            try:
                self.doc.remove_timeout_callback(self._next)
            except ValueError:
                pass  # it has just run
        self._next = self.doc.add_timeout_callback(self.write, self.delay_ms)

    def write(self):
        """Put the state's linked values in the URL now (an unchanged URL is no change)."""
        self._next = None
        kept = dict(parse_qsl(self.location.search.removeprefix("?"), keep_blank_values=True))
        self.location.search = "?" + urlencode({**kept, **url_query(self.state)})
