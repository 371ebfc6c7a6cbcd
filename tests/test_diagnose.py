"""The discrepancy workflow: effects hidden in synthetic data with 0.5 % noise; the
workflow is not told which. The noise fixes the floor: complex relative noise with 0.5 % in each
part gives a gap of sqrt(2) · 0.005 ≈ 0.0071."""

import functools
import json
import math

import numpy as np
import pytest

from cli.commands import main
from core.bushing import shape_factor, stiffness_points
from core.data import MeasuredStiffness
from core.design import PAPER_B, TABLE_1
from core.effects import EFFECTS
from core.identify.diagnose import BRANCHES, OFF, describe, diagnose, noise_variance, summary
from core.io.design_file import design_from_dict, write_design
from core.io.measured import read_stiffness
from core.synthetic import synthetic_stiffness

NOISE = 0.005
NOISE_GAP = math.sqrt(2) * NOISE
F_SWEEP = np.linspace(1.0, 100.0, 30)
A_PAPER_B = (0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3)
A_TABLE_1 = tuple(np.geomspace(1e-4, 1e-1, 5))
K_100HZ = abs(complex(stiffness_points(PAPER_B, 100.0, 0.1e-3)))

# Every effect of the library, hidden at a realistic size in a realistic test programme:
# (design, baseline branches, hidden effects, frequencies, amplitudes, fitted values to recover)
HIDDEN = {
    "friction": (PAPER_B, ("elastic", "fractional"), {}, F_SWEEP, A_PAPER_B,
                 {"friction_stress_max": 1.92e4, "friction_strain_half": 4.0e-3}),
    "fractional": (PAPER_B, ("elastic", "friction"), {}, F_SWEEP, A_PAPER_B,
                   {"fractional_coefficient": 6.0e5, "fractional_order": 0.20}),
    # a fixture of 0.5 kg: 5 % of |K| at 100 Hz
    "inertia": (PAPER_B, BRANCHES, {"inertia": {"mass": 0.5}}, F_SWEEP, A_PAPER_B, {"mass": 0.5}),
    "viscous": (PAPER_B, BRANCHES, {"viscous": {"viscosity": 1000.0}}, F_SWEEP, A_PAPER_B,
                {"viscosity": 1000.0}),
    # strain stiffening shows at large strain: a sweep up to 2 mm (ε̂ ≈ 0.066)
    "strain_stiffening": (PAPER_B, BRANCHES, {"strain_stiffening": {"stiffening": 10.0}}, F_SWEEP,
                          tuple(np.geomspace(0.05e-3, 2e-3, 5)), {"stiffening": 10.0}),
    "rate_amplitude_coupling": (PAPER_B, BRANCHES, {"rate_amplitude_coupling": {"rate_exponent": 0.05}},
                                F_SWEEP, A_PAPER_B, {"rate_exponent": 0.05}),
    # the strain varies as 1/r² in torsion: a thick-walled Table 1 bushing (b = 16 mm) across
    # its Fletcher–Gent knee; after the refit the single-strain model misses by about 1 %
    "nonuniform_strain": (TABLE_1.replace(outer_radius=0.016), BRANCHES, {"nonuniform_strain": {}}, np.linspace(10, 100, 30),
                          A_TABLE_1, {}),
    # standing waves need high frequency: a 10 Hz – 1 kHz sweep
    "wave_effects": (PAPER_B, BRANCHES, {"wave_effects": {"density": 1150.0}}, np.geomspace(10, 1000, 30),
                     A_PAPER_B, {"density": 1150.0}),
}


@functools.cache
def hidden_case(effect_id: str, seed: int = 7):
    design, baseline, effects, freqs, amps, truth = HIDDEN[effect_id]
    data = synthetic_stiffness(design.replace(effects=effects), freqs, amps, noise=NOISE, seed=seed)
    return diagnose(design, data, baseline=baseline), truth


def test_every_effect_of_the_library_has_a_hidden_case():
    assert set(HIDDEN) == set(EFFECTS)


@pytest.mark.parametrize("effect_id", list(HIDDEN))
def test_a_hidden_effect_is_named_and_the_gap_falls_to_the_noise(effect_id):
    result, truth = hidden_case(effect_id)
    assert result.added == [effect_id]
    assert not result.unexplained
    step = result.steps[0]
    assert step.bic_drop > 10
    assert step.gap_after < step.gap_before
    assert result.baseline.gap > 1.1 * result.final.gap  # the effect was visible …
    assert result.final.gap < 1.1 * NOISE_GAP  # … and is gone
    for name, value in truth.items():  # its parameters are those hidden, within their errors
        assert step.parameters[name] == pytest.approx(value, rel=0.15), name
        error = step.standard_errors[name]
        assert 0 < error < abs(step.parameters[name]), name
        assert abs(step.parameters[name] - value) < 5 * error + 1e-9 * abs(value), (name, step.parameters[name], error)
    assert result.noise_gap == pytest.approx(NOISE_GAP, rel=0.15)


def test_friction_is_named_for_a_baseline_without_it_the_teaching_case():
    result, _ = hidden_case("friction")
    report = result.report()
    assert report["baseline"] == ["elastic", "fractional"]
    assert report["added"] == ["friction"]
    assert report["steps"][0]["title"] == "Amplitude dependence (Fletcher–Gent effect)"
    # without friction the model cannot soften with amplitude: too soft at small amplitudes,
    # too stiff at large ones, at every frequency
    where = report["steps"][0]["where"]
    assert "too soft" in where and "too stiff" in where and "at every frequency" in where
    assert report["gap_baseline"] > 10 * report["gap_final"]


def test_nothing_is_added_to_data_the_model_explains():
    for design, amps in ((PAPER_B, A_PAPER_B), (TABLE_1, A_TABLE_1)):
        data = synthetic_stiffness(design, F_SWEEP, amps, noise=NOISE, seed=11)
        result = diagnose(design, data, held_out=False)
        assert result.added == []
        assert not result.unexplained
        assert result.final is result.baseline
        assert result.where_remaining == "no misfit above the noise."
        assert result.final.gap < 1.1 * NOISE_GAP


@pytest.mark.parametrize("effects", [
    {"inertia": {"mass": 0.5}, "rate_amplitude_coupling": {"rate_exponent": 0.05}},
    {"viscous": {"viscosity": 1000.0}, "strain_stiffening": {"stiffening": 10.0}},
])
def test_two_hidden_effects_are_both_found(effects):
    amps = np.geomspace(0.05e-3, 2e-3, 5) if "strain_stiffening" in effects else A_PAPER_B
    data = synthetic_stiffness(PAPER_B.replace(effects=effects), F_SWEEP, amps, noise=NOISE, seed=5)
    result = diagnose(PAPER_B, data, held_out=False)
    assert sorted(result.added) == sorted(effects)
    assert not result.unexplained
    assert result.final.gap < 1.1 * NOISE_GAP
    final = result.final.design.effect_parameters
    for eid, params in effects.items():
        for name, value in params.items():
            assert final[eid][name] == pytest.approx(value, rel=0.2)


def _outside(kind: str) -> MeasuredStiffness:
    """Paper B data with an effect the library does not have."""
    data = synthetic_stiffness(PAPER_B, F_SWEEP, A_PAPER_B, noise=NOISE, seed=7)
    f = data.frequency_hz
    if kind == "relaxation":  # a Maxwell element relaxing at 30 Hz: a loss peak, a stiffness step
        wt = 1j * f / 30.0
        k = data.stiffness + shape_factor(PAPER_B.geometry, "axial") * 0.3e6 * wt / (1 + wt)
    else:  # a resonance of the test rig at 130 Hz, 3 % strong
        k = data.stiffness * (1 + 0.03 / (1 - (f / 130) ** 2 + 0.1j * f / 130))
    return MeasuredStiffness(f, data.amplitude, k)


@pytest.mark.parametrize("kind", ["relaxation", "rig resonance"])
def test_an_effect_outside_the_library_is_unexplained_not_misnamed(kind):
    result = diagnose(PAPER_B, _outside(kind), held_out=False)
    assert result.added == []
    assert result.unexplained
    assert result.final.gap > 1.15 * NOISE_GAP
    assert result.where_remaining != "no misfit above the noise."
    assert "model too" in result.where_remaining
    assert "unexplained" in summary(result)


def test_the_held_out_gap_shows_the_extended_model_predicts():
    result, _ = hidden_case("inertia")
    held = result.held_out
    assert held["folds"] == len(A_PAPER_B)
    assert held["gap_final"] < 1.2 * NOISE_GAP  # amplitudes never fitted are predicted to the noise
    assert held["gap_baseline"] > 1.5 * held["gap_final"]


def test_the_report_and_predictions_follow_formats_md():
    result, _ = hidden_case("viscous")
    report = json.loads(json.dumps(result.report(), allow_nan=False))
    for key in ("baseline", "added", "steps", "gap_baseline", "gap_final", "unexplained"):
        assert key in report
    step = report["steps"][0]
    for key in ("effect", "title", "where", "evidence", "parameters", "standard_errors", "gap_before", "gap_after"):
        assert key in step
    assert set(step["standard_errors"]) == set(step["parameters"])
    assert step["evidence"]["bic_drop"] > 10
    # the same misfit reached along two paths (the step's fit and the report's): summation order
    # differs between machines, so they agree to round-off (n·ε ≈ 1e-13), not bit for bit
    assert step["gap_before"] == pytest.approx(report["gap_baseline"], rel=1e-10)
    assert step["gap_after"] == pytest.approx(report["gap_final"], rel=1e-10)
    # the final design is a design file whose stiffness is the predictions' final columns,
    # and whose gap is the reported gap
    final = design_from_dict(report["design"])
    data = result.data
    k = stiffness_points(final, data.frequency_hz, data.amplitude)
    pred = result.predictions()
    np.testing.assert_allclose(pred["final_magnitude"], np.abs(k), rtol=1e-12)
    np.testing.assert_allclose(pred["final_loss_factor"], k.imag / k.real, rtol=1e-10)
    gap = np.sqrt(np.mean(np.abs(k - data.stiffness) ** 2 / np.abs(data.stiffness) ** 2))
    assert report["gap_final"] == pytest.approx(gap, rel=1e-12)


def test_a_missing_branch_has_no_effect_at_all():
    off = PAPER_B.replace(**OFF)
    k = stiffness_points(off, F_SWEEP, 1e-4)
    assert np.all(np.abs(k) < 1e-20)


def test_the_noise_estimate_ignores_a_smooth_misfit():
    rng = np.random.default_rng(0)
    ff, aa = (m.ravel() for m in np.meshgrid(F_SWEEP, A_PAPER_B))
    data = MeasuredStiffness(ff, aa, np.full(ff.size, 1e6 + 0j))
    noise = 0.01 * (rng.standard_normal(ff.size) + 1j * rng.standard_normal(ff.size))
    trend = 0.05 * (ff / 100) ** 2 + 0.02j * np.log(aa / aa.min())
    s2 = 2 * 0.01**2
    assert noise_variance(noise, data) == pytest.approx(s2, rel=0.15)
    assert noise_variance(noise + trend, data) == pytest.approx(noise_variance(noise, data), rel=0.05)
    assert noise_variance(noise, data.select(ff == ff[0])) is not None
    assert noise_variance(noise[:2], data.select(np.arange(ff.size) < 2)) is None


def test_describe_says_where_and_which_way():
    ff, aa = (m.ravel() for m in np.meshgrid(F_SWEEP, A_PAPER_B))
    k_data = np.full(ff.size, 4e6 * (1 + 0.1j))
    data = MeasuredStiffness(ff, aa, k_data)
    # model too stiff at high frequency, as f², the same at every amplitude
    text = describe(data, k_data * (1 + 0.08 * (ff / 100) ** 2), "axial", 0.001)
    assert text.startswith("|K|: model too stiff from ")
    assert "at every amplitude" in text and "frequency squared" in text
    # loss factor too low at large amplitudes only, at every frequency
    k = k_data.real * (1 + 1j * (0.1 - 0.03 * (aa >= 0.17e-3)))
    text = describe(data, k, "axial", 0.001)
    assert text.startswith("loss factor: model too low at every frequency, from 0.17 mm up")
    assert describe(data, k_data, "axial", 0.001) == "no misfit above the noise."
    # both: a sentence each, the second capitalised after its full stop ("… %). loss factor:" read as one)
    both = describe(data, k * (1 + 0.08 * (ff / 100) ** 2), "axial", 0.001)
    assert both.startswith("|K|: model too stiff from ") and ". Loss factor: model too low" in both


def test_diagnose_refuses_a_bad_baseline():
    data = synthetic_stiffness(PAPER_B, F_SWEEP, A_PAPER_B)
    with pytest.raises(ValueError, match="baseline"):
        diagnose(PAPER_B, data, baseline=("elastic", "plastic"))
    with pytest.raises(ValueError, match="baseline"):
        diagnose(PAPER_B, data, baseline=())


# --------------------------------------------------------------------------------------------
# The command line
# --------------------------------------------------------------------------------------------


@pytest.fixture
def files(tmp_path):
    data = synthetic_stiffness(PAPER_B, F_SWEEP, A_PAPER_B, noise=NOISE, seed=7)
    measured = tmp_path / "measured.csv"
    data.to_csv(measured)
    design = tmp_path / "design.json"
    write_design(PAPER_B, design)
    return tmp_path, measured, design


def test_cli_diagnose_writes_report_and_predictions(files, capsys):
    tmp, measured, design = files
    assert main(["diagnose", str(measured), "--design", str(design), "--baseline", "elastic,fractional",
                 "--json", str(tmp / "r.json"), "--predictions", str(tmp / "p.csv")]) == 0
    report = json.loads((tmp / "r.json").read_text())
    assert report["baseline"] == ["elastic", "fractional"]
    assert report["added"] == ["friction"]
    out = capsys.readouterr().out
    assert "step 1: add friction" in out
    lines = (tmp / "p.csv").read_text().splitlines()
    assert lines[0] == ("frequency_hz,amplitude,baseline_magnitude,baseline_loss_factor,"
                        "final_magnitude,final_loss_factor")
    data = read_stiffness(measured)
    assert len(lines) == 1 + len(data)
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    np.testing.assert_allclose(rows[:, 0], data.frequency_hz, rtol=1e-11)
    np.testing.assert_allclose(rows[:, 1], data.amplitude, rtol=1e-11)


def test_cli_diagnose_prints_the_json_report_without_json(files, capsys):
    _, measured, design = files
    assert main(["diagnose", str(measured), "--design", str(design)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["added"] == [] and report["unexplained"] is False


@pytest.mark.parametrize("args, message", [
    (["--baseline", "elastic,plastic"], "--baseline"),
    (["--baseline", ""], "--baseline"),
])
def test_cli_diagnose_bad_input_is_one_line(files, capsys, args, message):
    _, measured, design = files
    with pytest.raises(SystemExit) as exc:
        main(["diagnose", str(measured), "--design", str(design), *args])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_cli_diagnose_bad_file_is_one_line(files, capsys):
    tmp, _, design = files
    bad = tmp / "bad.csv"
    bad.write_text("frequency_hz,amplitude,magnitude,loss_factor\n10,1e-4,nan,0.1\n")
    with pytest.raises(SystemExit) as exc:
        main(["diagnose", str(bad), "--design", str(design)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "line 2" in err and err.count("\n") == 1


def test_noise_free_data_add_exactly_what_is_missing():
    """With no noise the misfit of the right model is numerical (~1e-16): nothing spurious is
    added on top, and nothing is called unexplained."""
    for effects in ({}, {"inertia": {"mass": 0.5}}):
        data = synthetic_stiffness(PAPER_B.replace(effects=effects), F_SWEEP, A_PAPER_B, noise=0.0)
        result = diagnose(PAPER_B, data, held_out=False)
        assert result.added == list(effects)
        assert not result.unexplained
        assert result.final.gap < 1e-6


def test_scattered_points_off_any_grid():
    """Points at random frequencies and amplitudes: the noise is judged from nearest
    neighbours, the held-out check leaves out amplitude bands."""
    rng = np.random.default_rng(4)
    f = rng.uniform(1, 100, 150)
    x = np.exp(rng.uniform(math.log(1e-5), math.log(4e-4), 150))
    k = stiffness_points(PAPER_B.replace(effects={"inertia": {"mass": 0.5}}), f, x)
    k = k * (1 + NOISE * (rng.standard_normal(150) + 1j * rng.standard_normal(150)))
    result = diagnose(PAPER_B, MeasuredStiffness(f, x, k))
    assert result.added == ["inertia"]
    assert result.noise_gap == pytest.approx(NOISE_GAP, rel=0.2)
    assert result.held_out["folds"] == 5 and result.held_out["gap_final"] < 1.2 * NOISE_GAP
