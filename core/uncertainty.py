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
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import f as f_distribution

CONFIDENCE = 0.95
# the smallest residual scale trusted (relative error): exact or noise-free data still get
# intervals of a meaningful width rather than of round-off
NOISE_FLOOR = 1e-4
MAX_STEPS = 40  # outward steps per side (each doubles the step, capped at a tenth of the range)
BISECTIONS = 4  # refinements of a crossing
TIME_LIMIT_S = 60.0  # all profiles of one fit together


@dataclass(frozen=True)
class Profile:
    """Intervals in fitted coordinates, one (low, high) per parameter; ``None`` for a side the
    data do not bound within the fitting range. ``better`` is a point with a lower sum of squares
    than the optimum the profile started from, if the walk found one (the fit was not global)."""

    intervals: list[tuple[float | None, float | None]]
    better: np.ndarray | None
    threshold: float  # allowed rise of the sum of squares
    complete: bool  # False if the time limit stopped the walk (unfinished sides are open)


def profile(residuals: Callable[[np.ndarray], np.ndarray], theta: np.ndarray, lower, upper,
            step, *, confidence: float = CONFIDENCE, time_limit: float = TIME_LIMIT_S) -> Profile:
    """Profile every parameter of the least-squares problem ``residuals`` about its optimum
    ``theta`` within the bounds; ``step`` gives each parameter's first step (for example its
    linearised standard error, in the same coordinates)."""
    theta = np.asarray(theta, dtype=float)
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    r0 = residuals(theta)
    s_min = float(r0 @ r0)
    n, p = r0.size, theta.size
    dof = max(n - p, 1)
    s2 = max(s_min / dof, NOISE_FLOOR**2)
    threshold = s2 * float(f_distribution.ppf(confidence, 1, dof))
    deadline = time.monotonic() + time_limit
    walker = _Walker(residuals, theta, lower, upper, s_min, threshold, deadline)
    intervals = []
    for j in range(p):
        sides = []
        for direction in (-1.0, 1.0):
            sides.append(walker.side(j, direction, _first_step(step[j], upper[j] - lower[j])))
        intervals.append((sides[0], sides[1]))
    return Profile(intervals, walker.better, threshold, not walker.late)


def _first_step(step: float, span: float) -> float:
    step = abs(float(step)) if math.isfinite(step) else span
    return float(np.clip(step, span * 1e-6, span / 20))


class _Walker:
    def __init__(self, residuals, theta, lower, upper, s_min, threshold, deadline):
        self.residuals, self.theta, self.lower, self.upper = residuals, theta, lower, upper
        self.s_min, self.threshold, self.deadline = s_min, threshold, deadline
        self.better: np.ndarray | None = None
        self.best_s = s_min
        self.late = False

    def refit(self, j: int, value: float, starts: list[np.ndarray]) -> tuple[float, np.ndarray]:
        """The sum of squares with parameter ``j`` held at ``value``, the others refitted (from
        each of ``starts``, the best kept); the others' values."""
        others = np.arange(self.theta.size) != j

        def full(x):
            t = self.theta.copy()
            t[j], t[others] = value, x
            return t

        best = (math.inf, starts[0])
        for x0 in starts:
            if not others.any():
                r = self.residuals(full(x0))
                s, x = float(r @ r), x0
            else:
                lo, hi = self.lower[others], self.upper[others]
                try:
                    sol = least_squares(lambda x: self.residuals(full(x)), np.clip(x0, lo, hi),
                                        bounds=(lo, hi), method="trf", x_scale="jac", xtol=1e-10,
                                        ftol=1e-12, gtol=1e-12, max_nfev=200)
                except (ValueError, ArithmeticError):
                    continue
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
        optimum; ``None`` if it does not before the bound (or before the time runs out)."""
        others = np.arange(self.theta.size) != j
        x_hat = self.theta[others]
        edge = self.lower[j] if direction < 0 else self.upper[j]
        span = self.upper[j] - self.lower[j]
        inside, x_in, rise_in = float(self.theta[j]), x_hat, 0.0
        for _ in range(MAX_STEPS):
            if abs(edge - inside) <= 1e-12 * max(span, 1.0):
                return None  # the optimum sits at the bound: nothing beyond it to test
            if time.monotonic() > self.deadline:
                self.late = True
                return None
            value = inside + direction * step
            at_edge = direction * (value - edge) >= 0
            if at_edge:
                value = edge
            s, x = self.refit(j, value, [x_in, x_hat])
            rise = s - self.s_min
            if rise > self.threshold:
                return self._crossing(j, (inside, x_in, rise_in), (value, x, rise), x_hat)
            inside, x_in, rise_in = value, x, max(rise, 0.0)
            if at_edge:
                return None
            step = min(2.0 * step, span / 10)
        return None

    def _crossing(self, j, inner, outer, x_hat) -> float:
        """Bisect between a point inside and one outside, then interpolate the signed root
        sqrt(rise), which is linear in a parameter the model is linear in."""
        (a, xa, ra), (b, _, rb) = inner, outer
        for _ in range(BISECTIONS):
            mid = 0.5 * (a + b)
            s, x = self.refit(j, mid, [xa, x_hat])
            rise = s - self.s_min
            if rise > self.threshold:
                b, rb = mid, rise
            else:
                a, xa, ra = mid, x, max(rise, 0.0)
        root_a, root_b, root_t = math.sqrt(ra), math.sqrt(rb), math.sqrt(self.threshold)
        if root_b <= root_a:
            return b
        return a + (b - a) * (root_t - root_a) / (root_b - root_a)
