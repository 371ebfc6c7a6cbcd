"""The discrepancy workflow: where model and measurement disagree, which effect of the
library is missing, and the gap shrinking as it is added.

1. Fit the baseline (the design's geometry is known; the parameters of its branches and of any
   effects it already carries are fitted).
2. Describe the misfit over the (frequency, amplitude) plane in plain words (:func:`describe`).
3. Fit every candidate extension (an effect of :data:`core.effects.EFFECTS` not yet in the model,
   or a branch the baseline lacks) and rank them by the Bayesian information criterion
   BIC = N ln(RSS/N) + k ln N over the N real residuals (real and imaginary parts of the relative
   complex misfit, the gap's own terms). The best candidate is added when
   * its BIC drop exceeds :data:`BIC_THRESHOLD` (10: "very strong" evidence on Kass and
     Raftery's scale; a parameter fitted to pure noise gains about 1 against a ln N ≈ 6 penalty),
   * and it explains the misfit: it leaves at most a fifth of the misfit above the noise
     (:data:`EXPLAINED_FRACTION`), or no more than the noise estimate's own spread
     (:data:`NOISE_TOLERANCE`). An effect that only leans against a misfit of another shape
     (one outside the library) lowers the BIC too, but leaves most of it: it is not named.
   If no single candidate explains the misfit, pairs of candidates are fitted together (two
   effects hidden at once interact through the refitted baseline, so neither alone need explain
   much); a pair is added when it explains the misfit and each member is needed.
4. Repeat until nothing passes. If the misfit left is still above the noise
   (:data:`NOISE_RATIO`), it is reported as unexplained, with where it is.

The noise is estimated from the data, model-free in the sense that only the roughness of the
residuals counts: at each point inside a run of three (same amplitude along ln f, or same
frequency along ln amplitude) the residual minus the linear interpolation of its neighbours has,
for white noise of complex variance s², variance s² (1 + w₀² + w₂²). A smooth model misfit drops
out to first order, and the smallest estimate over the models fitted is kept.

A branch the baseline lacks is held at a value with no effect on any stiffness (:data:`OFF`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from .bushing import stiffness_points
from .data import MeasuredStiffness, loss_factor
from .design import Design
from .effects import EFFECTS
from .fit import (
    FitResult,
    fit_global,
    gap,
    parameter,
    parameter_values,
    relative_residual,
    with_values,
)
from .material import ConvergenceError

BRANCHES = ("elastic", "fractional", "friction")
BRANCH_PARAMETERS = {
    "elastic": ("shear_modulus",),
    "fractional": ("fractional_coefficient", "fractional_order"),
    "friction": ("friction_stress_max", "friction_strain_half"),
}
# a branch switched off: its modulus 1e-30 Pa, thirty orders below any rubber's
OFF = {"shear_modulus": 1e-30, "fractional_coefficient": 1e-30, "friction_stress_max": 1e-30}
BIC_THRESHOLD = 10.0
EXPLAINED_FRACTION = 0.8  # an effect is named when it explains 80 % of the misfit above the noise
NOISE_TOLERANCE = 0.15  # … or leaves no more than 15 % of the noise's variance (its estimate's spread)
NOISE_RATIO = 1.3  # a mean squared misfit above 1.3 × the noise's is "above the noise"
PAIR_POOL = 4  # pairs are sought among the four best single candidates
MAX_FOLDS, HELD_OUT_BANDS = 12, 5  # held-out folds: single values up to 12, else 5 bands
PRECISION = 1e-6  # relative misfits below this are numerical, not measured
GRID_1D, GRID_2D = 16, 9  # starting-value grids of a candidate's parameters
BASELINE_STARTS = 8

Progress = Callable[[float, str], None]


# --------------------------------------------------------------------------------------------
# The model: a design and the branches it has
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Model:
    """A design with a subset of the thesis' branches (the others held at :data:`OFF`)."""

    design: Design
    branches: tuple[str, ...] = BRANCHES

    @property
    def parts(self) -> tuple[str, ...]:
        """Branches and effects: what the model has."""
        return (*self.branches, *(eid for eid, _ in self.design.effects))

    @property
    def free(self) -> tuple[str, ...]:
        names = [p for b in self.branches for p in BRANCH_PARAMETERS[b]]
        names += [f"{eid}.{p}" for eid, params in self.design.effects for p, _ in params]
        return tuple(names)

    def add(self, effect_id: str, values: dict[str, float]) -> Model:
        if EFFECTS[effect_id].branch:
            branches = tuple(b for b in BRANCHES if b in self.branches or b == effect_id)
            return Model(with_values(self.design, values), branches)
        effects = {**self.design.effect_parameters, effect_id: values}
        return Model(self.design.replace(effects=effects), self.branches)


def baseline_model(design: Design, branches: Iterable[str] = BRANCHES) -> Model:
    branches = tuple(branches)
    unknown = [b for b in branches if b not in BRANCHES]
    if unknown or not branches:
        raise ValueError(f"baseline: give one or more of {', '.join(BRANCHES)}, got {','.join(branches) or 'none'}")
    off = {p: OFF[p] for b in BRANCHES if b not in branches for p in BRANCH_PARAMETERS[b] if p in OFF}
    return Model(with_values(design, off), tuple(b for b in BRANCHES if b in branches))


def candidates(model: Model) -> list[str]:
    """The effects that can extend ``model``: not in it, whatever they act on present, nothing
    they exclude present."""
    parts = set(model.parts)
    out = []
    for eid, effect in EFFECTS.items():
        if eid in parts or any(x in parts for x in effect.excludes):
            continue
        if effect.requires and not any(r in parts for r in effect.requires):
            continue
        out.append(eid)
    return out


# --------------------------------------------------------------------------------------------
# Misfit statistics
# --------------------------------------------------------------------------------------------


def bic(residual: np.ndarray, n_parameters: int) -> float:
    """BIC over the real and imaginary parts of the residual. A misfit below
    :data:`PRECISION` (relative) counts as none: the models are computed to about 1e-11, and
    differences below that are the optimiser's, not the data's."""
    n = 2 * residual.size
    rss = float(np.sum(np.abs(residual) ** 2))
    return n * math.log(max(rss / n, PRECISION**2)) + n_parameters * math.log(n)


def _runs(data: MeasuredStiffness):
    """Index triples (i, j, k) of neighbours along ln f at one amplitude and along ln amplitude
    at one frequency, with their log coordinates. Data on no such lines (scattered points) fall
    back on each point's two nearest neighbours in (ln f, ln amplitude), scaled to their ranges,
    weighted equally."""
    lf, la = np.log(data.frequency_hz), np.log(data.amplitude)
    triples = []
    for along, across in ((lf, la), (la, lf)):
        keys = np.round(across, 9)
        for key in np.unique(keys):
            idx = np.flatnonzero(keys == key)
            idx = idx[np.argsort(along[idx], kind="stable")]
            x = along[idx]
            for n in range(1, idx.size - 1):
                if x[n + 1] > x[n - 1]:
                    triples.append((idx[n - 1], idx[n], idx[n + 1], x[n - 1], x[n], x[n + 1]))
    if triples or lf.size < 3:
        return triples
    pts = np.column_stack([(v - v.min()) / (np.ptp(v) or 1.0) for v in (lf, la)])
    dist = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=-1)
    np.fill_diagonal(dist, np.inf)
    near = np.argsort(dist, axis=1)[:, :2]
    return [(int(a), j, int(b), 0.0, 1.0, 2.0) for j, (a, b) in enumerate(near)]


def noise_variance(residual: np.ndarray, data: MeasuredStiffness, runs=None) -> float | None:
    """Complex noise variance s² (E|n|²) estimated from the residual's roughness (at least
    :data:`PRECISION`²); ``None`` when the data have no run of three points to judge it by."""
    runs = _runs(data) if runs is None else runs
    if not runs:
        return None
    i, j, k, x0, x1, x2 = (np.array(c) for c in zip(*runs))
    i, j, k = i.astype(int), j.astype(int), k.astype(int)
    w0 = (x2 - x1) / (x2 - x0)
    w2 = (x1 - x0) / (x2 - x0)
    e = residual[j] - (w0 * residual[i] + w2 * residual[k])
    return max(float(np.mean(np.abs(e) ** 2 / (1.0 + w0**2 + w2**2))), PRECISION**2)


# --------------------------------------------------------------------------------------------
# Plain words: where the misfit is
# --------------------------------------------------------------------------------------------


def _bins(values: np.ndarray, most: int = 8) -> tuple[np.ndarray, list[tuple[float, float]]]:
    """Bin labels over ln(values): the distinct values if few, else equal-count bins."""
    distinct = np.unique(np.round(values, 12))
    if distinct.size <= most:
        labels = np.searchsorted(distinct, np.round(values, 12))
        return labels, [(v, v) for v in distinct]
    edges = np.quantile(np.log(values), np.linspace(0, 1, most + 1))
    labels = np.clip(np.searchsorted(edges, np.log(values), side="right") - 1, 0, most - 1)
    ranges = []
    for b in range(most):
        sel = values[labels == b]
        ranges.append((float(sel.min()), float(sel.max())) if sel.size else (math.nan, math.nan))
    return labels, ranges


def _fmt_freq(f: float) -> str:
    return f"{f:.3g} Hz"


def _amplitude_formatter(mode: str) -> Callable[[float], str]:
    if mode == "axial":
        return lambda x: f"{x * 1e3:.3g} mm"
    return lambda x: f"{x:.3g} rad"


def _growth(centres: np.ndarray, means: np.ndarray, what: str) -> str:
    """'growing with frequency squared' and the like, from a power-law fit of |misfit|."""
    if centres.size < 2 or np.ptp(np.log(centres)) < math.log(2.0):
        return ""
    p = np.polyfit(np.log(centres), np.log(np.abs(means)), 1)[0]
    if p > 1.6:
        return f"growing with {what} squared" if p < 2.6 else f"growing steeply with {what} (as {what}^{p:.1f})"
    if p > 0.6:
        return f"growing in proportion to {what}" if p < 1.4 else f"growing with {what} (as {what}^{p:.1f})"
    if p > 0.2:
        return f"growing slowly with {what}"
    if p < -0.2:
        return f"shrinking as the {what} grows"
    return ""


def _extent(ranges, significant: np.ndarray, fmt, noun: str) -> str:
    """'from 60 Hz up', 'at every amplitude', 'from … to …' from the significant bins."""
    idx = np.flatnonzero(significant)
    n = len(ranges)
    lo, hi = idx.min(), idx.max()
    if lo == hi and ranges[lo][0] == ranges[lo][1]:
        return f"at {fmt(ranges[lo][0])}"
    if lo == 0 and hi == n - 1:
        return f"at every {noun}"
    if hi == n - 1:
        return f"from {fmt(ranges[lo][0])} up"
    if lo == 0:
        return f"up to {fmt(ranges[hi][1])}"
    return f"from {fmt(ranges[lo][0])} to {fmt(ranges[hi][1])}"


def _profile(values, labels, n_bins, scale, mask):
    """Mean of ``values`` per bin over the points in ``mask``, and its standard error."""
    means, se = np.full(n_bins, np.nan), np.full(n_bins, np.inf)
    for b in range(n_bins):
        sel = values[(labels == b) & mask]
        if sel.size:
            means[b] = sel.mean()
            se[b] = scale / math.sqrt(sel.size)
    return means, se


def _region(values, axes, scale, level):
    """The frequency and amplitude bins where ``values`` is significantly positive: the
    frequency profile over all points, the amplitude profile over the points in the significant
    frequency bins, then the frequency profile again over those amplitudes."""
    (fl, fr), (al, ar) = axes
    everywhere = np.ones(values.size, bool)
    fm, fse = _profile(values, fl, len(fr), scale, everywhere)
    f_sig = fm > level * fse
    if not f_sig.any():
        return None
    am, ase = _profile(values, al, len(ar), scale, f_sig[fl])
    a_sig = am > level * ase
    if not a_sig.any():
        return None
    fm, fse = _profile(values, fl, len(fr), scale, a_sig[al])
    f_sig = fm > level * fse
    if not f_sig.any():
        return None
    return (fm, f_sig), (am, a_sig)


def describe(data: MeasuredStiffness, model_k: np.ndarray, mode: str, noise_sd: float,
             level: float = 3.0) -> str:
    """The misfit in plain words: for |K| and the loss factor, which way the model is off,
    where on the frequency and amplitude axes, and how it grows. ``noise_sd`` is the standard
    deviation of the relative noise in one part (real or imaginary).

    A bin of the frequency (amplitude) axis counts where the mean misfit over it is more than
    ``level`` standard errors from zero (see :func:`_region`). If nothing counts at 3 standard
    errors, 2 are tried before the misfit is called noise.
    """
    quantities = (
        ("|K|", np.abs(model_k) / data.magnitude - 1.0, ("too stiff", "too soft"), noise_sd),
        ("loss factor", loss_factor(model_k) - data.loss_factor, ("too high", "too low"),
         noise_sd * float(np.sqrt(np.mean(1.0 + data.loss_factor**2)))),
    )
    axes = (_bins(data.frequency_hz), _bins(data.amplitude))
    centres = [np.array([math.sqrt(lo * hi) for lo, hi in ranges]) for _, ranges in axes]
    fmt_amp = _amplitude_formatter(mode)
    phrases = []
    for name, misfit, (over, under), scale in quantities:
        parts = []
        for sign, word in ((1.0, over), (-1.0, under)):
            region = _region(sign * misfit, axes, scale, level)
            if region is None:
                continue
            (fm, f_sig), (am, a_sig) = region
            size = float(np.max(fm[f_sig]))
            text = (f"model {word} {_extent(axes[0][1], f_sig, _fmt_freq, 'frequency')}, "
                    f"{_extent(axes[1][1], a_sig, fmt_amp, 'amplitude')}")
            growth = [g for g in (_growth(centres[0][f_sig], fm[f_sig], "frequency"),
                                  _growth(centres[1][a_sig], am[a_sig], "amplitude")) if g]
            if growth:
                text += ", " + " and ".join(growth)
            amount = f"{size:.3f}" if name == "loss factor" else f"{100 * size:.2g} %"
            parts.append((size / scale, f"{text} (by up to {amount})"))
        if parts:
            parts.sort(reverse=True)
            phrases.append((parts[0][0], f"{name}: " + "; ".join(p for _, p in parts)))
    if not phrases:
        if level > 2.0:
            return describe(data, model_k, mode, noise_sd, level=2.0)
        return "no misfit above the noise."
    phrases.sort(reverse=True)
    return ". ".join(p for _, p in phrases) + "."


# --------------------------------------------------------------------------------------------
# The workflow
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Fitted:
    """A model fitted to the data, with its residual statistics."""

    model: Model
    fit: FitResult
    stiffness: np.ndarray  # the model's complex K at the data points
    residual: np.ndarray  # relative_residual(stiffness, data.stiffness)
    bic: float

    @property
    def design(self) -> Design:
        return self.fit.design

    @property
    def gap(self) -> float:
        return self.fit.gap

    @property
    def mean_square(self) -> float:
        return float(np.mean(np.abs(self.residual) ** 2))


@dataclass(frozen=True)
class Step:
    effect: str
    title: str
    where: str
    bic_drop: float
    explained_fraction: float | None
    parameters: dict[str, float]
    gap_before: float
    gap_after: float
    candidates: dict[str, float]  # every candidate's BIC drop at this step
    extra: dict = field(default_factory=dict)  # more evidence (the partner of a pair)

    def report(self) -> dict:
        evidence = {"bic_drop": self.bic_drop, "candidates_bic_drop": self.candidates, **self.extra}
        if self.explained_fraction is not None:
            evidence["explained_fraction"] = self.explained_fraction
        return {"effect": self.effect, "title": self.title, "where": self.where, "evidence": evidence,
                "parameters": self.parameters, "gap_before": self.gap_before, "gap_after": self.gap_after}


@dataclass(frozen=True)
class Diagnosis:
    data: MeasuredStiffness
    baseline: Fitted
    steps: list[Step]
    final: Fitted
    noise_variance: float | None
    unexplained: bool
    where_baseline: str
    where_remaining: str
    held_out: dict = field(default_factory=dict)

    @property
    def added(self) -> list[str]:
        return [s.effect for s in self.steps]

    @property
    def noise_gap(self) -> float | None:
        """The gap pure noise of the estimated size gives."""
        return None if self.noise_variance is None else math.sqrt(self.noise_variance)

    def report(self) -> dict:
        """The report of docs/files.md's ``bushing diagnose``."""
        out = {
            "baseline": list(self.baseline.model.branches),
            "added": self.added,
            "steps": [s.report() for s in self.steps],
            "gap_baseline": self.baseline.gap,
            "gap_final": self.final.gap,
            "unexplained": self.unexplained,
            "where_baseline": self.where_baseline,
            "where_remaining": self.where_remaining,
            "noise_gap": self.noise_gap,
            "points": len(self.data),
            "bic_threshold": BIC_THRESHOLD,
            "design": self.final.design.to_dict(),
        }
        if self.baseline.design.effects:
            out["baseline_effects"] = [eid for eid, _ in self.baseline.design.effects]
        if self.held_out:
            out["held_out"] = self.held_out
        return out

    def to_json(self) -> str:
        """The report as JSON text (strict: no NaN)."""
        return json.dumps(self.report(), indent=2, allow_nan=False) + "\n"

    def predictions(self) -> dict[str, np.ndarray]:
        """Per data row: the baseline's and the final model's |K| and loss factor."""
        kb, kf = self.baseline.stiffness, self.final.stiffness
        return {
            "frequency_hz": self.data.frequency_hz,
            "amplitude": self.data.amplitude,
            "baseline_magnitude": np.abs(kb),
            "baseline_loss_factor": loss_factor(kb),
            "final_magnitude": np.abs(kf),
            "final_loss_factor": loss_factor(kf),
        }


def _fit(model: Model, data: MeasuredStiffness, **kwargs) -> Fitted:
    result = fit_global(model.design, data, free=model.free, **kwargs)
    k = stiffness_points(result.design, data.frequency_hz, data.amplitude)
    residual = relative_residual(k, data.stiffness)
    return Fitted(Model(result.design, model.branches), result, k, residual, bic(residual, len(model.free)))


def _grid_values(names: list[str], n: int) -> list[dict[str, float]]:
    axes = []
    for name in names:
        spec = parameter(name)
        lo, hi = spec.bounds
        axes.append(np.geomspace(lo, hi, n + 2)[1:-1] if spec.log else np.linspace(lo, hi, n + 2)[1:-1])
    mesh = np.meshgrid(*axes, indexing="ij")
    return [dict(zip(names, (float(m.flat[i]) for m in mesh))) for i in range(mesh[0].size)]


def _candidate_starts(current: Fitted, effect_id: str, data: MeasuredStiffness, keep: int = 2):
    """Starting values for a candidate's parameters: the best ``keep`` of a grid across their
    fitting ranges, the rest of the model held at its fitted values."""
    effect = EFFECTS[effect_id]
    names = [p.name if effect.branch else f"{effect_id}.{p.name}" for p in effect.parameters]
    if not names:
        return [{}]
    grid = _grid_values(names, GRID_1D if len(names) == 1 else GRID_2D)
    scored = []
    for values in grid:
        trial = current.model.add(effect_id, {n.rpartition(".")[2]: v for n, v in values.items()})
        try:
            k = stiffness_points(trial.design, data.frequency_hz, data.amplitude)
        except (ValueError, ArithmeticError, ConvergenceError):
            continue
        r = relative_residual(k, data.stiffness)
        if np.all(np.isfinite(r)):
            scored.append((float(np.sum(np.abs(r) ** 2)), values))
    scored.sort(key=lambda s: s[0])
    return [v for _, v in scored[:keep]] or [grid[len(grid) // 2]]


def _fit_candidate(current: Fitted, effect_id: str, data: MeasuredStiffness) -> Fitted | None:
    starts = _candidate_starts(current, effect_id, data)
    model = current.model.add(effect_id, {n.rpartition(".")[2]: v for n, v in starts[0].items()})
    base = parameter_values(current.design)
    try:
        return _fit(model, data, initial=[{**base, **s} for s in starts])
    except (ValueError, ArithmeticError, ConvergenceError):
        return None  # the extended model cannot be fitted to these data: not a candidate


def _explains(before: Fitted, after: Fitted, noise: float | None) -> tuple[bool, float | None]:
    """Whether ``after`` leaves at most a fifth of ``before``'s misfit above the noise (or no more
    than the noise estimate's own uncertainty, :data:`NOISE_TOLERANCE`); and the fraction of the
    misfit above the noise that it explains."""
    if noise is None:
        return True, None
    excess_before = before.mean_square - noise
    left = after.mean_square - noise
    fraction = None if excess_before <= 0 else min(max((excess_before - left) / excess_before, 0.0), 1.0)
    return left <= max((1.0 - EXPLAINED_FRACTION) * excess_before, NOISE_TOLERANCE * noise), fraction


def _held_out(data: MeasuredStiffness, fits: dict[str, Fitted]) -> dict:
    """Leave one amplitude out (or, with fewer than three amplitudes, one frequency): refit each
    model on the rest from its fitted values, predict the points left out; the gap over them.
    With more than :data:`MAX_FOLDS` distinct values (scattered data), bands of equal count are
    left out instead of single values."""
    for axis, values in (("amplitude", data.amplitude), ("frequency", data.frequency_hz)):
        levels = np.unique(values)
        if levels.size >= 3:
            break
    else:
        return {}
    what = f"one {axis} at a time"
    if levels.size > MAX_FOLDS:
        edges = np.quantile(values, np.linspace(0, 1, HELD_OUT_BANDS + 1))
        values = np.clip(np.searchsorted(edges, values, side="right") - 1, 0, HELD_OUT_BANDS - 1)
        levels = np.unique(values)
        what = f"one {axis} band of {HELD_OUT_BANDS} at a time"
    out: dict = {"left_out": what, "folds": int(levels.size)}
    done: dict[int, float] = {}
    for label, fitted in fits.items():
        if id(fitted) in done:  # the same model (nothing was added): the same figure
            out[f"gap_{label}"] = done[id(fitted)]
            continue
        predicted = np.empty(len(data), dtype=complex)
        for level in levels:
            held = values == level
            try:
                refit = fit_global(fitted.design, data.select(~held), free=fitted.model.free, initial=[{}])
            except (ValueError, ArithmeticError, ConvergenceError):
                return {}  # too few points left to refit on: no held-out figure
            predicted[held] = stiffness_points(refit.design, data.frequency_hz[held], data.amplitude[held])
        out[f"gap_{label}"] = done[id(fitted)] = gap(predicted, data.stiffness)
    return out


def _lower(noise: float | None, estimate: float | None) -> float | None:
    if estimate is None:
        return noise
    return estimate if noise is None else min(noise, estimate)


def _best_pair(current: Fitted, tried: dict[str, Fitted], drops: dict[str, float],
               data: MeasuredStiffness, say: Progress, done: float):
    """The best pair of candidates fitted together, each needed (the pair beats either alone by
    more than the threshold); ``None`` if no pair is."""
    ranked = [eid for eid in sorted(drops, key=drops.get, reverse=True) if drops[eid] > 0][:PAIR_POOL]
    best = None
    for i, a in enumerate(ranked):
        for b in ranked[i + 1:]:
            if b not in candidates(tried[a].model):
                continue
            say(done, f"trying {EFFECTS[a].title.lower()} with {EFFECTS[b].title.lower()}")
            joint = _fit_candidate(tried[a], b, data)
            if joint is None:
                continue
            needed = min(tried[a].bic, tried[b].bic) - joint.bic
            better = best is None or joint.bic < best[1].bic
            if needed > BIC_THRESHOLD and current.bic - joint.bic > BIC_THRESHOLD and better:
                best = ((a, b), joint)
    return best


def diagnose(design: Design, data: MeasuredStiffness, *, baseline: Iterable[str] = BRANCHES,
             held_out: bool = True, progress: Progress | None = None) -> Diagnosis:
    """Run the discrepancy workflow on ``data`` from ``design`` (its geometry known, its
    parameters the starting values) with the ``baseline`` branches. Returns a :class:`Diagnosis`.
    """
    say = progress or (lambda fraction, message: None)
    runs = _runs(data)
    say(0.0, "fitting the baseline")
    current = _fit(baseline_model(design, baseline), data, starts=BASELINE_STARTS)
    first = current
    noise = noise_variance(current.residual, data, runs)
    accepted: list[tuple] = []  # (effect, before, after, drops, fitted values from, evidence)
    done = 0.1  # progress: each round of candidates takes half of what is left up to 0.8
    while True:
        names = candidates(current.model)
        tried: dict[str, Fitted] = {}
        span = (0.8 - done) / 2
        for i, eid in enumerate(names):
            say(done + span * i / len(names), f"step {len(accepted) + 1}: trying {EFFECTS[eid].title.lower()}")
            fitted = _fit_candidate(current, eid, data)
            if fitted is not None:
                tried[eid] = fitted
                noise = _lower(noise, noise_variance(fitted.residual, data, runs))
        done += span
        drops = {eid: current.bic - f.bic for eid, f in tried.items()}
        if not drops:
            break
        best = max(drops, key=drops.get)
        if drops[best] > BIC_THRESHOLD and _explains(current, tried[best], noise)[0]:
            accepted.append((best, current, tried[best], drops, tried[best], {}))
            current = tried[best]
            continue
        # no single effect explains the misfit: two that act together may (their fits interact
        # through the refitted baseline, so neither alone need explain much)
        pair = _best_pair(current, tried, drops, data, say, done)
        if pair is None:
            break
        (first_id, second_id), joint = pair
        noise = _lower(noise, noise_variance(joint.residual, data, runs))
        if not _explains(current, joint, noise)[0]:
            break
        accepted.append((first_id, current, tried[first_id], drops, joint, {"found_with": second_id}))
        accepted.append((second_id, tried[first_id], joint, {second_id: tried[first_id].bic - joint.bic}, joint,
                         {"found_with": first_id}))
        current = joint
    remaining = noise is not None and current.mean_square > NOISE_RATIO * noise

    # the words, with the final noise estimate: each misfit described once
    sd = math.sqrt((noise or current.mean_square) / 2.0)
    words: dict[int, str] = {}

    def where(fitted: Fitted) -> str:
        if id(fitted) not in words:
            words[id(fitted)] = describe(data, fitted.stiffness, design.mode, sd)
        return words[id(fitted)]

    steps = []
    for eid, before, after, step_drops, values_from, evidence in accepted:
        effect = EFFECTS[eid]
        values = parameter_values(values_from.design)
        params = {p.name: values[p.name if effect.branch else f"{eid}.{p.name}"] for p in effect.parameters}
        steps.append(Step(eid, effect.title, where(before), before.bic - after.bic, _explains(before, after, noise)[1],
                          params, before.gap, after.gap, step_drops, evidence))
    held = {}
    if held_out:
        say(0.85, "checking on held-out data")
        held = _held_out(data, {"baseline": first, "final": current})
    say(1.0, "done")
    return Diagnosis(data, first, steps, current, noise, remaining, where(first),
                     where(current) if remaining else "no misfit above the noise.", held)


def summary(diagnosis: Diagnosis) -> str:
    """The diagnosis in plain words, a few lines (the command line's summary)."""
    lines = [f"baseline ({', '.join(diagnosis.baseline.model.branches)}): gap {diagnosis.baseline.gap:.4g}"]
    if diagnosis.noise_gap is not None:
        lines[0] += f" (noise alone gives about {diagnosis.noise_gap:.4g})"
    lines.append(f"  where it disagrees: {diagnosis.where_baseline}")
    for n, s in enumerate(diagnosis.steps, 1):
        params = ", ".join(f"{k} = {v:.4g}" for k, v in s.parameters.items()) or "no parameters"
        lines.append(f"step {n}: add {s.effect} ({s.title}): {params}; BIC drop {s.bic_drop:.1f}; "
                     f"gap {s.gap_before:.4g} -> {s.gap_after:.4g}")
    if not diagnosis.steps:
        lines.append("no effect of the library is needed: nothing added")
    if diagnosis.unexplained:
        lines.append(f"unexplained: a misfit above the noise remains, no effect of the library explains it: "
                     f"{diagnosis.where_remaining}")
    held = diagnosis.held_out
    if held:
        lines.append(f"held out ({held['left_out']}): gap {held['gap_baseline']:.4g} baseline, "
                     f"{held['gap_final']:.4g} final")
    return "\n".join(lines) + "\n"
