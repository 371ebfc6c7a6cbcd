"""The work of a diagnosis, counted (issue #27, item 16): the diagnosis of the 150 points the
browser benchmark uploads stays within a count of model evaluations (counts, not seconds: they
do not depend on the machine's load), and the profile's cheaper crossing search still finds the
crossing a fine search finds."""

import functools
import math

import numpy as np
import pytest
from scipy import optimize, stats

import core.identify.fit as fit_module
from core import PAPER_B
from core.identify.diagnose import diagnose
from core.identify.uncertainty import CROSSING_TOLERANCE, profile
from core.synthetic import synthetic_stiffness

# the model evaluations of the 150-point diagnosis's fits (calls of stiffness_points, and the
# parameter sets of each call of core.points.PointsModel, a finite-difference Jacobian's columns
# at once): 10,563 before the profile's crossings were interpolated (the final profile 3,242 of
# them), 9,605 after (2,284); 6,315 once a start that joins an earlier start's path stops there
# (the viscous candidate's three starts crept side by side, 3,476 evaluations; 1,295 now), 6,004
# once the profile's refits start on the line through the path's last two points (1,973)
MAX_EVALUATIONS = 6_400
MAX_PROFILE_EVALUATIONS = 2_150
MAX_CANDIDATE_EVALUATIONS = 1_500  # any one candidate's fit
# passes of the model over the points (a Jacobian's columns one pass): 9,605 when each evaluation
# was one, 2,122 with the columns together
MAX_PASSES = 2_300


def test_the_150_point_diagnosis_stays_within_its_count_of_model_evaluations(monkeypatch):
    hidden = PAPER_B.replace(effects={"inertia": {"mass": 0.5}})
    data = synthetic_stiffness(hidden, np.linspace(1, 100, 30), [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3],
                               noise=0.005, seed=3)  # benchmarks/diagnose_browser.py's file
    counts: dict[str, int] = {}
    passes = [0]
    stage = ["start"]
    original = fit_module.stiffness_points

    def counted(*args, **kwargs):
        counts[stage[0]] = counts.get(stage[0], 0) + 1
        passes[0] += 1
        return original(*args, **kwargs)

    monkeypatch.setattr(fit_module, "stiffness_points", counted)
    points = getattr(fit_module, "PointsModel", None)  # many parameter sets in one pass (absent before)
    if points is not None:
        original_call = points.__call__

        def counted_call(self, values):
            k = original_call(self, values)
            counts[stage[0]] = counts.get(stage[0], 0) + len(k)
            passes[0] += 1
            return k

        monkeypatch.setattr(points, "__call__", counted_call)
    result = diagnose(PAPER_B, data, progress=lambda _f, message: stage.__setitem__(0, message))

    assert result.added == ["inertia"]  # the work counted is that of the right answer
    step = result.steps[0]
    assert abs(step.parameters["mass"] - 0.5) < 3 * step.standard_errors["mass"]
    assert counts["profiling the final model's parameters"] <= MAX_PROFILE_EVALUATIONS
    candidates = {s: n for s, n in counts.items() if s.startswith("step ")}
    assert max(candidates.values()) <= MAX_CANDIDATE_EVALUATIONS, candidates
    assert sum(counts.values()) <= MAX_EVALUATIONS
    assert passes[0] <= MAX_PASSES


def test_the_profile_crossing_is_where_a_fine_search_puts_it():
    """y = a·exp(−b·x) + noise (nonlinear in b): each end of each profile interval against the
    root of the profile's rise minus the threshold found by Brent's method on exact refits."""
    rng = np.random.default_rng(11)
    x = np.linspace(0.0, 4.0, 30)
    y = 2.0 * np.exp(-0.8 * x) + 0.05 * rng.standard_normal(x.size)

    def residuals(theta):
        return theta[0] * np.exp(-theta[1] * x) - y

    fit = optimize.least_squares(residuals, [1.0, 1.0], xtol=1e-15, ftol=1e-15, gtol=1e-15)
    s_min = float(fit.fun @ fit.fun)
    threshold = s_min / (x.size - 2) * stats.f.ppf(0.95, 1, x.size - 2)
    sd = np.sqrt(np.diag(np.linalg.inv(fit.jac.T @ fit.jac)) * s_min / (x.size - 2))

    prof = profile(residuals, fit.x, [-10.0, -10.0], [10.0, 10.0], sd)

    def rise(j, value):  # the profile exactly: the other parameter refitted from the optimum
        other = 1 - j

        def r(free):
            theta = np.empty(2)
            theta[j], theta[other] = value, free[0]
            return residuals(theta)

        sol = optimize.least_squares(r, [fit.x[other]], xtol=1e-15, ftol=1e-15, gtol=1e-15)
        return float(sol.fun @ sol.fun) - s_min - threshold

    assert prof.complete and prof.better is None
    for j, (lo, hi) in enumerate(prof.intervals):
        for end, outward in ((lo, -1.0), (hi, 1.0)):
            truth = optimize.brentq(functools.partial(rise, j), fit.x[j], fit.x[j] + outward * 10 * sd[j], xtol=1e-14)
            # g = sqrt(rise) − sqrt(threshold) within the tolerance: the end within about that
            # fraction of its distance from the optimum
            assert end == pytest.approx(truth, abs=3 * CROSSING_TOLERANCE * abs(truth - fit.x[j]))
            assert not math.isclose(end, fit.x[j])


@pytest.mark.parametrize("effects", [{}, {"inertia": {"mass": 0.4}}, {"viscous": {"viscosity": 80.0}},
                                     {"strain_stiffening": {"stiffening": 3.0}},
                                     {"rate_amplitude_coupling": {"rate_exponent": 0.1}},
                                     {"wave_effects": {"density": 1100.0}}])
def test_the_model_of_many_parameter_sets_at_once_gives_each_design_s_own_numbers(effects):
    """core.points.PointsModel (a Jacobian's columns in one pass) against stiffness_points of each
    design alone: the same numbers, bit for bit; values outside a fitting range refused."""
    from core.bushing import stiffness_points
    from core.points import PointsModel
    from core.registry import parameter, parameter_values, with_values

    design = PAPER_B.replace(effects=effects)
    names = tuple(parameter_values(design))
    f = np.repeat(np.linspace(1, 100, 30), 5)
    x = np.tile([0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3], 30)
    base = np.array([parameter_values(design)[n] for n in names])
    rows = [base] + [base * np.where(np.arange(base.size) == j, 1.01, 1.0) for j in range(base.size)]
    rows.append(base * 1.01)  # two rows alike: a parameter's values repeat, as in a Jacobian
    rows.append(base * 1.01)
    k = PointsModel(design, names, f, x)(np.array(rows))
    for row, values in zip(k, rows):
        alone = stiffness_points(with_values(design, dict(zip(names, values))), f, x)
        assert np.array_equal(row, alone)
    j = names.index("fractional_order")
    high = np.array(rows[:1])
    high[0, j] = parameter("fractional_order").bounds[1] * 1.5
    with pytest.raises(ValueError, match="fractional_order"):
        PointsModel(design, names, f, x)(high)
