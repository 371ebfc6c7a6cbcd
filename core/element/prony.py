"""The fractional derivative as a sum of exponentials over a stated band (docs/element.md).

Over a band [f₁, f₂] (Hz),

    (iω)^α ≈ Σ_j g_j · iω / (iω + λ_j),        g_j ≥ 0,

each term a Maxwell element whose state is integrated exactly over a time step. The rates λ_j
(1/s) are log-spaced from below f₁ to above f₂ (how far beyond the band depends on α: a small α
needs slow terms far below the band, an α near 1 fast ones far above it); the weights g_j
(s^−α) are the non-negative least-squares solution (:func:`scipy.optimize.nnls`) of the
relative complex error, its real and imaginary parts stacked as rows, on a grid of the band.
The number of terms is the smallest that meets the target (:data:`MAGNITUDE_TARGET`,
:data:`PHASE_TARGET`) on a dense check grid inside the band, up to :data:`MAX_TERMS`; the fit
reports the errors it reached on that grid (the largest relative magnitude error and the
largest phase error), whether or not they meet the target.

α = 1 is exactly a derivative: no sum of exponentials represents it (each term saturates), so
:func:`fit_power` refuses it and the element adds the term as a viscosity instead
(:mod:`core.element.coefficients`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

DEFAULT_BAND = (0.1, 2000.0)  # Hz
MAX_DECADES = 8.0  # the widest band: f₂/f₁ ≤ 10⁸
MAGNITUDE_TARGET = 1e-3  # relative
PHASE_TARGET = 1e-3  # rad
MAX_TERMS = 48
MIN_TERMS = 4
FIT_POINTS_PER_DECADE = 20
CHECK_POINTS_PER_DECADE = 500


def check_band(band) -> tuple[float, float]:
    """``band`` as (f₁, f₂) in Hz, or ValueError naming the rule it breaks: two finite positive
    frequencies, f₁ < f₂, at most :data:`MAX_DECADES` decades apart."""
    try:
        f1, f2 = (float(v) for v in band)
    except (TypeError, ValueError):
        raise ValueError(f"band: give two frequencies (f1, f2) in Hz, got {band!r}") from None
    if not (math.isfinite(f1) and math.isfinite(f2) and f1 > 0 and f2 > 0):
        raise ValueError(f"band: both frequencies must be positive finite numbers (Hz), got {f1:g} and {f2:g}")
    if not f1 < f2:
        raise ValueError(f"band: the lower frequency must be below the upper one, got {f1:g} Hz to {f2:g} Hz")
    if math.log10(f2 / f1) > MAX_DECADES:
        raise ValueError(f"band: at most {MAX_DECADES:g} decades wide (f2/f1 ≤ 1e{MAX_DECADES:g}), got "
                         f"{f1:g} Hz to {f2:g} Hz ({math.log10(f2 / f1):.3g} decades)")
    return f1, f2


@dataclass(frozen=True)
class PronyFit:
    """A fit of (iω)^α over a band by Σ g_j iω/(iω + λ_j).

    Attributes
    ----------
    alpha : float
        The fractional order α, in (0, 1).
    band : tuple of float
        (f₁, f₂), the band in Hz.
    rates : numpy.ndarray
        λ_j, 1/s, ascending.
    weights : numpy.ndarray
        g_j ≥ 0, s^−α.
    magnitude_error : float
        max |Σ/(iω)^α| − 1 over the band's check grid, relative.
    phase_error : float
        max |arg(Σ/(iω)^α)| over the check grid, rad.
    """

    alpha: float
    band: tuple[float, float]
    rates: np.ndarray
    weights: np.ndarray
    magnitude_error: float
    phase_error: float

    @property
    def terms(self) -> int:
        return int(self.rates.size)

    @property
    def meets_target(self) -> bool:
        """Whether the fit reaches :data:`MAGNITUDE_TARGET` and :data:`PHASE_TARGET`."""
        return self.magnitude_error <= MAGNITUDE_TARGET and self.phase_error <= PHASE_TARGET

    def response(self, frequency_hz) -> np.ndarray:
        """Σ_j g_j iω/(iω + λ_j) at ``frequency_hz`` (Hz), complex, s^−α·(rad/s)^α: compare with (iω)^α."""
        s = 2j * np.pi * np.asarray(frequency_hz, dtype=float)[..., None]
        return (s / (s + self.rates)) @ self.weights


def _grid(band, per_decade: int) -> np.ndarray:
    lo, hi = np.log10(band[0]), np.log10(band[1])
    return np.logspace(lo, hi, max(int(np.ceil((hi - lo) * per_decade)), 50))


def _extensions(alpha: float) -> tuple[tuple[float, float], ...]:
    """Decades of rates below f₁ and above f₂ to try, best first (measured over α 0.003–0.99:
    a small α needs terms far below the band, an α near 1 far above it)."""
    below = 3.0 if alpha < 0.02 else 2.0 if alpha < 0.1 else 1.5 if alpha < 0.5 else 1.0
    above = 0.5 if alpha < 0.03 else 1.0 if alpha < 0.65 else 2.0 if alpha < 0.95 else 3.0
    return (below, above), (below + 0.5, above), (below, above + 1.0)


def _errors(rates, weights, alpha, s_check) -> tuple[float, float]:
    ratio = (s_check[:, None] / (s_check[:, None] + rates)) @ weights / s_check**alpha
    return float(np.max(np.abs(np.abs(ratio) - 1.0))), float(np.max(np.abs(np.angle(ratio))))


def _fit(alpha, band, n, below, above, s_fit, s_check):
    w1, w2 = 2 * np.pi * band[0], 2 * np.pi * band[1]
    rates = np.logspace(np.log10(w1) - below, np.log10(w2) + above, n)
    a = (s_fit[:, None] / (s_fit[:, None] + rates)) / s_fit[:, None] ** alpha
    rows = np.vstack([a.real, a.imag])
    rhs = np.concatenate([np.ones(s_fit.size), np.zeros(s_fit.size)])
    scale = np.linalg.norm(rows, axis=0)
    try:
        g, _ = nnls(rows / scale, rhs, maxiter=100 * n)
    except RuntimeError:  # the active-set iteration did not finish: no fit at this count
        return None
    g = g / scale
    keep = g > 0
    rates, g = rates[keep], g[keep]
    return rates, g, *_errors(rates, g, alpha, s_check)


@functools.lru_cache(maxsize=64)
def _fit_cached(alpha: float, band: tuple[float, float]) -> PronyFit:
    s_fit = 2j * np.pi * _grid(band, FIT_POINTS_PER_DECADE)
    s_check = 2j * np.pi * _grid(band, CHECK_POINTS_PER_DECADE)
    best = None
    for n in range(MIN_TERMS, MAX_TERMS + 1):
        for below, above in _extensions(alpha):
            got = _fit(alpha, band, n, below, above, s_fit, s_check)
            if got is None:
                continue
            score = max(got[2] / MAGNITUDE_TARGET, got[3] / PHASE_TARGET)
            if best is None or score < best[0]:
                best = (score, got)
            if score <= 1.0:
                break
        if best is not None and best[0] <= 1.0:
            break
    rates, g, mag, phase = best[1]
    for arr in (rates, g):
        arr.setflags(write=False)
    return PronyFit(alpha, band, rates, g, mag, phase)


def fit_power(alpha: float, band=DEFAULT_BAND) -> PronyFit:
    """The sum of exponentials for (iω)^α over ``band`` (Hz): the fewest log-spaced terms that meet
    :data:`MAGNITUDE_TARGET` and :data:`PHASE_TARGET` inside the band, at most :data:`MAX_TERMS`
    (the best of those if none does: read :attr:`PronyFit.meets_target` and the errors).

    Parameters
    ----------
    alpha : float
        The fractional order, 0 < α < 1.
    band : (float, float), default (0.1, 2000)
        f₁ < f₂ in Hz, at most :data:`MAX_DECADES` decades apart.

    Returns
    -------
    PronyFit
        Rates (1/s), weights (s^−α) and the errors reached (relative magnitude, phase in rad).

    Raises
    ------
    ValueError
        If α is outside (0, 1) (α = 1 is an exact derivative: a viscosity, not exponentials) or
        the band breaks :func:`check_band`'s rules.
    """
    band = check_band(band)
    a = float(alpha)
    if a == 1.0:
        raise ValueError("alpha: α = 1 is an exact first derivative; no sum of exponentials represents it "
                         "(the element takes it as a viscosity m·dε/dt)")
    if not 0.0 < a < 1.0:
        raise ValueError(f"alpha: the fractional order must lie in (0, 1), got {alpha!r}")
    return _fit_cached(a, band)
