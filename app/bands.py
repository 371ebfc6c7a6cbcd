"""The what-ifs' tolerance bands of a session: the tolerances as a link writes them
(``tol=mu:10,L:1``, each parameter by its ``tolerance_key`` in :mod:`core.parameters`), the Monte
Carlo's settings, and the :class:`core.whatif.tolerance.Tolerances` the bands are drawn with, or
why there are none. No Panel import.
"""

from __future__ import annotations

import math

import param

from core.parameters import MATERIAL, PARAMETERS
from core.rules import RuleError, decimal
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
        """The band inputs' values, by the names of :func:`band_tolerances`' arguments."""
        return {name: getattr(self, name) for name in BAND_INPUTS}


# the band inputs (parameters of ToleranceBands); a band also depends on the fit (fit_result of
# app.fit_state.FitState) whose covariance it may use
BAND_INPUTS = tuple(n for n in ToleranceBands.param if n != "name")


def band_tolerances(tolerance_text: str, band_on: bool, band_distribution: str, band_samples: int,
                    band_seed: int, band_from_fit: bool, fit_result=None) -> Tolerances | str | None:
    """The tolerances the bands are drawn with (:class:`core.whatif.tolerance.Tolerances`), from
    the band inputs' values (:class:`ToleranceBands`) and the last fit (a
    :class:`core.identify.fit.FitResult` or None, for ``band_from_fit``); None when the bands are
    off; else the reason why there is no band (a str). Pure."""
    if not band_on:
        return None
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
