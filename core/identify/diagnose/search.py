"""The search: fit the baseline, try every candidate effect (and pairs), accept what the data
support, check on held-out data."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace

import numpy as np

from ...data import MAX_FIT_POINTS, MeasuredStiffness
from ...design import Design
from ...effects import effect_of, effect_title, split_id
from ...material import ConvergenceError
from ...registry import parameter, parameter_values
from ...residuals import gap, gaps_by_mode, relative_residual
from ..fit import fit_global, model_stiffness
from .model import BRANCHES, Model, baseline_model, candidates, fitting_names
from .report import Diagnosis, Fitted, Step
from .statistics import (
    BIC_THRESHOLD,
    NOISE_RATIO,
    PRECISION,
    bic,
    explains,
    lower,
    noise_variance,
    runs,
)
from .words import describe

PAIR_POOL = 4  # pairs are sought among the four best single candidates
MAX_FOLDS, HELD_OUT_BANDS = 12, 5  # held-out folds: single values up to 12, else 5 bands
GRID_1D, GRID_2D = 16, 9  # starting-value grids of a candidate's parameters
BASELINE_STARTS = 8

Progress = Callable[[float, str], None]


@dataclass(frozen=True)
class Accepted:
    """An effect the search accepted: the model before and after it, every candidate's BIC drop
    at that step, the fit whose values it reports (a pair's joint fit) and more evidence."""

    effect: str
    before: Fitted
    after: Fitted
    drops: dict[str, float]
    values_from: Fitted
    evidence: dict = field(default_factory=dict)


def _fit(model: Model, data: MeasuredStiffness, **kwargs) -> Fitted:
    result = fit_global(model.design, data, free=model.free, **{"intervals": False, **kwargs})
    k = model_stiffness(result.design, data)
    residual = relative_residual(k, data.stiffness) * data.weight  # binned data: one point's noise
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
    names = fitting_names(effect_id)
    if not names:
        return [{}]
    grid = _grid_values(names, GRID_1D if len(names) == 1 else GRID_2D)
    scored = []
    for values in grid:
        trial = current.model.add(effect_id, {n.rpartition(".")[2]: v for n, v in values.items()})
        try:
            k = model_stiffness(trial.design, data)
        except (ValueError, ArithmeticError, ConvergenceError):
            continue
        r = relative_residual(k, data.stiffness) * data.weight
        if np.all(np.isfinite(r)):
            scored.append((float(np.sum(np.abs(r) ** 2)), values))
    scored.sort(key=lambda s: s[0])
    return [v for _, v in scored[:keep]] or [grid[len(grid) // 2]]


def _fit_candidate(current: Fitted, effect_id: str, data: MeasuredStiffness,
                   origin: dict[str, float]) -> Fitted | None:
    """``current`` extended by ``effect_id``, fitted from the best grid starts with the fitted
    material, and from the best one with ``origin``'s (the design as the user gave it): a
    baseline refit bends its material to mimic the missing effect, and can hold the extended
    fit in a wrong valley. Measured: standing waves in torsion data (Im K < 0 past 780 Hz) were
    fitted at ρ = 1072 with a gap 12 times the noise, which a spurious second effect then took
    up; from the user's material the same fit finds ρ = 1099 (the truth 1100) at the noise."""
    starts = _candidate_starts(current, effect_id, data)
    model = current.model.add(effect_id, {n.rpartition(".")[2]: v for n, v in starts[0].items()})
    base = parameter_values(current.design)
    try:
        return _fit(model, data, initial=[*({**base, **s} for s in starts), {**base, **origin, **starts[0]}])
    except (ValueError, ArithmeticError, ConvergenceError):
        return None  # the extended model cannot be fitted to these data: not a candidate


def _held_out(data: MeasuredStiffness, fits: dict[str, Fitted]) -> dict:
    """Leave one amplitude out (or, with fewer than three amplitudes, one frequency): refit each
    model on the rest from its fitted values (dense data binned by the fit), predict every
    measured point left out; the gap over them.
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
                refit = fit_global(fitted.design, data.select(~held), free=fitted.model.free, initial=[{}],
                                   intervals=False)
            except (ValueError, ArithmeticError, ConvergenceError):
                return {}  # too few points left to refit on: no held-out figure
            predicted[held] = model_stiffness(refit.design, data.select(held))
        out[f"gap_{label}"] = done[id(fitted)] = gap(predicted, data.stiffness)
    return out


def _best_pair(current: Fitted, tried: dict[str, Fitted], drops: dict[str, float],
               data: MeasuredStiffness, modes: tuple[str, ...], say: Progress, done: float,
               origin: dict[str, float]):
    """The best pair of candidates fitted together, each needed (the pair beats either alone by
    more than the threshold); ``None`` if no pair is."""
    ranked = [eid for eid in sorted(drops, key=drops.get, reverse=True) if drops[eid] > 0][:PAIR_POOL]
    best = None
    for i, a in enumerate(ranked):
        for b in ranked[i + 1:]:
            if b not in candidates(tried[a].model, modes):
                continue
            say(done, f"trying {effect_title(a).lower()} with {effect_title(b).lower()}")
            joint = _fit_candidate(tried[a], b, data, origin)
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

    Data of several modes (a `mode` column) are fitted jointly, one material for every mode,
    each mode through its own shape factor: an effect of the rubber is one set of parameters
    for all modes, and each step reports which modes support it; an effect of the test rig (an
    apparent mass) is a candidate on each mode's rig separately. At the end, the joint model is
    weighed against one material per mode: if that is much better (BIC) and the joint misfit
    is above the noise, the diagnosis says the modes disagree.
    """
    say = progress or (lambda fraction, message: None)
    measured, data = data, data.binned(MAX_FIT_POINTS)  # dense data: the search works on bins
    modes = tuple(np.unique(data.mode.astype(str))) if data.mode is not None else ()
    modes = modes if len(modes) > 1 else ()
    triples = runs(data)
    origin = parameter_values(design)  # the user's material: a second start for every candidate
    say(0.0, "fitting the baseline")
    current = _fit(baseline_model(design, baseline), data, starts=BASELINE_STARTS)
    first = current
    noise = noise_variance(current.residual, data, triples)
    accepted: list[Accepted] = []
    done = 0.1  # progress: each round of candidates takes half of what is left up to 0.8
    while True:
        names = candidates(current.model, modes)
        tried: dict[str, Fitted] = {}
        span = (0.8 - done) / 2
        for i, eid in enumerate(names):
            say(done + span * i / len(names), f"step {len(accepted) + 1}, candidate {i + 1} of {len(names)}: "
                f"{effect_title(eid).lower()}")
            fitted = _fit_candidate(current, eid, data, origin)
            if fitted is not None:
                tried[eid] = fitted
                noise = lower(noise, noise_variance(fitted.residual, data, triples))
        done += span
        drops = {eid: current.bic - f.bic for eid, f in tried.items()}
        if not drops:
            break
        best = max(drops, key=drops.get)
        if drops[best] > BIC_THRESHOLD and explains(current, tried[best], noise)[0]:
            accepted.append(Accepted(best, current, tried[best], drops, tried[best]))
            current = tried[best]
            continue
        # no single effect explains the misfit: two that act together may (their fits interact
        # through the refitted baseline, so neither alone need explain much)
        pair = _best_pair(current, tried, drops, data, modes, say, done, origin)
        if pair is None:
            break
        (first_id, second_id), joint = pair
        noise = lower(noise, noise_variance(joint.residual, data, triples))
        if not explains(current, joint, noise)[0]:
            break
        accepted.append(Accepted(first_id, current, tried[first_id], drops, joint, {"found_with": second_id}))
        accepted.append(Accepted(second_id, tried[first_id], joint, {second_id: tried[first_id].bic - joint.bic},
                                 joint, {"found_with": first_id}))
        current = joint
    # what the data say about the final model's parameters: their profiles (which may also find
    # a slightly better optimum than the search did)
    say(0.8, "profiling the final model's parameters")
    current = _fit(current.model, data, initial=[{}], intervals=True)  # least squares never climbs
    if not accepted:
        first = current
    remaining = noise is not None and current.mean_square > NOISE_RATIO * noise
    # the report's gaps are over every measured point: a model fitted to bins is evaluated there
    every: dict[int, Fitted] = {}

    def on(fitted: Fitted) -> Fitted:
        if data is measured:
            return fitted
        if id(fitted) not in every:
            every[id(fitted)] = _on(measured, fitted)
        return every[id(fitted)]

    disagreement = {}
    if modes:
        say(0.82, "weighing one material for every mode against one per mode")
        disagreement = _disagreement(current, data, measured, on(current), remaining)

    # the words, with the final noise estimate: each misfit described once
    sd = math.sqrt((noise or current.mean_square) / 2.0)
    words: dict[int, str] = {}

    def where(fitted: Fitted) -> str:
        if id(fitted) not in words:
            words[id(fitted)] = _words(data, fitted.stiffness, design.mode, sd)
        return words[id(fitted)]

    steps = []
    for a in accepted:
        effect = effect_of(a.effect)
        values = parameter_values(a.values_from.design)
        names = dict(zip((p.name for p in effect.parameters), fitting_names(a.effect)))
        params = {p: values[n] for p, n in names.items()}
        # a parameter the final profile finds undetermined has no standard error worth quoting
        vague = tuple(p for p, n in names.items() if n in current.fit.undetermined)
        errors = {p: math.nan if p in vague else a.values_from.fit.standard_errors.get(n, math.nan)
                  for p, n in names.items()}
        rig_mode = (split_id(a.effect)[1] or design.mode) if modes and effect.rig else None
        support = _support(a.before, a.after, data, on(a.before), on(a.after)) if modes else {}
        steps.append(Step(effect.id, effect.title, where(a.before), a.before.bic - a.after.bic,
                          explains(a.before, a.after, noise)[1], params, on(a.before).gap, on(a.after).gap, a.drops,
                          a.evidence, errors, rig_mode, support, vague))
    held = {}
    if held_out:
        say(0.85, "checking on held-out data")
        held = _held_out(measured, {"baseline": first, "final": current})
    say(0.95, "describing where the models miss the data")
    where_first, where_final = where(first), where(current) if remaining else "no misfit above the noise."
    say(1.0, "done")
    return Diagnosis(measured, on(first), steps, on(current), noise, remaining, where_first, where_final, held,
                     disagreement)


def _words(data: MeasuredStiffness, k: np.ndarray, mode: str, sd: float) -> str:
    """Where a model and the data disagree, in plain words; mode by mode for several."""
    if data.mode is None or len(set(data.mode)) == 1:
        return describe(data, k, mode if data.mode is None else str(data.mode[0]), sd)
    return " ".join(f"{m}: {describe(data.of_mode(m), k[data.mode == m], m, sd)}"
                    for m in np.unique(data.mode.astype(str)))


def _mode_misfit(residual: np.ndarray, rows: np.ndarray) -> float:
    """A mode's term of the BIC's misfit, n ln(RSS/n) over its real residuals."""
    n = 2 * int(rows.sum())
    return n * math.log(max(float(np.sum(np.abs(residual[rows]) ** 2)) / n, PRECISION**2))


def _support(before: Fitted, after: Fitted, data: MeasuredStiffness, before_measured: Fitted,
             after_measured: Fitted) -> dict:
    """Each mode's share of a step's evidence: the drop of its own misfit term n ln(RSS/n) over
    ``data`` (the BIC drop's data part) and its gap before and after over every measured point
    (``*_measured``: the same models there). A mode *supports* the step when its drop exceeds
    :data:`BIC_THRESHOLD`, is *against* it when its misfit grows by as much, and is *neutral*
    otherwise (its data do not see the effect)."""
    gaps = [f.fit.gap_by_mode for f in (before_measured, after_measured)]
    out = {}
    for m in np.unique(data.mode.astype(str)):
        rows = data.mode == m
        drop = _mode_misfit(before.residual, rows) - _mode_misfit(after.residual, rows)
        verdict = "supports" if drop > BIC_THRESHOLD else "against" if drop < -BIC_THRESHOLD else "neutral"
        out[m] = {"bic_drop": drop, "verdict": verdict, "gap_before": gaps[0][m], "gap_after": gaps[1][m]}
    return out


def _disagreement(current: Fitted, data: MeasuredStiffness, measured: MeasuredStiffness, current_measured: Fitted,
                  remaining: bool) -> dict:
    """One material for every mode (``current``, fitted jointly) weighed against one per mode:
    the final model refitted to each mode's data alone, its parameters that act there free.
    The modes *disagree* when the BIC drops by more than :data:`BIC_THRESHOLD` for the extra
    parameters and the joint misfit is above the noise. Empty if a mode cannot be fitted alone
    (too few points for its parameters)."""
    rss, count, alone, values = 0.0, 0, {}, {}
    for m in np.unique(data.mode.astype(str)):
        model = current.model.alone(m)
        part = data.of_mode(m)
        try:
            fit = fit_global(model.design, measured.of_mode(m), free=model.acting, initial=[{}], intervals=False)
        except (ValueError, ArithmeticError, ConvergenceError):
            return {}
        r = relative_residual(model_stiffness(fit.design, part), part.stiffness) * part.weight
        rss += float(np.sum(np.abs(r) ** 2))
        count += len(model.acting)
        fitted = parameter_values(fit.design)
        alone[m], values[m] = fit.gap, {n: fitted[n] for n in model.acting}
    n = 2 * len(data)
    separate = n * math.log(max(rss / n, PRECISION**2)) + count * math.log(n)
    drop = current.bic - separate
    return {"disagree": bool(remaining and drop > BIC_THRESHOLD), "bic_drop": drop,
            "gap_joint_by_mode": current_measured.fit.gap_by_mode, "gap_alone_by_mode": alone,
            "parameters_alone": values}


def _on(data: MeasuredStiffness, fitted: Fitted) -> Fitted:
    """``fitted`` (fitted to binned data) evaluated at every point of ``data``."""
    k = model_stiffness(fitted.design, data)
    fit = replace(fitted.fit, gap=gap(k, data.stiffness), gap_by_mode=gaps_by_mode(k, data), points=len(data))
    return Fitted(fitted.model, fit, k, relative_residual(k, data.stiffness), fitted.bic)
