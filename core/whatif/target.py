"""Designs found from target stiffnesses: which a, b, L (and, within given ranges, which
compound) meet targets on |K|, the loss factor or the ratio of two directions, within limits.

The search works in logarithms: the inner radius a, the rubber's thickness t = b − a (so b > a
always) and the length L, and the free material parameters. Among the designs that meet every
target it seeks those nearest the starting design (the sum of squared log changes), by SLSQP
(SciPy) from the start and from a seeded Latin hypercube over the limits. If none meets the
targets, the design that misses them least within the limits (least squares on the misses, in
logarithms, with the limits held) is reported with the targets it misses and the limits that
bind there.

The search is bounded by counts, never by the clock (a loaded machine finds what a fast one
does): :data:`STARTS` starting points, at most :data:`MAX_ITERATIONS` SLSQP iterations from
each, and no new start once :data:`TARGET_EVALUATIONS` evaluations of a target have been spent.

A target is a quantity at an operating point (mode, frequency, amplitude): ``magnitude`` |K|,
``loss_factor`` η, or for a ``ratio`` of two modes |K₁|/|K₂|. Its value is a number (met within
± ``tolerance``, relative) or a range ``{"min": …, "max": …}``. ``docs/files.md`` gives the file,
:mod:`core.io.targets` reads it.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares, minimize

from ..bushing import MAX_STRAIN, stiffness_points
from ..design import Design
from ..parameters import GEOMETRY, MODE
from ..response import loss_factor
from ..rules import DesignError, RuleError
from ..sampling import latin_hypercube

SEARCHED = tuple("thickness" if n == "outer_radius" else n for n in GEOMETRY)  # a, t = b − a, L
STARTS = 12
FEASIBLE = 1e-6  # a constraint counts as met down to this (in logarithms)
# SLSQP iterations from one start: feasible searches converge in at most 15, an impossible one
# gives up (status 8) within 75
MAX_ITERATIONS = 60
INSIDE = 1e-7  # the closest miss keeps this log-margin inside the limits
CLOSEST_NFEV = 100  # least-squares iterations from each of the closest miss's starts (need < 35)
# evaluations of one target at one design (a few stiffnesses, about 0.1 ms): no new start once
# a search has spent these; the start under way adds at most MAX_ITERATIONS (n + 2) per target
TARGET_EVALUATIONS = 20_000


class TargetError(RuleError):
    """A targets file that cannot be used: ``key`` names where, ``rule`` the reason in plain
    words, ``code`` the rule (:mod:`core.rules`)."""


@dataclass(frozen=True)
class Target:
    """One target: ``quantity`` of ``modes`` (one mode, or two for a ratio) at ``frequency_hz``
    and ``amplitudes`` (one per mode, SI), between ``low`` and ``high`` (either may be None)."""

    modes: tuple[str, ...]
    quantity: str
    frequency_hz: float
    amplitudes: tuple[float, ...]
    low: float | None
    high: float | None
    value: float | None = None  # the number asked, for a target given as one

    @property
    def is_ratio(self) -> bool:
        return len(self.modes) == 2

    def measure(self, design: Design, directions: dict[str, Design] | None = None) -> float:
        """The target's quantity for ``design``; ``directions``: the design already taken into
        each mode (:meth:`core.design.Design.in_mode`), where the caller has them."""
        directions = directions or {m: design.in_mode(m) for m in self.modes}
        k = [complex(stiffness_points(directions[m], self.frequency_hz, x)) for m, x in zip(self.modes, self.amplitudes)]
        if self.is_ratio:
            return abs(k[0]) / abs(k[1])
        return abs(k[0]) if self.quantity == "magnitude" else float(loss_factor(k[0]))

    def describe(self, value=None, amplitude=None, frequency=None) -> str:
        """The target in words (``axial |K| = 4.5e+06 N/m at 10 Hz, 0.0001 m``). ``value``,
        ``amplitude`` and ``frequency`` write its numbers (functions of the SI value, and of the mode
        for an amplitude, to text with its unit); by default SI to 4 significant digits."""
        value = value or self.si
        amplitude = amplitude or (lambda x, m: f"{x:.4g} {MODE[m].amplitude.si}")
        frequency = frequency or (lambda f: f"{f:.4g} Hz")
        amp = " and ".join(amplitude(x, m) for m, x in zip(self.modes, self.amplitudes))
        what = (f"|K_{self.modes[0]}|/|K_{self.modes[1]}|" if self.is_ratio else
                f"{self.modes[0]} {'|K|' if self.quantity == 'magnitude' else 'loss factor'}")
        if self.value is not None:
            goal = f"= {value(self.value)}"
        else:
            goal = " and ".join(p for p in ((f"≥ {value(self.low)}" if self.low is not None else ""),
                                            (f"≤ {value(self.high)}" if self.high is not None else "")) if p)
        return f"{what} {goal} at {frequency(self.frequency_hz)}, {amp}"

    def si(self, value: float) -> str:
        """A value of the target's quantity in SI to 4 significant digits, with its unit
        (``4.5e+06 N/m``; a loss factor or a ratio without one)."""
        unit = "" if self.is_ratio or self.quantity == "loss_factor" else f" {MODE[self.modes[0]].stiffness.si}"
        return f"{value:.4g}{unit}"

    def misses(self, value: float) -> float:
        """How far ``value`` lies outside the target, relative (0 inside, or within
        :data:`FEASIBLE` of its edge)."""
        if self.low is not None and value < self.low * (1 - FEASIBLE):
            return value / self.low - 1.0
        if self.high is not None and value > self.high * (1 + FEASIBLE):
            return value / self.high - 1.0
        return 0.0


@dataclass(frozen=True)
class Problem:
    """A start design, its targets, the limits (SI, by :data:`core.io.targets.GEOMETRY_LIMITS`) and the
    material parameters left free within ranges."""

    start: Design
    targets: tuple[Target, ...]
    limits: dict[str, tuple[float, float]]
    free_material: dict[str, tuple[float, float]] = field(default_factory=dict)
    fixed: tuple[str, ...] = ()
    solutions: int = 3

    @property
    def variables(self) -> tuple[str, ...]:
        geo = tuple(n for n in SEARCHED if n not in self.fixed)
        return geo + tuple(self.free_material)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        ranges = [self.limits[n] if n in self.limits else self.free_material[n] for n in self.variables]
        return np.log([r[0] for r in ranges]), np.log([r[1] for r in ranges])

    def values(self, start: Design) -> dict[str, float]:
        g, m = start.geometry, start.material
        out = {n: g.outer_radius - g.inner_radius if n == "thickness" else getattr(g, n) for n in SEARCHED}
        out.update({n: getattr(m, n) for n in self.free_material})
        return out

    def design(self, z: np.ndarray) -> Design:
        v = {**self.values(self.start), **dict(zip(self.variables, np.exp(z)))}
        material = {n: v[n] for n in self.free_material}
        return self.start.replace(inner_radius=v["inner_radius"], outer_radius=v["inner_radius"] + v["thickness"],
                                  length=v["length"], **material)


@dataclass(frozen=True)
class Solution:
    design: Design
    distance: float  # sqrt(Σ (ln p − ln p₀)²) over the varied parameters
    achieved: tuple[float, ...]
    binding: tuple[str, ...]  # limits the solution sits on

    def report(self, targets) -> dict:
        return {"design": self.design.to_dict(), "distance": self.distance,
                "targets": [{"target": t.describe(), "value": v, "met": t.misses(v) == 0.0, "miss": t.misses(v)}
                            for t, v in zip(targets, self.achieved)],
                "binding_limits": list(self.binding)}


@dataclass(frozen=True)
class Words:
    """How a search's statement writes its numbers and names: a target (:meth:`Target.describe`),
    the value a design reaches for a target, a limit that binds (``outer_radius ≤ 0.04``, SI, as
    :attr:`Solution.binding` gives it), a relative change (a fraction) and a searched variable's
    name (``thickness``, a design parameter's or the thickness t = b − a)."""

    target: Callable[[Target], str]
    reached: Callable[[Target, float], str]
    limit: Callable[[str], str]
    change: Callable[[float], str]
    name: Callable[[str], str]


SI_WORDS = Words(Target.describe, Target.si, str, lambda fraction: f"{100 * fraction:+.3g} %", str)


@dataclass(frozen=True)
class Found:
    """What the search found: the feasible designs nearest the start (best first), or, when
    there are none, the closest miss and the statement why."""

    problem: Problem
    solutions: list[Solution]
    closest: Solution | None
    seconds: float

    @property
    def feasible(self) -> bool:
        return bool(self.solutions)

    @property
    def statement(self) -> str:
        """What was found, in words, numbers in SI (:data:`SI_WORDS`): the report's and the
        command line's."""
        return self.words(SI_WORDS)

    def words(self, words: Words) -> str:
        """What was found, in words, its numbers and names written by ``words``: how many designs
        meet the targets and how the nearest changes the start, or which targets the closest miss
        misses by how much (what it reaches) and which limits bind there."""
        if self.solutions:
            return _found_words(self.problem, self.solutions, words)
        return _why(self.problem, self.closest, words)

    def report(self) -> dict:
        out = {"feasible": self.feasible, "statement": self.statement,
               "solutions": [s.report(self.problem.targets) for s in self.solutions]}
        if self.closest is not None:
            out["closest"] = self.closest.report(self.problem.targets)
        return out

    def to_json(self) -> str:
        return json.dumps(self.report(), indent=2, allow_nan=False) + "\n"


# ---- the search --------------------------------------------------------------------------------------


class _Evaluator:
    """The targets' log-margins of a point z (cached: SLSQP asks for the same point twice).
    ``exact``: a target given as a number is an equality (hit it), not its tolerance band."""

    def __init__(self, problem: Problem, exact: bool = False):
        self.problem, self.exact = problem, exact
        self.cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    @property
    def spent(self) -> int:
        """Evaluations of a target so far (each point evaluates every target once)."""
        return len(self.cache) * len(self.problem.targets)

    def _both(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = np.asarray(z, float).tobytes()
        if key in self.cache:
            return self.cache[key]
        p = self.problem
        ineq, eq = [], []
        try:
            design = p.design(z)
            b = design.geometry.outer_radius
            ineq += [math.log(b / p.limits["outer_radius"][0]), math.log(p.limits["outer_radius"][1] / b)]
            directions = {m: design.in_mode(m) for t in p.targets for m in t.modes}  # once per point
            for t in p.targets:
                for m, x in zip(t.modes, t.amplitudes):
                    d = directions[m]
                    ineq.append(math.log(MAX_STRAIN / d.strain(x)))
            for t in p.targets:
                q = t.measure(design, directions)
                lq = math.log(q) if q > 0 else -50.0
                if self.exact and t.value is not None:
                    eq.append(lq - math.log(t.value))
                    continue
                ineq += [lq - math.log(t.low) if t.low is not None else 1.0,
                         math.log(t.high) - lq if t.high is not None else 1.0]
            out = np.array(ineq), np.array(eq)
            if not (np.all(np.isfinite(out[0])) and np.all(np.isfinite(out[1]))):
                raise ValueError("not finite")
        except (ValueError, ArithmeticError, DesignError):
            exact = [t for t in p.targets if self.exact and t.value is not None]
            out = (np.full(2 + sum(len(t.modes) for t in p.targets) + 2 * (len(p.targets) - len(exact)), -10.0),
                   np.full(len(exact), 10.0))
        self.cache[key] = out
        return out

    def margins(self, z: np.ndarray) -> np.ndarray:
        """g(z) ≥ 0 when met: b within its limits, the strain of each target's drive at most
        MAX_STRAIN, ln q − ln low and ln high − ln q per target (those not exact)."""
        return self._both(z)[0]

    def equalities(self, z: np.ndarray) -> np.ndarray:
        """h(z) = 0 when met: ln q − ln value of each exact target."""
        return self._both(z)[1]

    def met(self, z: np.ndarray) -> bool:
        ineq, eq = self._both(z)
        return bool(np.min(ineq, initial=1.0) >= -FEASIBLE and np.max(np.abs(eq), initial=0.0) <= FEASIBLE)


def _starts(problem: Problem, n: int, seed: int = 0) -> list[np.ndarray]:
    """The start design (within the limits), then ``n − 1`` points of a seeded Latin hypercube
    over the limits (in logarithms)."""
    lo, hi = problem.bounds()
    first = np.clip(np.log([problem.values(problem.start)[v] for v in problem.variables]), lo, hi)
    return [first] + list(lo + (hi - lo) * latin_hypercube(n - 1, len(problem.variables), seed))


def _binding(problem: Problem, z: np.ndarray, design: Design) -> tuple[str, ...]:
    lo, hi = problem.bounds()
    out = []
    for name, v, a, b in zip(problem.variables, z, lo, hi):
        if v - a < 1e-6:
            out.append(f"{name} ≥ {math.exp(a):.4g}")
        if b - v < 1e-6:
            out.append(f"{name} ≤ {math.exp(b):.4g}")
    b, (b_lo, b_hi) = design.geometry.outer_radius, problem.limits["outer_radius"]
    if math.log(b / b_lo) < 1e-6:
        out.append(f"outer_radius ≥ {b_lo:.4g}")
    if math.log(b_hi / b) < 1e-6:
        out.append(f"outer_radius ≤ {b_hi:.4g}")
    return tuple(out)


def _solution(problem: Problem, z: np.ndarray) -> Solution:
    design = problem.design(z)
    centre = np.log([problem.values(problem.start)[v] for v in problem.variables])
    return Solution(design, float(np.sqrt(np.sum((z - centre) ** 2))),
                    tuple(t.measure(design) for t in problem.targets), _binding(problem, z, design))


def solve(problem: Problem, starts: int = STARTS, seed: int = 0,
          progress: Callable[[float, str], None] | None = None) -> Found:
    """Search ``problem`` (:class:`Problem`): the feasible designs nearest the start, or the
    closest miss with the reason. ``seconds`` in the result is for the user's information only.
    ``progress(fraction, message)`` is told of each start as the search reaches it."""
    say = progress or (lambda fraction, message: None)
    t0 = time.perf_counter()
    lo, hi = problem.bounds()
    centre = np.log([problem.values(problem.start)[v] for v in problem.variables])
    points = _starts(problem, starts, seed)
    found: list[np.ndarray] = []
    # first hit the numbers asked exactly; only if no design can, settle for their tolerance
    # (the same search again when no target is a number: skipped)
    exact = any(t.value is not None for t in problem.targets)
    evaluators = (_Evaluator(problem, exact=True), _Evaluator(problem)) if exact else (_Evaluator(problem),)
    for n, ev in enumerate(evaluators):
        for i, z0 in enumerate(points):
            if sum(e.spent for e in evaluators) >= TARGET_EVALUATIONS:
                break
            say((n + i / len(points)) / len(evaluators),
                f"{'within the tolerance: ' if n else ''}start {i + 1} of {len(points)}")
            constraints = [{"type": "ineq", "fun": ev.margins}]
            if len(ev.equalities(z0)):
                constraints.append({"type": "eq", "fun": ev.equalities})
            sol = minimize(lambda z: float(np.sum((z - centre) ** 2)), z0, jac=lambda z: 2.0 * (z - centre),
                           method="SLSQP", bounds=list(zip(lo, hi)), constraints=constraints,
                           options={"maxiter": MAX_ITERATIONS, "ftol": 1e-12})
            z = np.clip(sol.x, lo, hi)
            if ev.met(z) and not any(np.max(np.abs(z - f)) < 1e-3 for f in found):
                found.append(z)
        if found:
            break
    solutions = sorted((_solution(problem, z) for z in found), key=lambda s: s.distance)[:problem.solutions]
    if solutions:
        return Found(problem, solutions, None, time.perf_counter() - t0)
    return Found(problem, [], _closest(problem, ev, points), time.perf_counter() - t0)


def _found_words(problem: Problem, solutions: list[Solution], words: Words) -> str:
    best = solutions[0]
    before, after = problem.values(problem.start), problem.values(best.design)
    changes = ", ".join(f"{words.name(n)} {words.change(after[n] / before[n] - 1)}" for n in problem.variables
                        if abs(after[n] / before[n] - 1) > 1e-9) or "nothing"
    count = "1 design meets" if len(solutions) == 1 else f"{len(solutions)} designs meet"
    binding = f"; the limits that bind there: {', '.join(map(words.limit, best.binding))}" if best.binding else ""
    return f"{count} every target. The nearest to the start changes {changes}{binding}."


def _closest(problem: Problem, ev: _Evaluator, points) -> Solution:
    """The design that misses the targets least within the limits (b's range, each drive's
    strain). First least squares on every negative log-margin, limits and targets alike, which
    keeps the limits wherever they can be kept; if a far-off target outweighed a limit in that
    sum (a |K| of 1e300 N/m put b at 1 m against a limit of 0.04 m), the targets' misses are
    minimised again with the limits held as constraints."""
    lo, hi = problem.bounds()
    n_limits = 2 + sum(len(t.modes) for t in problem.targets)  # the first margins (_Evaluator._both)
    best = None
    for z0 in points[:4]:
        try:
            sol = least_squares(lambda z: np.minimum(ev.margins(z), 0.0), np.clip(z0, lo, hi), bounds=(lo, hi),
                                method="trf", max_nfev=CLOSEST_NFEV)
        except ValueError:
            continue
        if best is None or sol.cost < best.cost:
            best = sol
    if best is not None and np.min(ev.margins(best.x)[:n_limits]) >= 0.0:
        return _solution(problem, best.x)
    return _solution(problem, _closest_within_limits(ev, points, lo, hi, n_limits))


def _closest_within_limits(ev: _Evaluator, points, lo, hi, n_limits: int) -> np.ndarray:
    """The targets' squared misses minimised by SLSQP with the limits held (1e-7 inside them:
    SLSQP meets a constraint to about 1e-8); the objective scaled to order one at each start,
    which keeps the constraints tight."""

    def shortfall(z):
        miss = np.minimum(ev.margins(z)[n_limits:], 0.0)
        return float(miss @ miss)

    limits = {"type": "ineq", "fun": lambda z: ev.margins(z)[:n_limits] - INSIDE}
    best = None
    for z0 in points[:4]:
        z0 = np.clip(z0, lo, hi)
        scale = max(shortfall(z0), 1.0)
        sol = minimize(lambda z, s=scale: shortfall(z) / s, z0, method="SLSQP", bounds=list(zip(lo, hi)),
                       constraints=[limits], options={"maxiter": MAX_ITERATIONS, "ftol": 1e-14})
        z = np.clip(sol.x, lo, hi)
        if np.min(ev.margins(z)[:n_limits]) >= 0.0 and (best is None or shortfall(z) < best[0]):
            best = (shortfall(z), z)
    return best[1] if best is not None else np.clip(points[0], lo, hi)


def _why(problem: Problem, closest: Solution, words: Words) -> str:
    missed = [f"{words.target(t)} is missed by {words.change(t.misses(v))} (it reaches {words.reached(t, v)})"
              for t, v in zip(problem.targets, closest.achieved) if abs(t.misses(v)) > 1e-6]
    if not missed:
        missed = ["the drive of a target would strain the rubber beyond what it survives"]
    if closest.binding:
        cause = f"the limits that bind there: {', '.join(map(words.limit, closest.binding))}"
    else:
        cause = "no limit binds there: the targets contradict each other"
    return f"The targets cannot be met. At the closest design, {'; '.join(missed)}; {cause}."
