"""The what-ifs' tolerance bands of a session: the tolerances as a link writes them
(``tol=mu:10,L:1``, each parameter by its ``tolerance_key`` in :mod:`core.parameters`), the Monte
Carlo's settings, and the :class:`core.whatif.tolerance.Tolerances` the bands are drawn with, or
why there are none. No Panel import.
"""

from __future__ import annotations

import math

import param

from core import Design
from core.numbers import format_number
from core.parameters import BY_NAME, DEFAULT_SHAPE, GEOMETRY, MATERIAL, PARAMETERS
from core.rules import OUTER_NOT_LARGER, RuleError, decimal
from core.shape import OutsideTable, table
from core.whatif.tolerance import SAMPLES, FitCovariance, ToleranceError, Tolerances

# a parameter's key in the tolerances of a link (tol=mu:10,L:1)
TOLERANCE_KEYS = {p.name: p.tolerance_key for p in PARAMETERS}
_TOLERANCE_NAMES = {v: k for k, v in TOLERANCE_KEYS.items()}


def parse_tolerances(text: str) -> dict[str, float]:
    """``mu:10,L:1`` → {"shear_modulus": 10.0, "length": 1.0} (± %); ToleranceError if a key is
    unknown, given twice or its value is not a number from 0 to 89."""
    out: dict[str, float] = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        key, _, value = item.partition(":")
        name = _TOLERANCE_NAMES.get(key.strip())
        try:
            number = decimal(value)  # the one number rule: no "1_0", "nan" or other digits
        except RuleError:
            number = math.nan
        if name is None or name in out or not 0.0 <= number <= 89.0:
            raise ToleranceError(f"the tolerances {text[:80]!r}: give key:percent pairs, keys from "
                                 f"{', '.join(TOLERANCE_KEYS.values())}, percents from 0 to 89")
        out[name] = number
    return out


class ToleranceBands(param.Parameterized):
    """The tolerance bands' inputs. A session's state (:class:`app.state.ExplorerState`) is one;
    the bands (or why there are none) are computed from their values by the pure functions
    below: :func:`band_tolerances`, :func:`banded`. Nothing here is written while bands are
    computed."""

    tolerance_text = param.String(default="", doc="The tolerances in ± % as a link writes them (TOLERANCE_KEYS): "
                                  "mu:10,L:1 is µ ±10 % and L ±1 %.")
    band_on = param.Boolean(default=False, label="Show tolerance bands on the stiffness plots")
    band_distribution = param.Selector(objects=["uniform", "normal"], default="uniform", label="Distribution",
                                       doc="Uniform over ± the tolerance, or normal with the tolerance at 3σ "
                                       "(truncated there).")
    band_samples = param.Integer(default=SAMPLES, bounds=(10, 2000), label="Samples")
    band_seed = param.Integer(default=0, bounds=(0, 2**31 - 1), label="Seed")
    band_from_fit = param.Boolean(default=False, label="Material from the fit's covariance",
                                  doc="Draw the five material parameters from the last fit's standard errors and "
                                  "correlation (instead of their tolerances).")

    @property
    def tolerance_pct(self) -> dict[str, float]:
        """The tolerances by parameter (core names), ± %. Raises ToleranceError for a text (a
        link's) that is not a list of known parameters with numbers."""
        return parse_tolerances(self.tolerance_text)

    @tolerance_pct.setter
    def tolerance_pct(self, values: dict[str, float]):
        self.tolerance_text = ",".join(f"{TOLERANCE_KEYS[n]}:{v:g}" for n, v in values.items() if v)

    def band_inputs(self) -> dict:
        """The band inputs' values and the design they vary, by the names of
        :func:`band_tolerances`' arguments."""
        return {**{name: getattr(self, name) for name in BAND_INPUTS}, "design": getattr(self, "design", None)}


# the band inputs (parameters of ToleranceBands); a band also depends on the fit (fit_result of
# app.fit_state.FitState) whose covariance it may use
BAND_INPUTS = tuple(n for n in ToleranceBands.param if n != "name")


def band_tolerances(tolerance_text: str, band_on: bool, band_distribution: str, band_samples: int,
                    band_seed: int, band_from_fit: bool, fit_result=None,
                    design: Design | None = None) -> Tolerances | str | None:
    """The tolerances the bands are drawn with (:class:`core.whatif.tolerance.Tolerances`), from
    the band inputs' values (:class:`ToleranceBands`) and the last fit (a
    :class:`core.identify.fit.FitResult` or None, for ``band_from_fit``); None when the bands are
    off; else the reason why there is no band (a str: for tolerances ``design`` cannot take,
    :func:`tolerance_refusal`'s). Pure."""
    if not band_on:
        return None
    if design is not None:
        try:
            refused = tolerance_refusal(parse_tolerances(tolerance_text), design)[1]
        except ToleranceError as exc:
            return str(exc)
        if refused:
            return refused
    try:
        material = set(MATERIAL) if band_from_fit else set()
        relative = {n: v / 100.0 for n, v in parse_tolerances(tolerance_text).items() if v and n not in material}
        covariance = None
        if band_from_fit:
            if fit_result is None:
                return "no fit yet: fit measured data first (Measured data and fit), or use tolerances"
            covariance = FitCovariance.of(fit_result)
        tol = Tolerances(relative, distribution=band_distribution, samples=band_samples, seed=band_seed,
                         covariance=covariance)
    except ToleranceError as exc:
        return str(exc)
    if not tol.varied:
        return "every tolerance is 0: give one (± %) to see a band"
    return tol


def banded(tolerances: Tolerances | str | None, compute) -> tuple[object | None, str]:
    """``(compute(tolerances), "")`` for :func:`band_tolerances`' outcome; ``(None, "")`` when the
    bands are off; ``(None, reason)`` when there are no tolerances or a band with them cannot be
    computed (``compute`` raised ToleranceError: e.g. a sample outside the finite-length
    table). Pure as ``compute`` is."""
    if tolerances is None:
        return None, ""
    if isinstance(tolerances, str):
        return None, tolerances
    try:
        return compute(tolerances), ""
    except ToleranceError as exc:
        return None, str(exc)


def tolerance_key(tolerances: Tolerances) -> tuple:
    """A hashable form of ``tolerances`` (a cache's key), equal for equal tolerances given in the
    same order (the order of a fit's parameters sets the order of their draws):
    :func:`tolerances_of` gives them back."""
    t = tolerances
    covariance = None if t.covariance is None else (
        tuple(t.covariance.standard_errors.items()),
        tuple((a, tuple(row.items())) for a, row in t.covariance.correlation.items()))
    return (tuple(t.relative.items()), tuple(t.absolute.items()), t.distribution, t.samples, t.seed,
            tuple(t.percentiles), covariance)


def tolerances_of(key: tuple) -> Tolerances:
    """The tolerances of a :func:`tolerance_key`."""
    relative, absolute, distribution, samples, seed, percentiles, covariance = key
    if covariance is not None:
        errors, correlation = covariance
        covariance = FitCovariance(dict(errors), {a: dict(row) for a, row in correlation})
    return Tolerances(dict(relative), dict(absolute), distribution, samples, seed, percentiles, covariance)


# ---- a refusal in the panel's words ---------------------------------------------------------


def _shown(name: str, value: float) -> str:
    """``value`` (SI) of parameter ``name`` in its display unit: ``17.5 mm``."""
    return BY_NAME[name].unit.shown(value, 4)


def tolerance_refusal(tolerance_pct: dict[str, float], design: Design) -> tuple[tuple[str, ...], str]:
    """The parameters (core names) whose tolerances (± %, by name) ``design`` cannot take, and
    why, in the panel's words and display units; ``((), "")`` when it can take them. The core
    judges (:meth:`core.whatif.tolerance.Tolerances.check`); a message names only parameters
    given a tolerance, and says how far the tolerance may go. A geometry whose samples would
    leave the finite-length table (a corner of the tolerance box outside it) is refused too."""
    relative = {n: v / 100.0 for n, v in tolerance_pct.items() if v}
    tol = Tolerances(relative)
    try:
        tol.check(design)
    except ToleranceError as exc:
        return _refusal_words(exc, relative, design)
    return _outside_table(relative, design)


def _refusal_words(exc: ToleranceError, relative: dict[str, float], design: Design) -> tuple[tuple[str, ...], str]:
    g = design.geometry
    a, b = g.inner_radius, g.outer_radius
    if exc.code == OUTER_NOT_LARGER:
        named = tuple(n for n in GEOMETRY if n in relative and n != "length")  # the radii
        given = " and ".join(f"{BY_NAME[n].symbol} ± {100 * relative[n]:g} %" for n in named)
        moves = []
        if "inner_radius" in relative:
            moves.append(f"a reach {_shown('inner_radius', a * (1 + relative['inner_radius']))}")
        if "outer_radius" in relative:
            moves.append(f"b fall to {_shown('outer_radius', b * (1 - relative['outer_radius']))}")
        if len(named) == 1:
            (name,) = named
            other = "outer_radius" if name == "inner_radius" else "inner_radius"
            bound = (f"with {BY_NAME[other].symbol} = {_shown(other, design.value(other))}, the tolerance of "
                     f"{BY_NAME[name].symbol} must stay below {format_number(100 * (b - a) / design.value(name), 3)} %")
        else:
            bound = f"the two half-widths together must stay below b − a = {_shown('length', b - a)}"
        lets = "lets" if len(named) == 1 else "let"
        return named, f"{given} {lets} {' and '.join(moves)}: some bushings would have no rubber (b ≤ a); {bound}."
    name = exc.key.removeprefix("tolerances.")
    if name in BY_NAME and name in relative:
        low, high = (design.value(name) * (1 + s * relative[name]) for s in (-1, 1))
        return (name,), (f"{BY_NAME[name].label} ± {100 * relative[name]:g} % spans {_shown(name, low)} to "
                         f"{_shown(name, high)}, outside what the model takes ({exc.rule}).")
    return (), str(exc)


def _outside_table(relative: dict[str, float], design: Design) -> tuple[tuple[str, ...], str]:
    """The geometry tolerances whose box leaves the finite-length table, and the ratios' ranges."""
    named = tuple(n for n in GEOMETRY if n in relative)
    if not named or design.shape != "finite":
        return (), ""
    g = design.geometry
    corners = [dict(zip(GEOMETRY, (g.inner_radius * (1 + i * relative.get("inner_radius", 0.0)),
                                   g.outer_radius * (1 + j * relative.get("outer_radius", 0.0)),
                                   g.length * (1 + k * relative.get("length", 0.0)))))
               for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]
    outside = False
    for corner in corners:
        try:
            _ = design.replace(**corner).shape_factor  # raises outside the table
        except OutsideTable:
            outside = True
            break
    if not outside:
        return (), ""
    t = table()
    radius = [c["outer_radius"] / c["inner_radius"] for c in corners]
    length = [c["length"] / (c["outer_radius"] - c["inner_radius"]) for c in corners]
    given = ", ".join(f"{BY_NAME[n].symbol} ± {100 * relative[n]:g} %" for n in named)
    way_out = (" (or switch off the finite-length shape factor: the long-bushing formula)"
               if DEFAULT_SHAPE[design.mode] != "finite" else "")
    return named, (f"With {given}, b/a spans {format_number(min(radius), 3)}–{format_number(max(radius), 3)} and L/(b − a) "
                   f"{format_number(min(length), 3)}–{format_number(max(length), 3)}; the finite-length table covers b/a "
                   f"{t.radius_ratio[0]:g}–{t.radius_ratio[-1]:g} and L/(b − a) {t.length_ratio[0]:g}–"
                   f"{t.length_ratio[-1]:g}: narrow the tolerance{way_out}.")
