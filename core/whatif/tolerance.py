"""Tolerance bands: how far |K| and the loss factor spread when the geometry and the compound
vary within their tolerances, or within the uncertainty of a fit.

A band is a Monte Carlo: ``samples`` designs drawn with a stated ``seed`` (NumPy's default
generator), each computed exactly (:func:`core.bushing.stiffness_points`); the band's
percentiles of |K| and η at every point are those of the samples. The draws:

* a parameter with a tolerance ±h (relative, as a fraction of its value, or absolute in SI units)
  is drawn ``uniform`` over [p − h, p + h], or ``normal`` with h = 3σ, truncated at ±h (no part
  lies outside its tolerance); the parameters are independent;
* with a fit's covariance (:class:`FitCovariance`), the material parameters the fit determined
  are drawn jointly normal in the fit's own coordinates (ln µ, ln m, α, ln σ_fmax, ln ε½) with the
  fit's standard errors and correlation; α is kept within (0.001, 1].

The first-order propagation is the check where the spread is small: σ² = g Σ gᵀ with g the
derivatives of |K| (or η) from :func:`core.whatif.sensitivity.log_derivatives` and Σ the draws'
covariance.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import numpy as np
from scipy import linalg, stats

from ..bushing import (
    bulk_correction,
    check_strain,
    equivalent_stiffness,
    factors,
    shape_factor,
    stiffness_points,
    strain_factor,
)
from ..design import Design
from ..identify.fit import FitResult
from ..material import equivalent_modulus
from ..parameters import GEOMETRY, MATERIAL, NAMES
from ..parts import Geometry
from ..registry import parameter
from ..response import loss_factor
from ..rules import (
    BAD_CHOICE,
    DUPLICATE_KEY,
    MISSING_KEY,
    NEGATIVE,
    NOT_A_NUMBER,
    NOT_FINITE,
    OUT_OF_RANGE,
    OUTER_NOT_LARGER,
    TOO_LARGE,
    UNKNOWN_KEY,
    DesignError,
    RuleError,
    is_number,
    whole_number,
)
from .sensitivity import log_derivatives

DISTRIBUTIONS = ("uniform", "normal")
SAMPLES = 500  # the default sample count
SAMPLE_RANGE = (10, 5000)
PERCENTILES = (5.0, 50.0, 95.0)
MAX_RELATIVE = 0.9  # a tolerance of ±90 % or more is no tolerance
MAX_EVALUATIONS = 20_000_000  # samples × points of one band
_TRUNCATED = stats.truncnorm(-3.0, 3.0)
_UNIT_STD = {"uniform": 1.0 / math.sqrt(3.0), "normal": float(_TRUNCATED.std()) / 3.0}  # of u in [−1, 1]
_FIT_KEYS = ("standard_errors", "correlation")


class ToleranceError(RuleError):
    """A tolerance specification that cannot be used: ``key`` names where, ``rule`` the reason
    in plain words, ``code`` the rule (:mod:`core.rules`)."""


@dataclass(frozen=True)
class FitCovariance:
    """A fit's uncertainty of the material: standard errors (natural units) and the correlation
    of the fitted (log) parameters, as :class:`core.identify.fit.FitResult` reports them."""

    standard_errors: dict[str, float]
    correlation: dict[str, dict[str, float]]

    @classmethod
    def of(cls, result: FitResult) -> FitCovariance:
        return cls.from_report(result.report())

    @classmethod
    def from_report(cls, report: Any) -> FitCovariance:
        """From the ``fit`` object of a fitted design file."""
        if not isinstance(report, Mapping) or any(not isinstance(report.get(k), Mapping) for k in _FIT_KEYS):
            raise ToleranceError("fit_covariance", "the design file has no fit report (standard_errors and "
                                 "correlation); give the output of `bushing fit`", MISSING_KEY)
        return cls(dict(report["standard_errors"]), {k: dict(v) for k, v in report["correlation"].items()})

    def matrix(self, design: Design) -> tuple[tuple[str, ...], np.ndarray]:
        """The material parameters and their covariance in the fit's coordinates."""
        names = tuple(n for n in self.standard_errors if n in NAMES)
        vague = [n for n in names if not is_number(self.standard_errors[n])]
        if vague:
            raise ToleranceError("fit_covariance", f"the fit does not determine {', '.join(vague)} (no standard "
                                 "error): its covariance cannot make a band; give a tolerance for it instead", NOT_FINITE)
        if not names:
            raise ToleranceError("fit_covariance", "the fit report holds no material parameter", MISSING_KEY)
        sd = np.array([self.standard_errors[n] / (design.value(n) if parameter(n).log else 1.0) for n in names])
        try:
            corr = np.array([[float(self.correlation[a][b]) for b in names] for a in names])
        except (KeyError, TypeError, ValueError):
            raise ToleranceError("fit_covariance", "the fit's correlation does not cover its parameters",
                                 MISSING_KEY) from None
        if not np.all(np.isfinite(corr)):
            raise ToleranceError("fit_covariance", "the fit's correlation is not defined (a degenerate fit)",
                                 NOT_FINITE)
        return names, corr * np.outer(sd, sd)


@dataclass(frozen=True)
class Tolerances:
    """Tolerances of a design's parameters: ``relative`` (a fraction of the value) or
    ``absolute`` (SI units) half-widths by parameter name (:data:`NAMES`), the
    ``distribution`` of the draws, their number and seed, the band's ``percentiles``, and
    optionally a fit's ``covariance`` for the material."""

    relative: dict[str, float] = field(default_factory=dict)
    absolute: dict[str, float] = field(default_factory=dict)
    distribution: str = "uniform"
    samples: int = SAMPLES
    seed: int = 0
    percentiles: tuple[float, ...] = PERCENTILES
    covariance: FitCovariance | None = None

    def __post_init__(self):
        for kind, values in (("relative", self.relative), ("absolute", self.absolute)):
            for name, h in values.items():
                key = f"tolerances.{name}"
                if name not in NAMES:
                    raise ToleranceError(key, f"unknown parameter (known: {', '.join(NAMES)})",
                                         UNKNOWN_KEY)
                if not is_number(h) or h < 0:
                    raise ToleranceError(key, f"must be a number ≥ 0, got {str(h)[:40]}",
                                         NEGATIVE if is_number(h) else NOT_A_NUMBER)
                if kind == "relative" and h >= MAX_RELATIVE:
                    raise ToleranceError(key, f"±{100 * h:g} % is not a tolerance (at most {100 * MAX_RELATIVE:g} %)",
                                         OUT_OF_RANGE)
        both = set(self.relative) & set(self.absolute)
        if both:
            raise ToleranceError(f"tolerances.{min(both)}", "given twice (relative and absolute)", DUPLICATE_KEY)
        if self.distribution not in DISTRIBUTIONS:
            raise ToleranceError("distribution", f"must be one of {', '.join(DISTRIBUTIONS)}, got "
                                 f"{str(self.distribution)[:40]}", BAD_CHOICE)
        if code := whole_number(self.samples, *SAMPLE_RANGE):
            raise ToleranceError("samples", f"a whole number from {SAMPLE_RANGE[0]} to {SAMPLE_RANGE[1]}, got "
                                 f"{str(self.samples)[:40]}", code)
        if code := whole_number(self.seed, 0, 2**63 - 1):
            raise ToleranceError("seed", f"a whole number from 0 to 2^63 − 1, got {str(self.seed)[:40]}", code)
        if not self.percentiles or any(not is_number(q) or not 0 <= q <= 100 for q in self.percentiles) or \
                len(self.percentiles) > 9:
            raise ToleranceError("percentiles", f"one to nine numbers from 0 to 100, got "
                                 f"{str(list(self.percentiles))[:60]}", OUT_OF_RANGE)

    @property
    def varied(self) -> bool:
        return self.covariance is not None or any(h > 0 for h in (*self.relative.values(), *self.absolute.values()))

    def half_widths(self, design: Design) -> dict[str, float]:
        """Every toleranced parameter's half-width in SI units (zero tolerances left out)."""
        out = {n: h * design.value(n) for n, h in self.relative.items()}
        out.update(self.absolute)
        return {n: h for n, h in out.items() if h > 0}

    def check(self, design: Design) -> None:
        """Refuse tolerances that take a part outside what is a bushing (b ≤ a, a size or modulus
        ≤ 0, α > 1), naming the parameter."""
        h = self.half_widths(design)
        if self.covariance is not None:
            names, _ = self.covariance.matrix(design)
            twice = sorted(set(names) & set(h))
            if twice:
                raise ToleranceError(f"tolerances.{twice[0]}", "given twice (a tolerance and the fit's covariance)",
                                     DUPLICATE_KEY)
        a_high = design.geometry.inner_radius + h.get("inner_radius", 0.0)
        b_low = design.geometry.outer_radius - h.get("outer_radius", 0.0)
        if a_high >= b_low:
            raise ToleranceError("tolerances", f"a may reach {a_high:.4g} m and b fall to {b_low:.4g} m: "
                                 "some parts would have no rubber (b ≤ a)", OUTER_NOT_LARGER)
        for name, width in h.items():
            low, high = design.value(name) - width, design.value(name) + width
            try:
                design.replace(**{name: low})
                design.replace(**{name: high})
            except DesignError as exc:
                raise ToleranceError(f"tolerances.{name}", f"±{width:.4g} takes it outside its range ({exc.rule})",
                                     OUT_OF_RANGE) from None

    def draws(self, design: Design) -> list[dict[str, float]]:
        """The sampled parameter values (only those that vary), one mapping per sample."""
        self.check(design)
        rng = np.random.default_rng(self.seed)
        n = self.samples
        out: dict[str, np.ndarray] = {}
        for name, width in sorted(self.half_widths(design).items()):
            u = rng.uniform(-1.0, 1.0, n) if self.distribution == "uniform" else \
                _TRUNCATED.rvs(n, random_state=rng) / 3.0
            out[name] = design.value(name) + width * u
        if self.covariance is not None:
            names, cov = self.covariance.matrix(design)
            centre = np.array([math.log(design.value(p)) if parameter(p).log else design.value(p) for p in names])
            theta = rng.multivariate_normal(centre, cov, n, method="eigh")
            for j, name in enumerate(names):
                lo, hi = parameter(name).bounds
                out[name] = np.exp(theta[:, j]) if parameter(name).log else np.clip(theta[:, j], max(lo, 1e-3), hi)
        return [{name: float(v[i]) for name, v in out.items()} for i in range(n)]

    def covariance_of_draws(self, design: Design) -> tuple[tuple[str, ...], np.ndarray]:
        """The names and the covariance of the draws in ln p (for first-order propagation): the
        tolerances' independent variances, then the fit's block (its coordinate θ is ln p, or α
        itself, whose ln-scale is 1/α)."""
        names, sd = [], []
        for name, width in sorted(self.half_widths(design).items()):
            names.append(name)
            sd.append(width * _UNIT_STD[self.distribution] / design.value(name))
        blocks = [np.diag(np.square(sd))]
        if self.covariance is not None:
            fit_names, cov = self.covariance.matrix(design)
            to_log = np.array([1.0 if parameter(n).log else 1.0 / design.value(n) for n in fit_names])
            names += list(fit_names)
            blocks.append(cov * np.outer(to_log, to_log))
        return tuple(names), linalg.block_diag(*blocks)


@dataclass(frozen=True)
class Band:
    """A tolerance band on a grid: the nominal design's |K| and η, the samples' percentiles of
    both (one array per percentile), their standard deviations, and the first-order standard
    deviations for the check."""

    percentiles: tuple[float, ...]
    magnitude: dict[float, np.ndarray]
    loss_factor: dict[float, np.ndarray]
    nominal_magnitude: np.ndarray
    nominal_loss_factor: np.ndarray
    std_magnitude: np.ndarray
    std_loss_factor: np.ndarray
    first_order_magnitude: np.ndarray
    first_order_loss_factor: np.ndarray
    samples: int
    seed: int
    distribution: str


def band(design: Design, frequency_hz, amplitude, tolerances: Tolerances, **kwargs) -> Band:
    """The band of ``design`` over the points (``frequency_hz``, ``amplitude`` broadcast) under
    ``tolerances``. ``kwargs`` go to :func:`core.bushing.stiffness_points` (slices, route).
    Raises :class:`ToleranceError` for tolerances that cannot be used or a band too large."""
    f, x = np.asarray(frequency_hz, float), np.asarray(amplitude, float)
    shape = np.broadcast_shapes(f.shape, x.shape)
    points = int(np.prod(shape))
    if tolerances.samples * points > MAX_EVALUATIONS:
        raise ToleranceError("", f"{tolerances.samples} samples × {points} points is more than "
                             f"{MAX_EVALUATIONS:.3g} evaluations: use fewer samples or a coarser grid",
                             TOO_LARGE)
    nominal = np.broadcast_to(stiffness_points(design, f, x, **kwargs), shape)
    k = sample_stiffness(design, tolerances.draws(design), f, x, **kwargs)
    magnitude, eta = np.abs(k), loss_factor(k)
    q = tolerances.percentiles
    mq, eq = np.percentile(magnitude, q, axis=0), np.percentile(eta, q, axis=0)
    first = first_order(design, f, x, tolerances, **kwargs)
    return Band(tuple(q), dict(zip(q, mq)), dict(zip(q, eq)), np.abs(nominal), loss_factor(nominal),
                magnitude.std(axis=0), eta.std(axis=0), first[0], first[1], tolerances.samples, tolerances.seed,
                tolerances.distribution)


def _refused(exc: Exception, sample: int | None = None) -> ToleranceError:
    """The band's refusal of a sample (numbered from 1) or of some sample the model refuses."""
    where = "" if sample is None else f"sample {sample + 1}: "
    return ToleranceError("", f"{where}within these tolerances the bushing leaves what the model computes: "
                          f"{exc}", OUT_OF_RANGE)


def sample_stiffness(design: Design, draws: list[dict[str, float]], frequency_hz, amplitude,
                     **kwargs) -> np.ndarray:
    """K of every sample, ``design`` with each of ``draws``' values, at the points
    (``frequency_hz``, ``amplitude`` broadcast, Hz and m or rad): shape (samples, *points), in N/m
    or N·m/rad. ``kwargs`` go to :func:`core.bushing.stiffness_points` (slices, route). All samples
    at once where the route is the single equivalent modulus (:func:`_closed_form_samples`), else
    sample by sample. Raises :class:`ToleranceError` for a sample the model refuses."""
    f, x = np.asarray(frequency_hz, float), np.asarray(amplitude, float)
    shape = np.broadcast_shapes(f.shape, x.shape)
    try:
        k = _closed_form_samples(design, draws, f, x, shape, **kwargs)
    except ToleranceError:
        raise
    except (ValueError, ArithmeticError) as exc:
        raise _refused(exc) from None
    if k is None:  # effects, slices or the time-domain route: each sample by the general route
        k = np.empty((len(draws), *shape), dtype=complex)
        for i, values in enumerate(draws):
            try:
                k[i] = stiffness_points(design.replace(**values), f, x, **kwargs)
            except (ValueError, ArithmeticError) as exc:
                raise _refused(exc, i) from None
    return k


def _closed_form_samples(design: Design, draws: list[dict[str, float]], f, x, shape, slices=1,
                         route: str = "analytic") -> np.ndarray | None:
    """Every sample's K at once, shape (samples, *shape), by the model's own eqs 14–18 over arrays
    of parameters: :func:`core.bushing.equivalent_stiffness` of
    :func:`core.material.equivalent_modulus` with S, c and the material one value per sample, the
    numbers :func:`core.bushing.stiffness_points` gives one design at a time. None where that is
    not the route (effects, slices, the time domain): the caller then computes sample by sample.
    Raises ValueError for a sample whose geometry the model refuses, :class:`ToleranceError` for
    one whose strain :func:`core.bushing.check_strain` refuses."""
    if design.effects or slices != 1 or route != "analytic":
        return None
    geometry_varies = any(name in draws[0] for name in GEOMETRY) if draws else False
    if geometry_varies and bulk_correction(design) is not None:
        return None  # the bulk modulus's factor depends on each sample's geometry: design by design
    n, ones = len(draws), (1,) * len(shape)

    def column(name: str) -> np.ndarray:
        if draws and name in draws[0]:
            return np.array([d[name] for d in draws]).reshape((n, *ones))
        return np.full((n, *ones), design.value(name))

    if geometry_varies:
        s, c = _sample_factors(design.mode, design.shape, tuple(
            tuple(d.get(name, design.value(name)) for name in GEOMETRY) for d in draws))
        # the model's strain check on the sample of the largest strain factor (the largest
        # strains); the nominal design's was checked by the band
        widest = int(np.argmax(c))
        try:
            check_strain(design.replace(**{p: v for p, v in draws[widest].items() if p in GEOMETRY}), x)
        except ValueError as exc:
            raise _refused(exc, widest) from None
        s, c = (v.reshape((n, *ones)) for v in (s, c))
    else:
        s, c = factors(design)
    # Material's fields, each one value per sample: equivalent_modulus broadcasts over them
    material = SimpleNamespace(**{name: column(name) for name in MATERIAL})
    k = np.broadcast_to(equivalent_stiffness(functools.partial(equivalent_modulus, material), s, c, f, x,
                                             bulk_correction(design)), (n, *shape))
    if not np.all(np.isfinite(k)):
        raise ValueError("the stiffness of a sample is not finite")
    return np.array(k)


@functools.lru_cache(maxsize=8)
def _sample_factors(mode: str, shape: str | None, geometries: tuple) -> tuple[np.ndarray, np.ndarray]:
    """The shape and strain factors (S, c) of each sampled geometry (a, b, L) in ``mode`` and
    ``shape``: kept for the next band of the same draws (an explorer view draws three, and a
    change of the material leaves them as they are)."""
    pairs = []
    for a, b, length in geometries:
        g = Geometry(a, b, length)
        pairs.append((shape_factor(g, mode, shape), strain_factor(g, mode, shape)))
    s, c = zip(*pairs)
    return np.array(s), np.array(c)


def first_order(design: Design, frequency_hz, amplitude, tolerances: Tolerances, **kwargs):
    """The standard deviations of |K| and η by first-order propagation, σ² = g Σ gᵀ (g the
    derivatives in ln p, Σ the draws' covariance in ln p)."""
    names, cov = tolerances.covariance_of_draws(design)
    shape = np.broadcast_shapes(np.shape(frequency_hz), np.shape(amplitude))
    if not names:
        return np.zeros(shape), np.zeros(shape)
    d = log_derivatives(design, frequency_hz, amplitude, names, **kwargs)
    out = []
    for j in (0, 1):
        g = np.stack([np.broadcast_to(d[n][j], shape) for n in names], axis=-1)
        out.append(np.sqrt(np.maximum(np.einsum("...i,ij,...j->...", g, cov, g), 0.0)))
    return out[0], out[1]


def band_columns(b: Band) -> dict[str, np.ndarray]:
    """The percentile columns ``magnitude_p5``, …, ``loss_factor_p95`` (flattened)."""
    def tag(q: float) -> str:
        return f"{q:g}".replace(".", "_")
    out = {f"magnitude_p{tag(q)}": v.ravel() for q, v in b.magnitude.items()}
    out.update({f"loss_factor_p{tag(q)}": v.ravel() for q, v in b.loss_factor.items()})
    return out
