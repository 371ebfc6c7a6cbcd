"""Plain words for what the user must know about a fit (:func:`core.identify.fit.fit_global`):
parameters driven to the end of their fitting range, parameters the data do not determine, an
unfinished profile.
"""

from __future__ import annotations

import math

from ..parameters import BY_NAME, Parameter, Unit
from ..registry import parameter_unit
from .uncertainty import CONFIDENCE, SIDE_EVALUATIONS


def _value_words(name: str, value: float, mode: str) -> str:
    """A value of parameter ``name`` (its fitting name, SI) in ``mode`` as people read it: a
    material field in the unit of its field (``3.55 MPa``), an effect's parameter in its unit
    (``0.52 kg``), a pure number alone."""
    if name in BY_NAME:
        return BY_NAME[name].unit.shown(value)
    si = parameter_unit(name, mode)
    return Unit(si, si).shown(value)


def _pushed(spec: Parameter, x: float, interval, edge: str, span: float) -> bool:
    """Whether the data push a parameter at the ``edge`` of its fitting range against it: its
    profile excludes values a tenth of the range away (else the data do not see it there, as a
    mass of 1e-12 kg, and it is merely not determined)."""
    if interval is None:
        return True  # not profiled: the edge is all that is known
    inner = interval[1] if edge == "lower" else interval[0]  # the side away from the edge
    if inner is None:
        return False
    return abs((math.log(inner) if spec.log else inner) - x) <= span / 10


def fit_warnings(problem, sol, intervals: dict, complete: bool) -> tuple[str, ...]:
    """Plain words for what the user must know about a fit: parameters driven to the end of
    their fitting range, parameters the data do not determine, an unfinished profile."""
    lo, hi = problem.bounds()
    values = problem.values(sol.x)
    out, at_edge = [], set()
    for i, (name, spec) in enumerate(zip(problem.free, problem.specs)):
        span = hi[i] - lo[i]
        edge = "lower" if sol.x[i] - lo[i] <= 1e-6 * span else "upper" if hi[i] - sol.x[i] <= 1e-6 * span else None
        if edge and _pushed(spec, sol.x[i], intervals.get(name), edge, span):
            at_edge.add(name)
            shown = _value_words(name, values[name], problem.design.mode)
            out.append(f"{name} ran to the {edge} end of its fitting range ({shown}): "
                       f"the model cannot follow these data there; check that the design's mode and "
                       f"geometry are those of the measurement")
    for name, (a, b) in intervals.items():
        if (a is None or b is None) and name not in at_edge:
            mode = problem.design.mode
            which = ("any value in its fitting range" if a is None and b is None
                     else f"any value up to {_value_words(name, b, mode)}" if a is None
                     else f"any value from {_value_words(name, a, mode)} up")
            out.append(f"{name} is not determined by these data: {which} fits them as well "
                       f"({CONFIDENCE:.0%} profile); measure more amplitudes or frequencies to pin it down")
    if not complete:
        out.append(f"the profile intervals are incomplete: a side spent its {SIDE_EVALUATIONS} evaluations "
                   f"of the model before the end (unfinished sides are open)")
    return tuple(out)
