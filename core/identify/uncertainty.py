"""Profile-likelihood intervals: what the data really say about each fitted parameter.

Linearised standard errors describe the misfit's curvature at the optimum only. When the data
cannot separate two parameters (one amplitude cannot fix both friction parameters and µ), the
misfit is flat along a valley, the curvature says little and the standard errors can be far too
small or absurdly large. The profile walks along each parameter instead: the parameter is held
at a value and all the others refitted; the interval is where the refitted sum of squares S
stays within

    S − S_min ≤ s² · F(1, n − p; confidence),     s² = S_min / (n − p),

the classical likelihood-ratio (F-test) interval of nonlinear least squares. For a model linear
in its parameters it is exactly the t-interval θ̂ ± t(n − p) · se. A side that never rises above
the threshold before the parameter's fitting range ends is open: the data do not bound the
parameter there. A parameter with an open side is *not determined* by the data.

Everything here works on the fitted coordinates (logarithms for positive parameters), on a
residual function of all of them, with their bounds.

The work is bounded by counts, never by the clock, so that a result does not depend on the
machine: a side takes at most :data:`MAX_STEPS` outward steps (enough to reach the end of the
fitting range from the smallest first step) and :data:`SECANTS` interpolations, then if need be
:data:`BISECTIONS` refinements, of its crossing; a refit at most
:data:`REFIT_NFEV` iterations; and a side at most :data:`SIDE_EVALUATIONS` evaluations of the
residuals. A side that spends them before it crosses the threshold is left open, and the
profile says it is not complete.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import OptimizeResult, least_squares
from scipy.stats import f as f_distribution

CONFIDENCE = 0.95
# the smallest residual scale trusted (relative error): exact or noise-free data still get
# intervals of a meaningful width rather than of round-off
NOISE_FLOOR = 1e-4
FIRST_STEP = (1e-6, 1 / 20)  # the first step's least and largest, as fractions of the range
LONGEST_STEP = 1 / 10  # steps double up to this fraction of the range
# doubling from the least first step reaches the longest step in 17 steps, which then reach the
# end of the range in at most 10 more: a side never needs more
MAX_STEPS = math.ceil(math.log2(LONGEST_STEP / FIRST_STEP[0])) + round(1 / LONGEST_STEP) + 1
BISECTIONS = 4  # refinements of a crossing
# a crossing is found where the signed root of the rise is within this fraction of the threshold's
# root: the interval's end within about a thousandth of its distance from the optimum
CROSSING_TOLERANCE = 1e-3
SECANTS = 2  # refits that try to meet a crossing by interpolation before bisecting
# a refit's iterations in the stages of minimise (evaluations, the Jacobian's not counted): a
# warm-started refit of these models converges in fewer than 20 trf iterations, or stalls
REFIT_NFEV = (20, 40, 100)
# residual evaluations of one side of a profile: the sides of the examples' fits and diagnoses,
# absurd designs' included, take at most about 1600; at under a millisecond each (a fit's binned
# points) a side takes at most a few seconds
SIDE_EVALUATIONS = 3000
# a start within this fraction of each parameter's span of an earlier start's iterate (at no lower
# cost) has joined its path (:class:`Paths`)
MERGE = 1e-3
# the linearised covariance: a singular value of the Jacobian at most this fraction of the largest
# is the round-off of its finite differences (relative steps of 1.5e-8), its direction not
# determined by the data; a parameter's share of such a direction beyond NULL_LOADING (the
# direction's own round-off is about 1e-6) makes that parameter not determined
RANK_TOLERANCE = 1e-7
NULL_LOADING = 1e-4


@dataclass(frozen=True)
class Profile:
    """Intervals in fitted coordinates, one (low, high) per parameter; ``None`` for a side the
    data do not bound within the fitting range. ``better`` is a point with a lower sum of squares
    than the optimum the profile started from, if the walk found one (the fit was not global)."""

    intervals: list[tuple[float | None, float | None]]
    better: np.ndarray | None
    threshold: float  # allowed rise of the sum of squares
    complete: bool  # False if a side spent its SIDE_EVALUATIONS first (that side is open)
    evaluations: int = 0  # of the residuals, the whole profile


class _Exhausted(Exception):
    """A side has spent its evaluations."""


def minimise(fun: Callable[[np.ndarray], np.ndarray], x0, lower, upper, iterations: tuple[int, int, int], *,
             xtol: float, allowance: int | None = None,
             many: Callable[[list[np.ndarray]], list[np.ndarray]] | None = None,
             callback: Callable[[OptimizeResult], None] | None = None) -> tuple[OptimizeResult | None, bool]:
    """Bounded least squares of ``fun`` from ``x0``, each stage bounded by its ``iterations``
    (function evaluations, the Jacobian's not counted): trust-region reflective; if it has not
    converged, dogbox from where it stopped; if that has not converged to a lower sum of squares
    either, trust-region reflective again from the better point. The best point of the stages.

    trf creeps, a tiny step at a time, when a parameter that no longer acts lies against its
    bound (a mass of 1e-12 kg): dogbox holds such a parameter on the bound and converges in a
    few iterations; but dogbox alone may stop in a worse minimum, which the last stage leaves.

    With ``allowance``, at most that many evaluations of ``fun`` in all (an iteration and its
    finite-difference Jacobian cost at most 1 + len(x0)). Returns the solution and whether the
    allowance cut an unconverged search short (the solution None if nothing was allowed).
    Raises ValueError where ``fun`` is not finite at ``x0``.

    ``many``, if given, is ``fun`` of several points at once (a list of them, the same numbers):
    the finite-difference Jacobian's columns are computed by it in one call (least_squares'
    ``workers``), each still counted as an evaluation. ``callback`` is least_squares' at every
    iterate of every stage; raising StopIteration ends the search there (status −2)."""
    spent = [0]

    def counted(x):
        spent[0] += 1
        return fun(x)

    def columns(_fun, points):
        points = list(points)
        spent[0] += len(points)
        return many(points)

    def stage(method, x, most):
        allowed = most if allowance is None else min(most, (allowance - spent[0]) // (np.size(x0) + 1))
        if allowed < 1:
            return None, True
        sol = least_squares(counted, x, bounds=(lower, upper), method=method, x_scale="jac", xtol=xtol,
                            ftol=1e-12, gtol=1e-12, max_nfev=allowed, workers=columns if many else None,
                            callback=callback)
        return sol, sol.status == 0 and allowed < most

    first, cut = stage("trf", np.asarray(x0, dtype=float), iterations[0])
    if first is None or first.status != 0 or cut:
        return first, cut
    second, cut = stage("dogbox", first.x, iterations[1])
    if second is None:
        return first, True
    better = second if second.cost < first.cost else first
    if (second.status != 0 and better is second) or cut:
        return better, cut
    third, cut = stage("trf", better.x, iterations[2])
    if third is None:
        return better, True
    return (third if third.cost < better.cost else better), cut and third.status == 0


class Paths:
    """The iterates of the starts searched so far (fitted coordinates and costs): a later start
    that comes within :data:`MERGE` of an earlier iterate, at no lower cost, has joined that
    start's path and will end where it ended (least squares never climbs, so no lower): its
    search stops there. Measured: the three starts of a candidate whose parameter the data push
    to the end of its range (integer-order viscous damping, µ to 100 Pa) crept side by side,
    each for some 180 iterations."""

    def __init__(self, lo, hi):
        self.span = np.asarray(hi, dtype=float) - np.asarray(lo, dtype=float)
        self.points, self.costs = np.empty((0, self.span.size)), np.empty(0)

    def follow(self, walked: list):
        """least_squares' callback for a new start: StopIteration where it joins an earlier
        path; its iterates collected in ``walked`` (:meth:`add` them when it ends)."""
        def callback(intermediate_result):
            x, cost = intermediate_result.x, float(intermediate_result.cost)
            if self.costs.size:
                near = np.max(np.abs(self.points - x) / self.span, axis=1) <= MERGE
                if np.any(near & (cost >= self.costs)):
                    raise StopIteration
            walked.append((np.array(x), cost))
        return callback

    def add(self, walked: list) -> None:
        if walked:
            self.points = np.vstack([self.points, [x for x, _ in walked]])
            self.costs = np.concatenate([self.costs, [c for _, c in walked]])


def linearised(jac: np.ndarray, sum_of_squares: float, names, values: dict[str, float],
               logs) -> tuple[dict, dict, np.ndarray]:
    """The linearised uncertainties at an optimum: cov = s² (JᵀJ)⁻¹ with s² the residual
    variance; the standard errors in natural units (the delta method, for a parameter fitted as
    its logarithm when ``logs`` says so), the correlations, and the standard deviations in
    fitted coordinates.

    The covariance is formed from the singular values of J (J = U S Vᵀ, cov = s² V S⁻² Vᵀ), not
    by inverting JᵀJ, whose condition is J's squared. A singular value at most
    :data:`RANK_TOLERANCE` of the largest is the finite differences' round-off, not the data: its
    direction is not determined. A parameter that moves along such a direction (by more than
    :data:`NULL_LOADING` of it) has an infinite standard error, and its correlations are not
    defined (NaN); the others' come from the directions the data determine. Measured: one
    amplitude leaves µ, σ_fmax and ε½ a common direction (a singular value 5e-10 of the largest);
    inverting JᵀJ gave negative variances, standard errors of 0 and correlations of ±inf."""
    jac = np.asarray(jac, dtype=float)
    dof = max(jac.shape[0] - len(names), 1)
    s2 = sum_of_squares / dof
    _, singular, vt = np.linalg.svd(jac, full_matrices=False)
    kept = singular > RANK_TOLERANCE * (singular[0] if singular.size else 0.0)
    v = vt[kept].T / singular[kept]
    cov = s2 * (v @ v.T)
    free = ~np.any(np.abs(vt[~kept]) > NULL_LOADING, axis=0)  # no part in an undetermined direction
    sd = np.where(free, np.sqrt(np.clip(np.diag(cov), 0.0, None)), np.inf)
    errors = {name: float(values[name] * sd[i] if log else sd[i]) for i, (name, log) in enumerate(zip(names, logs))}
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = np.where(np.outer(free, free), cov / np.outer(sd, sd), np.nan)
    correlation = {a: {b: float(np.round(corr[i, j], 12)) for j, b in enumerate(names)} for i, a in enumerate(names)}
    return errors, correlation, sd


def profile(residuals: Callable[[np.ndarray], np.ndarray], theta: np.ndarray, lower, upper,
            step, *, confidence: float = CONFIDENCE, evaluations: int = SIDE_EVALUATIONS,
            many: Callable[[list[np.ndarray]], list[np.ndarray]] | None = None) -> Profile:
    """Profile every parameter of the least-squares problem ``residuals`` about its optimum
    ``theta`` within the bounds; ``step`` gives each parameter's first step (for example its
    linearised standard error, in the same coordinates). At most ``evaluations`` evaluations of
    ``residuals`` per side, and one at the optimum. ``many``: ``residuals`` of several points at
    once, for the refits' Jacobians (:func:`minimise`)."""
    theta = np.asarray(theta, dtype=float)
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    r0 = residuals(theta)
    s_min = float(r0 @ r0)
    n, p = r0.size, theta.size
    dof = max(n - p, 1)
    s2 = max(s_min / dof, NOISE_FLOOR**2)
    threshold = s2 * float(f_distribution.ppf(confidence, 1, dof))
    walker = _Walker(residuals, theta, lower, upper, s_min, threshold, many)
    intervals, complete = [], True
    for j in range(p):
        sides = []
        for direction in (-1.0, 1.0):
            walker.allow(evaluations)
            try:
                sides.append(walker.side(j, direction, _first_step(step[j], upper[j] - lower[j])))
            except _Exhausted:
                sides.append(None)
                complete = False
        intervals.append((sides[0], sides[1]))
    return Profile(intervals, walker.better, threshold, complete, walker.spent + 1)


def _first_step(step: float, span: float) -> float:
    """A side's first step: the parameter's linearised standard deviation, within FIRST_STEP of
    its range. A parameter with none (undetermined to first order) starts at the least step: its
    valley is then followed from the optimum, each refit warm-started from the one before.
    Measured (a sweep at one amplitude, µ): a first step of a twentieth of the range jumped into
    the valley's bend, where the refits stopped short and read as a crossing at a fifth of the
    threshold (3.51 MPa instead of 3.55)."""
    step = abs(float(step)) if math.isfinite(step) else 0.0
    return float(np.clip(step, span * FIRST_STEP[0], span * FIRST_STEP[1]))


def _along(first, second, value: float) -> np.ndarray:
    """The other parameters' start for a refit at ``value``: on the line through two points of
    the profile's path, (value, others) each (a warm start a step ahead, which the path's
    curvature alone keeps from being the answer); the second point's own if there is no first."""
    if first is None or first[0] == second[0]:
        return second[1]
    return second[1] + (second[1] - first[1]) * ((value - second[0]) / (second[0] - first[0]))


class _Walker:
    def __init__(self, residuals, theta, lower, upper, s_min, threshold, many=None):
        self.residuals, self.theta, self.lower, self.upper = residuals, theta, lower, upper
        self.many = many
        self.s_min, self.threshold = s_min, threshold
        self.better: np.ndarray | None = None
        self.best_s = s_min
        self.spent = 0  # evaluations of the residuals, every side
        self.left = 0  # of the current side's evaluations

    def allow(self, evaluations: int) -> None:
        """Start a side that may spend ``evaluations``."""
        self.left = evaluations

    def _charge(self, evaluations: int) -> None:
        self.spent += evaluations
        self.left -= evaluations

    def refit(self, j: int, value: float, starts: list[np.ndarray]) -> tuple[float, np.ndarray]:
        """The sum of squares with parameter ``j`` held at ``value``, the others refitted (from
        each of ``starts``, the best kept); the others' values. Raises :class:`_Exhausted` when
        the side's evaluations run out before a refit has converged."""
        others = np.arange(self.theta.size) != j

        def full(x):
            t = self.theta.copy()
            t[j], t[others] = value, x
            return t

        best = (math.inf, starts[0])
        for x0 in starts:
            if self.left < 1:
                raise _Exhausted
            if not others.any():
                r = self.residuals(full(x0))
                self._charge(1)
                s, x = float(r @ r), x0
            else:
                lo, hi = self.lower[others], self.upper[others]
                spent = [0]

                def fun(x, spent=spent):
                    spent[0] += 1
                    return self.residuals(full(x))

                def fun_many(xs, spent=spent):
                    spent[0] += len(xs)
                    return self.many([full(x) for x in xs])

                try:
                    sol, cut = minimise(fun, np.clip(x0, lo, hi), lo, hi, REFIT_NFEV, xtol=1e-10,
                                        allowance=self.left, many=fun_many if self.many else None)
                except (ValueError, ArithmeticError):
                    self._charge(spent[0])
                    continue
                self._charge(spent[0])
                if cut:
                    raise _Exhausted
                if not np.all(np.isfinite(sol.fun)):
                    continue
                s, x = 2.0 * float(sol.cost), sol.x
            if s < best[0]:
                best = (s, x)
            if best[0] - self.s_min <= self.threshold:
                break  # inside: another start cannot move the crossing outwards
        if best[0] < self.best_s - 1e-9 * max(self.s_min, 1e-300):
            self.best_s, self.better = best[0], full(best[1])
        return best

    def side(self, j: int, direction: float, step: float) -> float | None:
        """Where the profile of parameter ``j`` crosses the threshold going ``direction`` from the
        optimum; ``None`` if it does not before the bound."""
        others = np.arange(self.theta.size) != j
        x_hat = self.theta[others]
        edge = self.lower[j] if direction < 0 else self.upper[j]
        span = self.upper[j] - self.lower[j]
        inside, x_in, rise_in = float(self.theta[j]), x_hat, 0.0
        before = None  # the inside point before, (value, others): the path's slope
        for _ in range(MAX_STEPS):
            if abs(edge - inside) <= 1e-12 * max(span, 1.0):
                return None  # the optimum sits at the bound: nothing beyond it to test
            value = inside + direction * step
            at_edge = direction * (value - edge) >= 0
            if at_edge:
                value = edge
            s, x = self.refit(j, value, [_along(before, (inside, x_in), value), x_hat])
            rise = s - self.s_min
            if rise > self.threshold:
                return self._crossing(j, (inside, x_in, rise_in), (value, x, rise), x_hat)
            before = (inside, x_in)
            inside, x_in, rise_in = value, x, max(rise, 0.0)
            if at_edge:
                return None
            step = min(2.0 * step, span * LONGEST_STEP)
        return None

    def _crossing(self, j, inner, outer, x_hat) -> float:
        """Where the profile crosses the threshold between a point inside and one outside.

        First up to :data:`SECANTS` refits where the signed root g = sqrt(rise) −
        sqrt(threshold), linear in a parameter the model is linear in, is interpolated to vanish
        (regula falsi, the bracket narrowed by each): where g comes within
        :data:`CROSSING_TOLERANCE` of the threshold's root, that is the crossing (a smooth
        profile: one or two refits, not :data:`BISECTIONS`). Otherwise (a curved profile, as at
        a cliff) bisect the bracket as first given, then interpolate the signed root in the
        bracket reached. The side's evaluations spent meanwhile end it: the crossing is
        interpolated in the bracket reached."""
        root_t = math.sqrt(self.threshold)
        (a, xa, ra), (b, xb, rb) = inner, outer
        root_a, root_b = math.sqrt(ra), math.sqrt(rb)
        for _ in range(SECANTS):
            if root_b <= root_a:
                break
            guess = a + (b - a) * (root_t - root_a) / (root_b - root_a)
            try:
                s, x = self.refit(j, guess, [_along((a, xa), (b, xb), guess), x_hat])
            except _Exhausted:
                return guess
            root = math.sqrt(max(s - self.s_min, 0.0))
            if abs(root - root_t) <= CROSSING_TOLERANCE * root_t:
                return guess
            if root > root_t:
                b, xb, root_b = guess, x, root
            else:
                a, xa, root_a = guess, x, root
        (a, xa, ra), (b, _, rb) = inner, outer
        for _ in range(BISECTIONS):
            mid = 0.5 * (a + b)
            try:
                s, x = self.refit(j, mid, [xa, x_hat])
            except _Exhausted:
                break
            rise = s - self.s_min
            if rise > self.threshold:
                b, rb = mid, rise
            else:
                a, xa, ra = mid, x, max(rise, 0.0)
        root_a, root_b, root_t = math.sqrt(ra), math.sqrt(rb), math.sqrt(self.threshold)
        if root_b <= root_a:
            return b
        return a + (b - a) * (root_t - root_a) / (root_b - root_a)
