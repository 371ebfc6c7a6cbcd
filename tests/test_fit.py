"""Parameter identification: known parameters recovered from synthetic noisy data, within the
reported standard errors; the thesis' two-step procedure; the loop's harmonic."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core import PAPER_B, TABLE_1, stiffness, stiffness_points
from core.data import MeasuredLoop
from core.identify.fit import fit_global, fit_two_step
from core.parameters import MATERIAL as PARAMETERS
from core.parts import as_dict
from core.synthetic import synthetic_loop as make_loop
from core.synthetic import synthetic_stiffness

NOISE = 0.005


def synthetic(design, freqs, amps, seed, noise=NOISE):
    return synthetic_stiffness(design, freqs, amps, noise=noise, seed=seed)


def synthetic_loop(design, f, amp, seed, periods=2, per_period=200, phase=0.3, offset=(2e-6, 15.0)):
    lp = make_loop(design, f, amp, periods=periods, per_period=per_period, phase=phase, seed=seed)
    return MeasuredLoop(lp.time_s, lp.displacement + offset[0], lp.force + offset[1])


CASES = {
    "axial": (PAPER_B, np.linspace(1, 100, 30), [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3]),
    "torsion": (TABLE_1, np.linspace(10, 100, 30), [1.74e-5, 1.74e-4, 1.74e-3, 1.74e-2, 1.74e-1]),
}
GUESSES = [
    {"shear_modulus": 0.6, "fractional_coefficient": 1.7, "fractional_order": 0.4, "friction_stress_max": 2.0, "friction_strain_half": 0.25},
    {"shear_modulus": 1.6, "fractional_coefficient": 0.4, "fractional_order": 0.7, "friction_stress_max": 0.5, "friction_strain_half": 3.0},
    {"shear_modulus": 1.0, "fractional_coefficient": 1.0, "fractional_order": 0.1, "friction_stress_max": 1.0, "friction_strain_half": 1.0},
]


def guess(design, factors):
    values = as_dict(design.material)
    changed = {k: (factors[k] if k == "fractional_order" else values[k] * factors[k]) for k in factors}
    return design.replace(**changed)


@pytest.mark.parametrize("mode", ["axial", "torsion"])
@pytest.mark.parametrize("start", range(len(GUESSES)))
def test_recovers_known_parameters_within_standard_errors(mode, start):
    design, freqs, amps = CASES[mode]
    data = synthetic(design, freqs, amps, seed=11)
    result = fit_global(guess(design, GUESSES[start]), data)
    truth = as_dict(design.material)
    for p in PARAMETERS:
        z = (getattr(result.design.material, p) - truth[p]) / result.standard_errors[p]
        assert abs(z) < 4, (p, z)
    # what is left is the noise: |n|² has mean 2·NOISE²
    assert result.gap == pytest.approx(NOISE * np.sqrt(2), rel=0.25)


def test_standard_errors_are_calibrated():
    """Across noise realisations the errors divided by the reported standard errors spread
    like a unit normal (the delta-method covariance is honest)."""
    design, freqs, amps = CASES["axial"]
    z = {p: [] for p in PARAMETERS}
    for seed in range(24):
        r = fit_global(design, synthetic(design, freqs, amps, seed=100 + seed), starts=1)
        for p in PARAMETERS:
            z[p].append((getattr(r.design.material, p) - getattr(design.material, p)) / r.standard_errors[p])
    for p in PARAMETERS:
        spread = np.std(z[p])
        assert 0.55 < spread < 1.6, (p, spread)
        assert abs(np.mean(z[p])) < 3 * 1.6 / np.sqrt(24), p


def test_correlation_is_a_correlation_matrix():
    design, freqs, amps = CASES["torsion"]
    r = fit_global(design, synthetic(design, freqs, amps, seed=3))
    m = np.array([[r.correlation[a][b] for b in PARAMETERS] for a in PARAMETERS])
    assert_allclose(np.diag(m), 1.0, atol=1e-9)
    assert_allclose(m, m.T, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(m) > -1e-9)


def test_the_thesis_two_step_procedure_predicts_other_amplitudes():
    """Paper B: the 0.1 Hz, 1 mm loop and the 1–100 Hz sweep at 0.1 mm identify the model;
    it then predicts the other amplitudes to the noise."""
    design = PAPER_B
    loop = synthetic_loop(design, 0.1, 1e-3, seed=5)
    sweep = synthetic(design, np.arange(1.0, 101.0), [0.1e-3], seed=6)
    start = guess(design, GUESSES[0])
    result = fit_two_step(start, loop, sweep)
    others = synthetic(design, np.linspace(1, 100, 20), [0.013e-3, 0.04e-3, 0.17e-3, 0.25e-3, 0.35e-3], seed=7)
    predicted = stiffness_points(result.design, others.frequency_hz, others.amplitude)
    from core.residuals import gap

    assert gap(predicted, others.stiffness) < 2 * NOISE * np.sqrt(2)
    assert result.loop_rms < 0.02 and result.method == "two-step"
    for p in PARAMETERS:
        z = (getattr(result.design.material, p) - getattr(design.material, p)) / result.standard_errors[p]
        assert abs(z) < 4, (p, z)


def test_loop_alone_with_the_sweep_in_one_global_fit():
    design = PAPER_B
    result = fit_global(guess(design, GUESSES[1]), synthetic(design, np.arange(1.0, 101.0, 3), [0.1e-3], seed=8),
                        loop=synthetic_loop(design, 0.1, 1e-3, seed=9))
    for p in PARAMETERS:
        z = (getattr(result.design.material, p) - getattr(design.material, p)) / result.standard_errors[p]
        assert abs(z) < 4, (p, z)


def test_loop_harmonic_recovers_frequency_amplitude_and_phase():
    lp = synthetic_loop(PAPER_B, 0.37, 2.5e-4, seed=1, periods=3, per_period=97, phase=1.1)
    f, amp, theta = lp.harmonic()
    assert f == pytest.approx(0.37, rel=1e-6)
    assert amp == pytest.approx(2.5e-4, rel=1e-4)
    assert_allclose(np.sin(theta), np.sin(2 * np.pi * 0.37 * lp.time_s + 1.1), atol=1e-4)


def test_too_few_points_or_no_data_refused():
    data = synthetic(PAPER_B, [10.0], [1e-4], seed=0)
    with pytest.raises(ValueError, match="cannot determine"):
        fit_global(PAPER_B, data)
    with pytest.raises(ValueError, match="give measured"):
        fit_global(PAPER_B)


def test_fit_report_is_the_design_file_plus_fit(tmp_path):
    import json

    from core import loads_design

    design, freqs, amps = CASES["axial"]
    r = fit_global(design, synthetic(design, freqs, amps, seed=2), starts=2)
    text = json.dumps(r.to_dict())
    assert loads_design(text).material == r.design.material
    report = json.loads(text)["fit"]
    assert set(report["standard_errors"]) == set(PARAMETERS)
    assert report["gap"] == pytest.approx(r.gap)
    # the fitted model reproduces the grid computation
    assert_allclose(stiffness_points(r.design, 10.0, 1e-4), stiffness(r.design, 10.0, 1e-4).stiffness[0, 0])


def test_a_refitted_design_is_named_fitted_once():
    from core.identify.diagnose import diagnose
    from core.identify.fit import fitted_name
    from core.synthetic import synthetic_stiffness

    assert fitted_name("VP") == "VP (fitted)" == fitted_name("VP (fitted)")
    assert fitted_name(None) is None
    data = synthetic_stiffness(PAPER_B, np.linspace(1, 100, 10), [1e-5, 1e-4, 1e-3], seed=1)
    report = diagnose(PAPER_B, data, held_out=False).report()
    assert report["design"]["name"] == f"{PAPER_B.name} (fitted)"


def test_progress_tells_where_the_fit_is_and_changes_nothing():
    """``progress`` hears every start of how many, then the profile, its fractions never going
    back and within 0–1; the result is the same fit as without it (issue #27 item 12)."""
    design, freqs, amps = CASES["axial"]
    data = synthetic(design, freqs, amps, seed=4)
    heard = []
    quiet = fit_global(design, data, starts=3)
    told = fit_global(design, data, starts=3, progress=lambda f, m: heard.append((f, m)))
    assert told.to_json() == quiet.to_json()
    messages = [m for _, m in heard]
    assert [m for m in messages if "," not in m][:3] == ["start 1 of 3", "start 2 of 3", "start 3 of 3"]
    assert any(m.startswith("profiling the intervals") for m in messages)
    fractions = [f for f, _ in heard]
    assert all(0.0 <= f <= 1.0 for f in fractions) and fractions == sorted(fractions)


def test_two_step_progress_names_its_rounds():
    design, freqs, _ = CASES["axial"]
    loop = synthetic_loop(design, 0.1, 1e-4, seed=5)
    sweep = synthetic(design, freqs, [1e-4], seed=6)
    heard = []
    told = fit_two_step(design, loop, sweep, progress=lambda f, m: heard.append((f, m)))
    assert told.to_json() == fit_two_step(design, loop, sweep).to_json()
    messages = [m for _, m in heard]
    for words in ("round 1 of 2, the loop: start 1 of 4", "round 2 of 2, the sweep: start 1 of 4",
                  "all five together, start 1 of 1"):
        assert words in messages, words
    assert all(0.0 <= f <= 1.0 for f, _ in heard)
