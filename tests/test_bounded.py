"""Work bounded by counts, never by the clock: an absurd but valid design is searched in a
bounded number of model evaluations and gets the statement its data support (a parameter the
data do not see is undetermined), whatever the machine's speed; and an apparent mass is shown in
its mode's one unit, kg in a translation, kg·m² in a rotation."""

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from core import PAPER_B, TABLE_1
from core.identify import fit as fit_module
from core.identify.diagnose import diagnose, summary
from core.identify.fit import fit_global
from core.identify.uncertainty import SIDE_EVALUATIONS, minimise, profile
from core.io.design_file import read_design
from core.io.measured import read_stiffness
from core.io.targets import problem_from_dict
from core.numbers import format_number
from core.registry import parameter_unit
from core.synthetic import synthetic_stiffness
from core.whatif import target as target_module

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.fixture
def evaluations(monkeypatch):
    """Counts every evaluation of a fit's residuals (the model at every data point): the work,
    a finite-difference Jacobian's columns evaluated together (_Problem.residuals_many) each one."""
    count = [0]
    residuals, many = fit_module._Problem.residuals, fit_module._Problem.residuals_many

    def counted(self, theta):
        count[0] += 1
        return residuals(self, theta)

    def counted_many(self, thetas):
        count[0] += len(thetas)
        return many(self, thetas)

    monkeypatch.setattr(fit_module._Problem, "residuals", counted)
    monkeypatch.setattr(fit_module._Problem, "residuals_many", counted_many)
    return count


def _linear_problem(seed=4):
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 3.0, 25)
    y = 1.5 - 0.7 * x + 0.2 * rng.standard_normal(x.size)
    design = np.column_stack([np.ones_like(x), x])
    return design, y


# ---- the counts themselves -------------------------------------------------------------------

def test_a_least_squares_search_never_spends_more_than_its_allowance():
    """Rosenbrock's valley (minimum at (1, 1), known in closed form) from (−1.2, 1): the whole
    search converges there; with an allowance of 30 evaluations it spends no more and says it
    was cut short."""
    spent = [0]

    def rosenbrock(x):
        spent[0] += 1
        return np.array([10.0 * (x[1] - x[0] ** 2), 1.0 - x[0]])

    lo, hi = np.array([-5.0, -5.0]), np.array([5.0, 5.0])
    sol, cut = minimise(rosenbrock, np.array([-1.2, 1.0]), lo, hi, (20, 40, 100), xtol=1e-12)
    assert not cut
    np.testing.assert_allclose(sol.x, [1.0, 1.0], atol=1e-6)  # converged: far below 1e-6
    spent[0] = 0
    sol, cut = minimise(rosenbrock, np.array([-1.2, 1.0]), lo, hi, (20, 40, 100), xtol=1e-12, allowance=30)
    assert cut and spent[0] <= 30


def test_a_side_that_spends_its_evaluations_is_open_and_the_profile_says_so():
    """The same linear model twice: with the default count the intervals are the classical
    t-intervals and the profile is complete; allowed 3 evaluations a side, no side can finish:
    every side is open and the profile says it is not complete. Counts decide, not the clock."""
    design, y = _linear_problem()
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    dof = y.size - 2
    se = np.sqrt(np.sum((design @ coef - y) ** 2) / dof * np.diag(np.linalg.inv(design.T @ design)))
    half = stats.t.ppf(0.975, dof) * se

    full = profile(lambda c: design @ c - y, coef, [-100, -100], [100, 100], se)
    assert full.complete and full.evaluations <= 4 * SIDE_EVALUATIONS + 1
    for (lo, hi), c, h in zip(full.intervals, coef, half):
        assert lo == pytest.approx(c - h, rel=1e-6) and hi == pytest.approx(c + h, rel=1e-6)

    cut = profile(lambda c: design @ c - y, coef, [-100, -100], [100, 100], se, evaluations=3)
    assert not cut.complete and cut.intervals == [(None, None), (None, None)]
    assert cut.evaluations <= 4 * 3 + 1


def test_a_material_bound_is_worded_in_the_unit_of_its_field():
    """A sweep at one amplitude cannot fix µ apart from the friction branch: the warning gives
    µ's bound in MPa, the unit of its field in the explorer, from the one formatter (issue #27,
    items 5 and 7; it read "any value up to 3550000 Pa"); ε½, a pure number, stays bare."""
    design = read_design(EXAMPLES / "paper_b_guess.json")
    result = fit_global(design, read_stiffness(EXAMPLES / "paper_b_sweep_0.1mm.csv"))
    low, high = result.intervals["shear_modulus"]
    assert low is None and high is not None
    text = " ".join(result.warnings)
    assert f"shear_modulus is not determined by these data: any value up to {format_number(high / 1e6, 3)} MPa fits" in text
    assert " Pa " not in text and "000 " not in text
    low, high = result.intervals["friction_strain_half"]
    assert f"friction_strain_half is not determined by these data: any value up to {format_number(high, 3)} fits" in text


def test_a_parameter_the_data_do_not_see_is_open_up_to_the_end_of_its_range():
    """Data without friction (σ_fmax = 1 Pa, nothing at these strains): ε½ acts on nothing, so
    every value in its range fits them as well. The walk reaches ε½'s upper end, 10, which
    the model must accept (exp(ln 10) is a hair above 10: it used to be refused there, and the
    refusal read as a crossing just below 10 and a warning that the model cannot follow)."""
    truth = PAPER_B.replace(friction_stress_max=1.0)
    data = synthetic_stiffness(truth, np.linspace(1, 100, 20), [1e-5, 1e-4, 3.5e-4], noise=0.005, seed=3)
    result = fit_global(PAPER_B, data)
    assert result.intervals["friction_strain_half"] == (None, None)
    assert any(w.startswith("friction_strain_half is not determined by these data: any value in its fitting range")
               for w in result.warnings)
    assert not any("ran to the" in w for w in result.warnings)


# ---- absurd designs --------------------------------------------------------------------------

def _with_effects(path, effects):
    return read_design(path).replace(effects=effects)


def test_an_absurd_mass_is_undetermined_after_bounded_work(evaluations):
    """Paper B's five-amplitude data have no fixture mass; a design claims 1e300 kg. The mass is
    refitted from the end of its range (1e4 kg) and comes out undetermined: any mass up to a
    bound fits. That bound is far below the 5 % of |K| at the top frequency that a mass would
    take (ω²M = 0.05 |K|, ten times the data's 0.5 % noise) and the work is bounded: the profile
    of six parameters may spend 12 · SIDE_EVALUATIONS = 36 000 evaluations by construction, the
    searches about 10 000; the clock-bounded walk spent about 120 000 (40 s)."""
    data = read_stiffness(EXAMPLES / "paper_b_stiffness.csv")
    design = _with_effects(EXAMPLES / "paper_b_true.json", {"inertia": {"mass": 1e300}})
    result = diagnose(design, data)

    assert evaluations[0] < 50_000
    final = result.final.fit
    assert "inertia.mass" in final.undetermined
    low, high = final.intervals["inertia.mass"]
    top = int(np.argmax(data.frequency_hz))
    visible = 0.05 * abs(data.stiffness[top]) / (2 * np.pi * data.frequency_hz[top]) ** 2
    assert low is None and 0 < high < visible
    assert result.final.fit.design.effects  # the mass is still in the model, refitted
    assert any(w.startswith("inertia.mass is not determined") and f"{high:.3g} kg " in w for w in final.warnings)


def test_a_fixed_mass_of_1e300_kg_refuses_the_fit_at_once(evaluations):
    """`bushing fit` holds the design's effects: with 1e300 kg the model misses every point by
    about 1e300 times, beyond any fit. Each of the 8 starts is refused at its first point, after
    the model there and its finite-difference Jacobian (1 + 5 evaluations); it used to walk
    24 000 evaluations through overflowed sums of squares and call everything undetermined."""
    data = read_stiffness(EXAMPLES / "paper_b_with_fixture_mass.csv")
    design = _with_effects(EXAMPLES / "paper_b_true.json", {"inertia": {"mass": 1e300}})
    with pytest.raises(ValueError, match="misses the data by more than"):
        fit_global(design, data)
    assert evaluations[0] <= 8 * (1 + 5)


def test_a_design_mass_of_zero_still_finds_the_fixture():
    """A design with "mass": 0 (valid: not negative) starts the mass's search at the low end of
    its range, where the mass does nothing; the starts spread over the whole range find the
    fixture all the same: the mass the diagnosis finds for a design without one."""
    data = read_stiffness(EXAMPLES / "paper_b_with_fixture_mass.csv")
    plain = diagnose(read_design(EXAMPLES / "paper_b_true.json"), data, held_out=False)
    zero = diagnose(_with_effects(EXAMPLES / "paper_b_true.json", {"inertia": {"mass": 0.0}}), data,
                    held_out=False)
    step = plain.steps[0]
    assert plain.added == ["inertia"] and zero.added == []  # the mass is in the zero's baseline
    mass = zero.final.design.effect_parameters["inertia"]["mass"]
    assert mass == pytest.approx(step.parameters["mass"], abs=2 * step.standard_errors["mass"])


def test_impossible_targets_are_searched_in_bounded_work(monkeypatch):
    """Six contradicting targets with the whole compound free (eight variables): the search stops
    starting points after TARGET_EVALUATIONS; the start under way adds at most MAX_ITERATIONS
    iterations of (n + 1) constraint evaluations and a short line search; the closest miss four
    least-squares searches of CLOSEST_NFEV iterations and, if they leave a limit, four
    constrained ones like the start's. (Bounded by 20 s, it spent 150 000.)"""
    spent = [0]
    both = target_module._Evaluator._both

    def counted(self, z):
        if np.asarray(z, float).tobytes() not in self.cache:
            spent[0] += len(self.problem.targets)
        return both(self, z)

    monkeypatch.setattr(target_module._Evaluator, "_both", counted)
    free = {"shear_modulus": {"min": 1e5, "max": 1e8}, "fractional_coefficient": {"min": 1e4, "max": 1e8},
            "fractional_order": {"min": 0.05, "max": 0.9}, "friction_stress_max": {"min": 1e3, "max": 1e6},
            "friction_strain_half": {"min": 1e-4, "max": 1e-1}}
    targets = []
    for i, mode in enumerate(["axial", "torsion", "radial", "conical", "axial", "torsion"]):
        amp = 1e-4 if mode in ("axial", "radial") else 1e-3
        if i % 2 == 0:
            targets.append({"mode": mode, "frequency_hz": 1 + 10 * i, "amplitude": amp,
                            "magnitude": 1e6 * (1 + i) if amp == 1e-4 else 1e3 * (1 + i)})
        else:
            targets.append({"mode": mode, "frequency_hz": 1 + 10 * i, "amplitude": amp, "loss_factor": 0.05 + 0.3 * i})
    problem = problem_from_dict({"design": PAPER_B.to_dict(), "targets": targets, "free_material": free})
    found = target_module.solve(problem)
    assert not found.feasible and "cannot be met" in found.statement
    n = len(problem.variables)
    bound = (target_module.TARGET_EVALUATIONS
             + target_module.MAX_ITERATIONS * (n + 4) * len(targets)
             + 4 * target_module.CLOSEST_NFEV * (n + 1) * len(targets)
             + 4 * target_module.MAX_ITERATIONS * (n + 4) * len(targets))
    assert spent[0] <= bound


# ---- the unit of an apparent mass -------------------------------------------------------------

def test_a_mass_is_in_kg_in_translations_and_kg_m2_in_rotations():
    """A translation's rig carries a mass (kg), a rotation's a moment of inertia (kg·m²); a rig
    effect tied to another mode is in that mode's unit."""
    assert [parameter_unit("inertia.mass", m) for m in ("axial", "radial", "torsion", "conical")] == [
        "kg", "kg", "kg·m²", "kg·m²"]
    assert parameter_unit("inertia@torsion.mass", "axial") == "kg·m²"
    assert parameter_unit("inertia@radial.mass", "conical") == "kg"
    assert parameter_unit("viscous.viscosity", "torsion") == "Pa·s"


@pytest.mark.parametrize("design, unit", [(PAPER_B, "kg"), (TABLE_1, "kg·m²")])
def test_the_diagnosis_words_a_mass_in_its_modes_unit(design, unit):
    """Data without a fixture, a design that carries an apparent mass: the data do not see a
    small mass, and the diagnosis says up to what mass, in kg on the axial rig and in kg·m² on
    the torsion rig (it used to print kg/kg·m² for both)."""
    amplitudes = (1e-5, 4e-5, 1e-4, 1.7e-4, 3.5e-4) if design.mode == "axial" else tuple(np.geomspace(1e-4, 1e-1, 5))
    data = synthetic_stiffness(design, np.linspace(1.0, 100.0, 30), amplitudes, noise=0.005, seed=7)
    result = diagnose(design.replace(effects={"inertia": {"mass": 1e-3}}), data, held_out=False)
    low, high = result.final.fit.intervals["inertia.mass"]
    assert low is None
    text = summary(result)
    assert f"inertia.mass is not determined by these data: any value up to {format_number(high, 3)} {unit} fits" in text
    assert "kg/" not in text
