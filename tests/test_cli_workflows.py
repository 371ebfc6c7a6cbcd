"""The workflows users run with the installed `bushing` script (docs/files.md): a fit with a
measured loop, a fit on some amplitudes that predicts the others, and designs from targets,
feasible or not. Each is checked against the truth the example data were made from
(examples/README.md) or against another command (`bushing stiffness`, `bushing loop`)."""

import csv
import io
import json
import math
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from tests.test_cli import installed_script

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "examples"
TRUE = json.loads((EX / "paper_b_true.json").read_text(encoding="utf-8"))["material"]
PARAMETERS = ("shear_modulus", "fractional_coefficient", "fractional_order", "friction_stress_max",
              "friction_strain_half")
NOISE = 0.005  # examples/README.md: 0.5 % in each part of K, 0.5 % of the loop's peak force


def bushing(*args, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([*installed_script(), *map(str, args)], capture_output=True, text=True,
                          check=False, cwd=cwd)


def table(text: str) -> dict[str, np.ndarray]:
    """A CSV of the command line or of examples/ as named columns (numbers where they are)."""
    rows = list(csv.reader(io.StringIO(text)))
    cols = {}
    for j, name in enumerate(rows[0]):
        values = [r[j] for r in rows[1:]]
        try:
            cols[name] = np.array(values, dtype=float)
        except ValueError:
            cols[name] = values
    return cols


def complex_stiffness(cols) -> np.ndarray:
    """K from a stiffness table, polar (|K|, η: K' = |K|/√(1+η²), K'' = η K') or rectangular."""
    if "stiffness_real" in cols:
        return cols["stiffness_real"] + 1j * cols["stiffness_imag"]
    real = cols["magnitude"] / np.sqrt(1 + cols["loss_factor"] ** 2)
    return real * (1 + 1j * cols["loss_factor"])


def gap(model, measured) -> float:
    """docs/files.md: √(mean(|K_model − K_data|² / |K_data|²))."""
    return float(np.sqrt(np.mean(np.abs(model - measured) ** 2 / np.abs(measured) ** 2)))


def stiffness_of(design_path, freqs, amplitude, cwd) -> np.ndarray:
    """`bushing stiffness` at one amplitude on the data's (evenly spaced) frequencies."""
    done = bushing("stiffness", design_path, "--freq", freqs[0], freqs[-1], len(freqs),
                   "--amp", amplitude, cwd=cwd)
    assert done.returncode == 0, done.stderr
    cols = table(done.stdout)
    np.testing.assert_allclose(cols["frequency_hz"], freqs, rtol=1e-9)  # the data's frequencies
    return complex_stiffness(cols)


# ---- bushing fit --loop -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def fits(tmp_path_factory):
    """The README's fit of the Paper B example, with and without the measured loop."""
    out = tmp_path_factory.mktemp("fits")
    reports = {}
    for key, extra in (("loop", ["--loop", EX / "paper_b_loop.csv"]), ("no loop", [])):
        done = bushing("fit", EX / "paper_b_stiffness.csv", "--design", EX / "paper_b_guess.json",
                       *extra, "-o", out / f"{key}.json", cwd=out)
        assert done.returncode == 0 and done.stdout == "", done.stderr
        reports[key] = json.loads((out / f"{key}.json").read_text(encoding="utf-8"))
        reports[key]["stderr"] = done.stderr
    reports["dir"] = out
    return reports


def test_fit_with_a_loop_recovers_the_truth_within_two_standard_errors(fits):
    fitted = fits["loop"]
    assert fitted["stderr"] == ""  # every parameter determined: no warning
    report = fitted["fit"]
    assert report["undetermined"] == [] and report["points"] == 150
    for name in PARAMETERS:
        error, se = fitted["material"][name] - TRUE[name], report["standard_errors"][name]
        # 2 SE: the seeded data put each estimate 1.1-1.5 SE from the truth
        assert abs(error) <= 2 * se, f"{name}: {error / se:+.2f} SE off the truth"
        low, high = report["intervals"][name]
        assert low <= TRUE[name] <= high, name  # the 95 % profile interval holds the truth
    # the gap of 150 points with complex noise of 0.5 % per part: √2 · 0.005 = 0.00707, known
    # to ±1/√300 ≈ 6 % (300 real residuals) less the 5 parameters' share
    assert report["gap"] == pytest.approx(math.sqrt(2) * NOISE, rel=0.12)


def test_loop_rms_is_the_loops_misfit_relative_to_its_peak(fits):
    """docs/files.md: `loop_rms`, the RMS misfit of the loop's force relative to its peak, here
    from `bushing loop` of the fitted design at the measured drive (two periods of 200 samples
    from phase 0, examples/README.md)."""
    out = fits["dir"]
    done = bushing("loop", out / "loop.json", "--freq", 0.1, "--amp", 1e-3, "--points", 200,
                   cwd=out)
    assert done.returncode == 0, done.stderr
    model = table(done.stdout)
    measured = table((EX / "paper_b_loop.csv").read_text(encoding="utf-8"))
    np.testing.assert_allclose(np.tile(model["displacement"], 2), measured["displacement"],
                               atol=1e-9 * 1e-3)  # the same drive, sample for sample
    misfit = np.sqrt(np.mean((np.tile(model["force"], 2) - measured["force"]) ** 2))
    peak = np.max(np.abs(measured["force"]))
    # the peak of the noisy data or of the model, the measured mean removed or not: within 3 %
    assert fits["loop"]["fit"]["loop_rms"] == pytest.approx(misfit / peak, rel=0.03)
    # and it is the stated noise, 0.5 % of the peak (400 samples: ±1/√800 ≈ 3.5 %)
    assert fits["loop"]["fit"]["loop_rms"] == pytest.approx(NOISE, rel=0.12)


def test_the_loop_changes_the_fit(fits):
    """The loop at 1 mm (beyond the sweeps' 0.35 mm: the friction saturated) and 0.1 Hz (the
    fractional branch small) measures µ almost alone: every standard error shrinks, µ's most."""
    se_loop = fits["loop"]["fit"]["standard_errors"]
    se_none = fits["no loop"]["fit"]["standard_errors"]
    assert "loop_rms" not in fits["no loop"]["fit"]
    for name in PARAMETERS:
        assert se_loop[name] < se_none[name], name
    assert se_loop["shear_modulus"] < 0.5 * se_none["shear_modulus"]
    mu = fits["loop"]["material"]["shear_modulus"], fits["no loop"]["material"]["shear_modulus"]
    moved = mu[0] / mu[1] - 1
    assert abs(moved) > 1e-3  # a different fit, not the same one reported twice


# ---- bushing fit --fit-on amplitude=… ---------------------------------------------------------

FIT_ON = (1.3e-5, 1e-4, 3.5e-4)  # of the example's 0.013, 0.04, 0.1, 0.17, 0.35 mm
HELD_OUT = (4e-5, 1.7e-4)


@pytest.fixture(scope="module")
def fit_on(tmp_path_factory):
    out = tmp_path_factory.mktemp("fit_on")
    selection = "amplitude=" + "+".join(f"{a:g}" for a in FIT_ON)
    done = bushing("fit", EX / "paper_b_stiffness.csv", "--design", EX / "paper_b_guess.json",
                   "--fit-on", selection, "-o", out / "fitted.json", cwd=out)
    assert done.returncode == 0, done.stderr
    return out, selection, json.loads((out / "fitted.json").read_text(encoding="utf-8"))


def measured_group(amplitude):
    cols = table((EX / "paper_b_stiffness.csv").read_text(encoding="utf-8"))
    rows = np.isclose(cols["amplitude"], amplitude, rtol=1e-6)
    assert rows.sum() == 30
    return cols["frequency_hz"][rows], complex_stiffness(cols)[rows]


def test_fit_on_some_amplitudes_reports_every_group(fit_on):
    out, selection, fitted = fit_on
    prediction = fitted["fit"]["prediction"]
    assert prediction["fit_on"] == selection and prediction["points_fitted"] == 90
    groups = {round(g["amplitude"] * 1e6): g for g in prediction["groups"]}  # in µm
    assert sorted(groups) == [13, 40, 100, 170, 350]
    for a in FIT_ON + HELD_OUT:
        g = groups[round(a * 1e6)]
        assert g["mode"] == "axial" and g["points"] == 30 and g["fitted"] == (a in FIT_ON)
        # the group's gap is the fitted design's, as `bushing stiffness` computes it, against
        # those rows of the file (12 and 10 printed digits: far below 1e-6)
        freqs, measured = measured_group(a)
        predicted = stiffness_of(out / "fitted.json", freqs, a, out)
        assert g["gap"] == pytest.approx(gap(predicted, measured), rel=1e-6), a
    assert fitted["fit"]["points"] == 90


def test_fit_on_fits_the_chosen_rows_only(fit_on, fits):
    """Fewer rows, less information: every standard error of the fit on 90 rows exceeds the one of
    the fit on all 150 (about √(150/90) ≈ 1.3 times)."""
    part, whole = fit_on[2]["fit"]["standard_errors"], fits["no loop"]["fit"]["standard_errors"]
    for name in PARAMETERS:
        assert 1.1 * whole[name] < part[name] < 2 * whole[name], name


def test_fit_on_pools_the_held_out_groups(fit_on):
    prediction = fit_on[2]["fit"]["prediction"]
    groups = {round(g["amplitude"] * 1e6): g for g in prediction["groups"]}
    held = [groups[round(a * 1e6)] for a in HELD_OUT]
    points = sum(g["points"] for g in held)
    pooled = math.sqrt(sum(g["points"] * g["gap"] ** 2 for g in held) / points)
    assert prediction["gap_held_out"] == pytest.approx(pooled, rel=1e-9)


def test_fit_on_predicts_the_held_out_amplitudes_as_the_truth_does(fit_on):
    """The held-out amplitudes, predicted from the other three, against the noise-free truth
    (examples/paper_b_true.json) and against the data made from it."""
    out, _, fitted = fit_on
    groups = {round(g["amplitude"] * 1e6): g for g in fitted["fit"]["prediction"]["groups"]}
    for a in HELD_OUT:
        freqs, measured = measured_group(a)
        truth = stiffness_of(EX / "paper_b_true.json", freqs, a, out)
        predicted = stiffness_of(out / "fitted.json", freqs, a, out)
        # 90 points of 0.5 % noise pin five parameters to a few 0.1 %; interpolated in amplitude
        assert np.max(np.abs(predicted / truth - 1)) < 0.01, a
        # the prediction misses the data by the noise, as the truth itself does
        assert groups[round(a * 1e6)]["gap"] < 1.15 * gap(truth, measured), a


# ---- bushing design ---------------------------------------------------------------------------

START = {"mode": "axial", "geometry": {"inner_radius": 0.02, "outer_radius": 0.035, "length": 0.09},
         "material": TRUE}
AT = {"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4}
NUMBER = r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?"


def design_run(tmp_path, problem, output=True):
    path = tmp_path / "targets.json"
    path.write_text(json.dumps(problem), encoding="utf-8")
    args = ["design", path] + (["-o", tmp_path / "designs.json"] if output else [])
    done = bushing(*args, cwd=tmp_path)
    text = (tmp_path / "designs.json").read_text(encoding="utf-8") if output else done.stdout
    report = json.loads(text)
    return done, report


def magnitude_at(tmp_path, design: dict) -> float:
    """|K| of a design at the targets' operating point, from `bushing stiffness`."""
    path = tmp_path / "candidate.json"
    path.write_text(json.dumps(design), encoding="utf-8")
    return float(np.abs(stiffness_of(path, [10.0], 1e-4, tmp_path)[0]))


def test_design_meets_the_example_targets_and_says_how(tmp_path):
    """The README's example: one line on standard output, the design in the file."""
    problem = json.loads((EX / "paper_b_targets.json").read_text(encoding="utf-8"))
    done, report = design_run(tmp_path, problem)
    assert done.returncode == 0 and done.stderr == ""
    (line,) = done.stdout.splitlines()
    assert done.stdout == line + "\n" and line == report["statement"]
    words = re.fullmatch(rf"1 design meets every target\. The nearest to the start changes "
                         rf"thickness ({NUMBER}) %, length ({NUMBER}) %\.", line)
    assert words, line
    assert report["feasible"] and len(report["solutions"]) == 1
    geometry = report["solutions"][0]["design"]["geometry"]
    assert geometry["inner_radius"] == pytest.approx(0.02, rel=1e-12)  # the shaft kept
    thickness = geometry["outer_radius"] - geometry["inner_radius"]
    # the stated changes are the file's design's, to the 3 digits printed
    assert float(words.group(1)) == pytest.approx(100 * (thickness / 0.015 - 1), abs=0.006)
    assert float(words.group(2)) == pytest.approx(100 * (geometry["length"] / 0.09 - 1), abs=0.006)
    assert geometry["outer_radius"] <= 0.040 and geometry["length"] <= 0.100 and thickness >= 0.002
    # the targets, checked by `bushing stiffness`: |K| = 4 kN/mm within the default 1 %
    assert magnitude_at(tmp_path, report["solutions"][0]["design"]) == pytest.approx(4e6, rel=0.01)


def test_contradicting_targets_are_said_to_contradict_each_other(tmp_path):
    problem = {"design": START,
               "targets": [{**AT, "magnitude": {"min": 5e6}}, {**AT, "magnitude": {"max": 4e6}}]}
    done, report = design_run(tmp_path, problem)
    assert done.returncode == 0 and done.stderr == ""  # an answer, not an error (docs/files.md)
    (line,) = done.stdout.splitlines()
    assert line == report["statement"]
    assert line.startswith("The targets cannot be met. At the closest design, ")
    assert line.endswith("; no limit binds there: the targets contradict each other.")
    assert not report["feasible"] and report["solutions"] == []
    closest = report["closest"]
    assert closest["binding_limits"] == []
    reached = magnitude_at(tmp_path, closest["design"])
    # the least miss of |K| ≥ 5 and ≤ 4 kN/mm lies between them, near the middle: 4.39 MN/m for
    # the least squared relative misses, 4.47 for the least squared log ones (not the start's 4.06)
    assert 4.3e6 < reached < 4.6e6
    low, high = closest["targets"]
    assert low["value"] == pytest.approx(reached, rel=1e-9)
    assert high["value"] == pytest.approx(reached, rel=1e-9)
    assert low["miss"] == pytest.approx(reached / 5e6 - 1, rel=1e-9)
    assert high["miss"] == pytest.approx(reached / 4e6 - 1, rel=1e-9)
    assert f"missed by {100 * low['miss']:+.3g} % (it reaches {reached:.4g} N/m)" in line
    # without -o the report itself goes to standard output, and nothing else
    plain, again = design_run(tmp_path, problem, output=False)
    assert plain.returncode == 0 and again["statement"] == line


def test_targets_beyond_the_limits_name_the_limits_that_bind(tmp_path):
    """|K| = 40 kN/mm cannot be reached with the shaft kept, t ≥ 2 mm and L ≤ 100 mm: the
    stiffest bushing allowed is the thinnest and longest (K grows with L and falls with b/a,
    eq 18), so the closest design sits on those two limits and reaches that bushing's |K|."""
    problem = {"design": START, "targets": [{**AT, "magnitude": 4e7}], "fixed": ["inner_radius"],
               "limits": {"outer_radius": {"max": 0.040}, "length": {"max": 0.100},
                          "thickness": {"min": 0.002}}}
    done, report = design_run(tmp_path, problem)
    assert done.returncode == 0 and done.stderr == ""
    (line,) = done.stdout.splitlines()
    assert line.startswith("The targets cannot be met.") and line.endswith(
        "; the limits that bind there: thickness ≥ 0.002, length ≤ 0.1.")
    closest = report["closest"]
    assert sorted(closest["binding_limits"]) == ["length ≤ 0.1", "thickness ≥ 0.002"]
    stiffest = {**START, "geometry": {"inner_radius": 0.02, "outer_radius": 0.022, "length": 0.1}}
    limit = magnitude_at(tmp_path, stiffest)
    assert closest["targets"][0]["value"] == pytest.approx(limit, rel=1e-6)
    assert f"(it reaches {limit:.4g} N/m)" in line
