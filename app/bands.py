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
    """The tolerance bands' inputs and their message. A session's state (:class:`app.state.
    ExplorerState`) is one; its ``fit_result`` (the last fit, or None) may give the material's
    spread instead of its tolerances."""

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
    band_message = param.String(default="", doc="Why no band is drawn, if one was asked for.")

    @property
    def tolerance_pct(self) -> dict[str, float]:
        """The tolerances by parameter (core names), ± %. Raises ToleranceError for a text (a
        link's) that is not a list of known parameters with numbers."""
        return parse_tolerances(self.tolerance_text)

    @tolerance_pct.setter
    def tolerance_pct(self, values: dict[str, float]):
        self.tolerance_text = ",".join(f"{TOLERANCE_KEYS[n]}:{v:g}" for n, v in values.items() if v)

    def tolerances(self) -> Tolerances | None:
        """The tolerances the bands are drawn with (:class:`core.whatif.tolerance.Tolerances`), None
        when bands are off or nothing varies. Raises ToleranceError with the reason."""
        if not self.band_on:
            return None
        material = set(MATERIAL) if self.band_from_fit else set()
        relative = {n: v / 100.0 for n, v in self.tolerance_pct.items() if v and n not in material}
        covariance = None
        if self.band_from_fit:
            if self.fit_result is None:
                raise ToleranceError("no fit yet: fit measured data first (Measured data and fit), or use tolerances")
            covariance = FitCovariance.of(self.fit_result)
        tol = Tolerances(relative, distribution=self.band_distribution, samples=self.band_samples, seed=self.band_seed,
                         covariance=covariance)
        if not tol.varied:
            raise ToleranceError("every tolerance is 0: give one (± %) to see a band")
        return tol

    def checked_tolerances(self) -> Tolerances | None:
        """:meth:`tolerances`, or None with the reason in :attr:`band_message` (a band computed
        with them may still say why it cannot be: :meth:`banded`)."""
        try:
            tol = self.tolerances()
        except ToleranceError as exc:
            self.band_message = str(exc)
            return None
        self.band_message = ""
        return tol

    def banded(self, compute):
        """``compute(tolerances)`` with the tolerances of the bands, or None when there are none
        or a sample cannot be computed (the reason in :attr:`band_message`)."""
        tolerances = self.checked_tolerances()
        if tolerances is None:
            return None
        try:
            return compute(tolerances)
        except ToleranceError as exc:  # e.g. a sample outside the finite-length table
            self.band_message = str(exc)
            return None


# what a band depends on: the inputs above, and the fit whose covariance it may use
BAND_PARAMETERS = (*(n for n in ToleranceBands.param if n not in ("name", "band_message")), "fit_result")
