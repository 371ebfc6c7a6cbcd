"""Identification of the five material parameters from measured data.

Two procedures:

* :func:`fit_global`: all five parameters to all data at once. The misfit is the complex
  relative error of stiffness, (K_model − K_data)/|K_data| (real and imaginary parts), the same
  quantity as the gap of docs/files.md, plus, when a measured loop is given, the loop force error
  relative to its RMS, weighted so that the loop counts as much as the stiffness points.
  Parameters are fitted as ln µ, ln m, α, ln σ_fmax, ln ε½ (positive by construction; α bounded
  to (0, 1]); bounded least squares (trust-region reflective) from several starting points, and
  the best is kept.
* :func:`fit_two_step`: the thesis' procedure (Paper B): the quasi-static loop gives µ, σ_fmax
  and ε½; a frequency sweep at one amplitude gives m and α; the two steps alternate until
  neither moves.

Standard errors come from the Jacobian at the optimum, cov = s² (JᵀJ)⁻¹ with s² the residual
variance, carried to the natural parameters by the delta method; the correlation matrix is that
of the fitted (log) parameters, which the monotone transforms leave unchanged to first order.
They are only the curvature at the optimum: the 95 % intervals come from the profile of each
parameter (:mod:`core.identify.uncertainty`), and a parameter whose profile stays flat to the end of its
fitting range is reported as not determined by the data (its standard error null).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..bushing import check_measured_amplitude, stiffness_points
from ..data import MAX_FIT_POINTS, MAX_FIT_SAMPLES, MeasuredLoop, MeasuredStiffness
from ..design import Design
from ..loops import steady_loop_force
from ..parameters import BRANCH_PARAMETERS, MATERIAL
from ..parts import as_dict
from ..points import PointsModel
from ..registry import parameter, parameter_values, with_values
from ..residuals import gap, gaps_by_mode, relative_residual
from ..rules import decimal
from ..sampling import latin_hypercube
from ..shape import OutsideTable
from .fit_words import fit_warnings as _warnings
from .progress import PROGRESS_EVERY, Progress  # noqa: F401
from .progress import forward as _forward
from .progress import reporting as _reporting
from .uncertainty import CONFIDENCE, SIDE_EVALUATIONS, Paths, linearised, minimise, profile

FIT_NFEV = (100, 100, 200)  # iterations from one start in the stages of uncertainty.minimise
# a relative misfit beyond this is no fit, and its squares would overflow: not evaluable
MAX_RESIDUAL = 1e100


def model_stiffness(design: Design, data: MeasuredStiffness) -> np.ndarray:
    """The design's complex K at every row of ``data``, each row in its own mode (a file's
    `mode` column) or the design's."""
    if data.mode is None:
        return stiffness_points(design, data.frequency_hz, data.amplitude)
    k = np.empty(len(data), dtype=complex)
    for mode in np.unique(data.mode.astype(str)):
        rows = data.mode == mode
        k[rows] = stiffness_points(design.in_mode(mode), data.frequency_hz[rows], data.amplitude[rows])
    return k


def check_data_amplitudes(design: Design, data: MeasuredStiffness) -> None:
    """Every row's amplitude within what a test can drive and resolve, in its own mode."""
    if data.mode is None:
        check_measured_amplitude(design, data.amplitude)
        return
    for mode in np.unique(data.mode.astype(str)):
        try:
            check_measured_amplitude(design.in_mode(mode), data.amplitude[data.mode == mode], f"{mode} amplitude")
        except OutsideTable as exc:  # this bushing has no shape factor in that direction
            raise ValueError(f"the data's {mode} rows: {exc}") from None


def folded(phase: np.ndarray, values: np.ndarray, bins: int):
    """A steady periodic record folded onto one period: the mean phase (in [0, 2π)) and value in
    each of ``bins`` equal phase bins that holds samples, and their counts; the record itself
    (counts of 1) if it has no more samples than ``bins``."""
    if phase.size <= bins:
        return phase, values, np.ones(phase.size)
    wrapped = np.mod(phase, 2.0 * np.pi)
    _, label = np.unique(np.minimum((wrapped * bins / (2.0 * np.pi)).astype(np.int64), bins - 1),
                         return_inverse=True)
    count = np.bincount(label).astype(float)
    return (np.bincount(label, weights=wrapped) / count, np.bincount(label, weights=values) / count, count)


@dataclass(frozen=True)
class FitResult:
    """A fitted design with its uncertainties and misfit."""

    design: Design
    standard_errors: dict[str, float]
    correlation: dict[str, dict[str, float]]
    gap: float  # over the stiffness points (NaN without them)
    cost: float
    points: int
    method: str
    starts: int = 1
    loop_rms: float | None = None  # relative RMS force misfit of the loop, if one was fitted
    history: list = field(default_factory=list)
    # profile-likelihood intervals at CONFIDENCE, natural units; None for a side the data do not
    # bound within the fitting range (empty if the fit was not profiled)
    intervals: dict[str, tuple[float | None, float | None]] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    gap_by_mode: dict[str, float] = field(default_factory=dict)  # with data of several modes
    prediction: dict = field(default_factory=dict)  # cross-mode prediction (fit on a subset)

    @property
    def undetermined(self) -> list[str]:
        """The parameters the data do not determine: their interval is open on a side."""
        return [k for k, (lo, hi) in self.intervals.items() if lo is None or hi is None]

    def report(self) -> dict:
        """The ``fit`` object of the fitted design file (docs/files.md). A number the data do
        not define (a standard error or correlation of a degenerate fit, the standard error of
        an undetermined parameter) is null. The standard errors have the keys of the design's
        ``material`` (in its order), a parameter held known (the bulk modulus, unless freed)
        at 0, then those of any other fitted parameter."""
        def finite(v):
            return float(v) if v is not None and math.isfinite(v) else None

        vague = set(self.undetermined)
        errors = {k: None if k in vague else finite(v) for k, v in self.standard_errors.items()}
        material = as_dict(self.design.material)
        out = {
            "standard_errors": {**{k: errors.get(k, 0.0) for k in material},
                                **{k: v for k, v in errors.items() if k not in material}},
            "correlation": {a: {b: finite(v) for b, v in row.items()} for a, row in self.correlation.items()},
            "gap": finite(self.gap),
            "points": self.points,
            "method": self.method,
            "starts": self.starts,
        }
        if self.intervals:
            out["confidence"] = CONFIDENCE
            out["intervals"] = {k: [finite(lo), finite(hi)] for k, (lo, hi) in self.intervals.items()}
            out["undetermined"] = self.undetermined
        if self.gap_by_mode:
            out["gap_by_mode"] = {k: finite(v) for k, v in self.gap_by_mode.items()}
        if self.prediction:
            out["prediction"] = self.prediction
        if self.warnings:
            out["warnings"] = list(self.warnings)
        if self.loop_rms is not None:
            out["loop_rms"] = self.loop_rms
        return out

    def to_dict(self) -> dict:
        return {**self.design.to_dict(), "fit": self.report()}

    def to_json(self) -> str:
        """The fitted design file (docs/files.md): the design and its ``fit`` object."""
        return json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n"


def _clip(value: float, bounds: tuple[float, float]) -> float:
    """``value`` within ``bounds`` (NaN stays NaN): np.clip's result for a number, without its
    cost, a tenth of a diagnosis's CPU under cProfile (this runs at every residual evaluation)."""
    return float(min(max(value, bounds[0]), bounds[1]))


class _Problem:
    """Residuals of a design against measured data, over a subset of its parameters (material
    names, or ``effect.name`` for the parameters of its effects)."""

    def __init__(self, design: Design, data: MeasuredStiffness | None, loop: MeasuredLoop | None,
                 free: tuple[str, ...]):
        self.design, self.free = design, free
        self.full_data, self.full_loop = data, loop  # the gap and the loop's misfit are over these
        self.data = None if data is None else data.binned(MAX_FIT_POINTS)  # the fit works on these
        self.loop = loop
        self.base = parameter_values(design)
        self.specs = [parameter(p) for p in free]
        self.scales = [(s.log, s.bounds) for s in self.specs]
        self.low, self.high = (np.array(b, dtype=float) for b in zip(*(s.bounds for s in self.specs)))
        if loop is not None:
            self.loop_f, self.loop_amp, phase = loop.harmonic()
            force = loop.force - np.mean(loop.force)
            self.loop_scale = float(np.sqrt(np.mean(force**2)))
            self.loop_phase, self.loop_force, count = folded(phase, force, MAX_FIT_SAMPLES)
            n_k = 0 if data is None else data.measured_points
            # the loop weighs as much as the stiffness points (or as one point per sample alone)
            self.loop_weight = math.sqrt(max(n_k, loop.force.size) / loop.force.size) * np.sqrt(count)

    def to_theta(self, values: dict) -> np.ndarray:
        """Fitted coordinates of ``values``, each clipped into its fitting range first (a design's
        mass of 1e300 kg or of 0 starts the search at the end of the range)."""
        clipped = [_clip(values[p], s.bounds) for p, s in zip(self.free, self.specs)]
        return np.array([math.log(v) if s.log else v for v, s in zip(clipped, self.specs)])

    def values(self, theta) -> dict[str, float]:
        """Natural values of fitted coordinates, within the fitting ranges (exp(ln 10) is a hair
        above 10, which ε½'s range refuses)."""
        return {p: _clip(math.exp(t) if log else t, bounds) for p, t, (log, bounds) in zip(self.free, theta, self.scales)}

    def model(self, theta) -> Design:
        return with_values(self.design, self.values(theta))

    def bounds(self):
        lo = [math.log(s.bounds[0]) if s.log else s.bounds[0] for s in self.specs]
        hi = [math.log(s.bounds[1]) if s.log else s.bounds[1] for s in self.specs]
        return lo, hi

    def residuals(self, theta) -> np.ndarray:
        """The misfit at fitted coordinates ``theta``: the relative stiffness errors (real and
        imaginary parts, weighted by the bins' counts), then the loop's force errors."""
        if self._points() is not None:
            return self._together([theta])[0]
        return self._residuals(theta)

    def _residuals(self, theta) -> np.ndarray:
        design = self.model(theta)
        parts = []
        if self.data is not None:
            k = model_stiffness(design, self.data)
            r = relative_residual(k, self.data.stiffness) * self.data.weight
            parts += [r.real, r.imag]
        if self.loop is not None:
            f = sum(steady_loop_force(design, self.loop_f, self.loop_amp, self.loop_phase))
            parts.append(self.loop_weight * (f - self.loop_force) / self.loop_scale)
        return _evaluable(np.concatenate(parts))

    def residuals_many(self, thetas: list[np.ndarray]) -> list[np.ndarray]:
        """:meth:`residuals` at each of ``thetas``, the same numbers: the model at every point in
        one evaluation (:class:`core.points.PointsModel`) where it allows (stiffness data of one
        mode, no loop), else point by point. What a finite-difference Jacobian asks."""
        if self._points() is None:
            return [self._residuals(t) for t in thetas]
        return self._together(thetas)

    def _together(self, thetas) -> list[np.ndarray]:
        raw = np.array([[math.exp(t) if log else t for t, (log, _) in zip(theta, self.scales)] for theta in thetas])
        k = self._points()(np.minimum(np.maximum(raw, self.low), self.high))  # as _clip: NaN stays NaN
        r = relative_residual(k, self.data.stiffness) * self.data.weight
        return list(_evaluable(np.concatenate([r.real, r.imag], axis=1)))

    def _points(self) -> PointsModel | None:
        """The model at the data's points, for many values of the free parameters at once; None
        where it does not serve (a loop, data of several modes, the continuum)."""
        if not hasattr(self, "_points_model"):
            usable = self.data is not None and self.loop is None and self.data.mode is None
            model = PointsModel(self.design, self.free, self.data.frequency_hz, self.data.amplitude) if usable else None
            self._points_model = model if model is not None and model.usable else None
        return self._points_model


def _evaluable(r: np.ndarray) -> np.ndarray:
    """Residuals beyond :data:`MAX_RESIDUAL` (NaN too) infinite: the model is not evaluable there."""
    return np.where(np.abs(r) <= MAX_RESIDUAL, r, np.inf)


def _uncertainties(problem: _Problem, sol) -> tuple[dict, dict, np.ndarray]:
    logs = [spec.log for spec in problem.specs]
    return linearised(sol.jac, 2.0 * sol.cost, problem.free, problem.values(sol.x), logs)


def _starts(problem: _Problem, n: int, seed: int = 0) -> list[np.ndarray]:
    """The design's own values first (clipped into their fitting ranges), then a seeded
    Latin-hypercube spread around them: moduli and ε½ within a factor 10 either way, α across
    (0.05, 0.8), an effect's parameters across their whole fitting range (a design's mass of 0
    or 1e300 kg says nothing about where to look)."""
    first = problem.to_theta(problem.base)
    if n <= 1:
        return [first]
    starts = [first]
    for point in latin_hypercube(n - 1, len(problem.free), seed):
        theta = []
        for j, (name, spec) in enumerate(zip(problem.free, problem.specs)):
            u = point[j]
            lo, hi = (math.log(b) for b in spec.bounds) if spec.log else spec.bounds
            if name == "fractional_order":
                theta.append(0.05 + 0.75 * u)
            elif "." in name:  # an effect's
                theta.append(lo + (hi - lo) * u)
            elif spec.log:
                theta.append(first[j] + math.log(10.0) * (2 * u - 1))
            else:
                theta.append(lo + (hi - lo) * u)
        starts.append(np.array(theta))
    return starts


def _solve(problem: _Problem, starts: list[np.ndarray], progress: Progress | None = None,
           share: tuple[float, float] = (0.0, 0.6)):
    """The best of the bounded least-squares searches from ``starts``; ``progress`` told which
    start of how many runs, its fraction within ``share``."""
    lo, hi = problem.bounds()
    best = None
    paths = Paths(lo, hi)
    for i, theta0 in enumerate(starts):
        theta0 = np.clip(theta0, lo, hi)
        fraction = share[0] + (share[1] - share[0]) * i / len(starts)
        residuals = _reporting(problem.residuals, progress, fraction, f"start {i + 1} of {len(starts)}")
        walked: list = []
        try:
            sol, _ = minimise(residuals, theta0, lo, hi, FIT_NFEV, xtol=1e-12, many=problem.residuals_many,
                              callback=paths.follow(walked))
        except (ValueError, FloatingPointError, OverflowError):
            continue  # a start the model cannot evaluate: try the next
        paths.add(walked)
        if sol.status == -2:
            continue  # it joined an earlier start's path: it ends no lower
        if np.all(np.isfinite(sol.fun)) and (best is None or sol.cost < best.cost):
            best = sol
    if best is None:
        raise ValueError(f"the fit failed from every starting point: the model cannot be evaluated there, or "
                         f"misses the data by more than {MAX_RESIDUAL:.0e} times (check the data and the "
                         f"design: its mode, geometry and the values of what is not fitted)")
    return best


def fitted_name(name: str | None) -> str | None:
    """The name of a fitted design: "(fitted)" added once, however often a design is refitted."""
    if not name or name.endswith(" (fitted)"):
        return name
    return f"{name} (fitted)"


def _profiled(problem: _Problem, sol, progress: Progress | None = None):
    """Profile every free parameter; if the walk finds a lower misfit than the optimum (the
    search was not global), refit from there and profile again. The solution, its intervals in
    natural units and whether the profile finished within its count of evaluations."""
    lo, hi = problem.bounds()
    for attempt in range(3):
        sd = _uncertainties(problem, sol)[2]
        stage = "profiling the intervals" + (f" again ({attempt + 1})" if attempt else "")
        budget = 2 * len(problem.free) * SIDE_EVALUATIONS  # profile's most
        prof = profile(_reporting(problem.residuals, progress, 0.6 + 0.1 * attempt, stage, budget, 0.3), sol.x, lo, hi,
                       sd, many=problem.residuals_many)
        if prof.better is None:
            break
        moved = _solve(problem, [prof.better], progress, (0.65 + 0.1 * attempt,) * 2)
        if moved.cost >= sol.cost:
            break
        sol = moved
    intervals = {}
    for name, spec, (a, b) in zip(problem.free, problem.specs, prof.intervals):
        ends = [None if t is None else math.exp(t) if spec.log else float(t) for t in (a, b)]
        intervals[name] = (ends[0], ends[1])
    return sol, intervals, prof.complete


def _result(problem: _Problem, sol, method: str, starts: int, design: Design, intervals=None,
            warnings=()) -> FitResult:
    errors, corr, _ = _uncertainties(problem, sol)
    fitted = problem.model(sol.x)
    fitted = fitted.replace(name=fitted_name(design.name))
    g, by_mode = float("nan"), {}
    data, loop = problem.full_data, problem.full_loop  # every measured point, binned or not
    if data is not None:
        k = model_stiffness(fitted, data)
        g, by_mode = gap(k, data.stiffness, data.count), gaps_by_mode(k, data)
    loop_rms = None
    if loop is not None:
        f = sum(steady_loop_force(fitted, problem.loop_f, problem.loop_amp, loop.harmonic()[2]))
        measured = loop.force - np.mean(loop.force)
        # docs/files.md: relative to the loop's peak force (the fit weighs it by its RMS instead)
        loop_rms = float(np.sqrt(np.mean((f - measured) ** 2)) / np.max(np.abs(measured)))
    n = 0 if data is None else data.measured_points
    return FitResult(fitted, errors, corr, g, float(sol.cost), n, method, starts, loop_rms,
                     intervals=intervals or {}, warnings=tuple(warnings), gap_by_mode=by_mode)


def fit_global(design: Design, data: MeasuredStiffness | None = None, loop: MeasuredLoop | None = None,
               *, starts: int = 8, free: tuple[str, ...] = MATERIAL, seed: int = 0,
               initial: Sequence[Mapping[str, float]] = (), intervals: bool = True,
               progress: Progress | None = None) -> FitResult:
    """Fit the parameters ``free`` of ``design`` to all the data at once.

    ``design`` gives the geometry, the mode and the starting values; ``data`` measured
    stiffness, ``loop`` a measured loop (at least one of the two). ``free`` names material
    parameters or effect parameters as ``effect_id.name``. The search starts from the design's
    values and ``starts − 1`` seeded points around them, or, if ``initial`` is given, from those
    points (mappings of some free parameters' values, the rest the design's). With
    ``intervals`` each parameter is profiled (:mod:`core.identify.uncertainty`) for its interval, which
    may also find a better optimum than the starts did. ``progress(fraction, message)``, if given,
    hears where the fit is (the start of how many, the profile, the count of evaluations) a few
    times a second at most; the result does not depend on it.
    Returns a :class:`FitResult`.
    """
    if data is None and loop is None:
        raise ValueError("give measured stiffness, a measured loop, or both")
    if data is not None:
        check_data_amplitudes(design, data)  # the measured amplitudes, for this bushing
    if loop is not None:
        check_measured_amplitude(design, loop.harmonic()[1], "the loop's amplitude")
        loop.check_force()  # after the amplitude: a displacement in wrong units is named as such
    n = (0 if data is None else 2 * len(data)) + (0 if loop is None else loop.force.size)
    if n <= len(free):
        raise ValueError(f"{n // 2} points cannot determine {len(free)} parameters")
    problem = _Problem(design, data, loop, tuple(free))
    progress = _forward(progress)
    if initial:
        points = [problem.to_theta({**problem.base, **dict(v)}) for v in initial]
    else:
        points = _starts(problem, starts, seed)
    sol = _solve(problem, points, progress, (0.0, 0.6 if intervals else 1.0))
    if not intervals:
        return _result(problem, sol, "global", len(points), design)
    sol, found, complete = _profiled(problem, sol, progress)
    return _result(problem, sol, "global", len(points), design, found, _warnings(problem, sol, found, complete))


def selection(data: MeasuredStiffness, design_mode: str, spec: str) -> np.ndarray:
    """The rows that ``spec`` chooses: ``key=value[+value…]`` items joined by commas, keys
    ``mode`` (mode names) and ``amplitude`` (m or rad, matched to 1e-6 relative), e.g.
    ``mode=axial,amplitude=1e-4``. Raises ValueError on a bad spec or an empty choice."""
    chosen = np.ones(len(data), dtype=bool)
    modes = data.modes(design_mode)
    for item in filter(None, (part.strip() for part in spec.split(","))):
        key, sep, value = item.partition("=")
        values = [v.strip() for v in value.split("+") if v.strip()]
        if not sep or not values or key.strip() not in ("mode", "amplitude"):
            raise ValueError(f"--fit-on: {item!r}: give mode=NAME[+NAME…] or amplitude=VALUE[+VALUE…]")
        if key.strip() == "mode":
            chosen &= np.isin(modes.astype(str), values)
        else:
            try:
                amps = [decimal(v) for v in values]
            except ValueError:
                raise ValueError(f"--fit-on: {item!r}: amplitudes are numbers in m or rad") from None
            chosen &= np.any([np.isclose(data.amplitude, a, rtol=1e-6, atol=0) for a in amps], axis=0)
    if not chosen.any():
        raise ValueError(f"--fit-on {spec!r} chooses none of the {len(data)} rows")
    return chosen


def predicted(result: FitResult, data: MeasuredStiffness, fitted_on: np.ndarray, spec: str) -> dict:
    """The sequel's protocol: the fit of ``fitted_on`` rows predicting every (mode, amplitude)
    group of ``data``; each group's gap, whether it was fitted, and the gap of all held-out rows."""
    design = result.design
    k = model_stiffness(design, data)
    modes = data.modes(design.mode).astype(str)
    groups = []
    for mode in np.unique(modes):
        for amp in np.unique(data.amplitude[modes == mode]):
            rows = (modes == mode) & (data.amplitude == amp)
            groups.append({"mode": mode, "amplitude": float(amp), "points": int(rows.sum()),
                           "fitted": bool(fitted_on[rows].all()), "gap": gap(k[rows], data.stiffness[rows])})
    held = ~fitted_on
    out = {"fit_on": spec, "points_fitted": int(fitted_on.sum()), "groups": groups}
    if held.any():
        out["gap_held_out"] = gap(k[held], data.stiffness[held])
    return out


def fit_two_step(design: Design, loop: MeasuredLoop, sweep: MeasuredStiffness,
                 *, rounds: int = 2, progress: Progress | None = None) -> FitResult:
    """The thesis' identification (Paper B): the quasi-static loop gives µ, σ_fmax, ε½ (m and α
    held), the one-amplitude frequency sweep gives m and α (the others held), ``rounds`` times;
    then all five are refined together on the loop and the sweep (alternating steps alone creep
    along the strong µ–m correlation), which is the point the alternation converges to.
    ``progress(fraction, message)``, if given, hears the round and step ("round 1 of 2, the loop: …")."""
    def step(fraction: float, words: str) -> Progress | None:
        return None if progress is None else lambda f, m: progress(fraction + 0.1 * f, f"{words}: {m}")

    current = design
    history = []
    on_loop = BRANCH_PARAMETERS["elastic"] + BRANCH_PARAMETERS["friction"]  # µ, σ_fmax, ε½
    for i in range(rounds):
        at = 0.6 * i / rounds
        step1 = fit_global(current, loop=loop, free=on_loop, starts=4, intervals=False,
                           progress=step(at, f"round {i + 1} of {rounds}, the loop"))
        step2 = fit_global(step1.design, data=sweep, free=BRANCH_PARAMETERS["fractional"],
                           starts=4, intervals=False, progress=step(at + 0.3 / rounds, f"round {i + 1} of {rounds}, the sweep"))
        current = step2.design
        history.append(as_dict(current.material))
    joint = fit_global(current, data=sweep, loop=loop, starts=1,
                       progress=None if progress is None else lambda f, m: progress(0.6 + 0.4 * f, f"all five together, {m}"))
    return dataclasses.replace(joint, method="two-step", starts=4,
                               history=[*history, as_dict(joint.design.material)])
