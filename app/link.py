"""The link that holds a session: the URL names of the state's parameters (the whole design and
operating point; a design parameter's name in it is its ``url_key`` in :mod:`core.parameters`)."""

from __future__ import annotations

import param

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


def _unjudged(p: param.Parameter) -> param.Parameter:
    """A link's copy of the state's parameter ``p``: of its kind, but a number of any value or
    none (the state judges it)."""
    if isinstance(p, param.Selector):
        return param.Selector(objects=list(p.objects), default=p.default)
    if isinstance(p, (param.Boolean, param.String)):
        return type(p)(default=p.default)
    return param.Number(default=None, allow_None=True)


class ShareLink(param.Parameterized):
    """The design as the address bar shows it: the state's linked parameters (:data:`URL_NAMES`),
    untouched by validation (the state judges them). A link opened (or the browser's back
    button) applies at once; the state's changes reach the address bar after a pause, so a
    slider drag is one history entry and one URL write, not one per step."""


for _name in URL_NAMES:
    ShareLink.param.add_parameter(_name, _unjudged(ExplorerState.param[_name]))
