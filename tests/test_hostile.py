"""Hostile input to the command line, through the installed entry point in a subprocess: bad
input ends with exit status 2 and one line on standard error naming what is wrong; valid input,
however odd, gives a clean result; never a traceback, a warning or a NaN in an output.

HANG_GUARD_S only stops a run that hangs: it is no speed check (a slow machine passes)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from core import PAPER_B, write_design
from core.data import MeasuredStiffness

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
DESIGN = json.loads((EXAMPLES / "paper_b_true.json").read_text())


HANG_GUARD_S = 900  # each run takes seconds; only a hang takes a quarter of an hour


def bushing(*argv, stdout=subprocess.PIPE):
    return subprocess.run([sys.executable, "-m", "cli.main", *map(str, argv)], stdout=stdout,
                          stderr=subprocess.PIPE, text=True, timeout=HANG_GUARD_S, check=False)


def design_file(tmp_path, text, name="d.json"):
    path = tmp_path / name
    path.write_text(text)
    return path


def edited(change) -> str:
    text = json.dumps(DESIGN)
    for old, new in change:
        assert old in text, old
        text = text.replace(old, new)
    return text


HUGE = "1" + "0" * 400
DESIGNS = {
    "an integer too large for a float": (edited([('"shear_modulus": 2420000.0', f'"shear_modulus": {HUGE}')]),
                                         "material.shear_modulus"),
    "an effect's integer too large": (edited([('"material": {', f'"effects": {{"inertia": {{"mass": {HUGE}}}}}, "material": {{')]),
                                      "inertia"),
    "nested thousands deep": ("[" * 20000 + "]" * 20000, "nested too deeply"),
    "a key given twice": (edited([('"mode": "axial"', '"mode": "axial", "mode": "torsion"')]), "given twice"),
    "NaN": (edited([('"shear_modulus": 2420000.0', '"shear_modulus": NaN')]), "material.shear_modulus"),
    "radii of 1e-300 m": (edited([('"inner_radius": 0.02', '"inner_radius": 1e-300')]), "geometry.inner_radius"),
    "an outer radius of 1e300 m": (edited([('"outer_radius": 0.035', '"outer_radius": 1e300')]), "geometry.outer_radius"),
    "50 MB": ('{"name": "' + "x" * 50_000_000 + '"}', "too large"),
}


@pytest.mark.parametrize("case", list(DESIGNS))
def test_hostile_design_files(case, tmp_path):
    text, needle = DESIGNS[case]
    path = design_file(tmp_path, text)
    for argv in (("loop", path, "--freq", 1, "--amp", 1e-3), ("stiffness", path, "--freq", 1, 10, 2, "--amp", 1e-4)):
        r = bushing(*argv)
        assert r.returncode == 2 and r.stdout == "", (case, r.stderr)
        assert r.stderr.count("\n") == 1 and needle in r.stderr, (case, r.stderr)


OPTIONS = {
    "a loop of 1e14 points": (("loop", "{d}", "--freq", 1, "--amp", 1e-3, "--points", 99999999999999), "at most"),
    "ten million frequencies": (("stiffness", "{d}", "--freq", 1, 100, 10000000, "--amp", 1e-3), "at most"),
    "a grid over a million points": (("stiffness", "{d}", "--freq", 1, 100, 100000, "--amp", *([1e-4] * 20)), "points"),
    "a negative amplitude": (("stiffness", "{d}", "--freq", 1, 100, 3, "--amp", -1e-3), "--amp"),
    "an amplitude of 1e300, continuum": (("stiffness", "{d}", "--freq", 1, 100, 3, "--amp", 1e300, "--continuum"),
                                         "amplitude"),
    "an amplitude of 1e300, loop": (("loop", "{d}", "--freq", 1, "--amp", 1e300), "amplitude"),
    "underscores in a number": (("stiffness", "{d}", "--freq", 1, 100, 3, "--amp", "4_858_578"), "--amp"),
    "inf": (("loop", "{d}", "--freq", "inf", "--amp", 1e-3), "--freq"),
}


@pytest.mark.parametrize("case", list(OPTIONS))
def test_hostile_options(case):
    argv, needle = OPTIONS[case]
    r = bushing(*(str(a).format(d=EXAMPLES / "paper_b_true.json") for a in argv))
    assert r.returncode == 2 and r.stdout == "", (case, r.stderr)
    assert r.stderr.count("\n") == 1 and needle in r.stderr and "Traceback" not in r.stderr, (case, r.stderr)


def stiffness_csv(path, rows):
    path.write_text("frequency_hz,amplitude,magnitude,loss_factor\n" + "".join(",".join(map(str, r)) + "\n" for r in rows))
    return path


def test_hostile_measured_files(tmp_path):
    design = EXAMPLES / "paper_b_true.json"
    good = [(f, a, 4.2e6, 0.14) for f in (1, 10, 100) for a in (1e-5, 1e-4, 1e-3)]
    cases = {
        "an amplitude of 1e300": ([*good, (10, 1e300, 4e6, 0.1)], "amplitude"),
        "a frequency of 1e300 Hz": ([*good, (1e300, 1e-4, 4e6, 0.1)], "frequency_hz must be within"),
        "an amplitude of 1e-20 m": ([*good, (10, 1e-20, 4e6, 0.1)], "at least"),
    }
    for case, (rows, needle) in cases.items():
        path = stiffness_csv(tmp_path / "m.csv", rows)
        for command in ("fit", "diagnose"):
            r = bushing(command, path, "--design", design)
            assert r.returncode == 2 and r.stdout == "", (case, command, r.stderr)
            assert r.stderr.count("\n") == 1 and needle in r.stderr, (case, command, r.stderr)


def test_a_stiffness_of_any_sign_is_fitted_and_diagnosed(tmp_path):
    """A negative loss factor (a blocked transfer stiffness above a wave resonance) and Re K < 0
    (a mass-dominated one) are measurements, not errors: fit and diagnose read them and finish."""
    measured = (EXAMPLES / "paper_b_stiffness.csv").read_text()
    rows = measured.count("\n")  # the header and the file's rows, one of them added below
    files = {"a negative loss factor": measured + "800,0.008,7950.23,-0.0075\n"}
    header, _, body = measured.partition("\n")
    assert header == "frequency_hz,amplitude,magnitude,loss_factor", header
    polar = [[float(c) for c in line.split(",")] for line in body.splitlines()]
    files["Re K < 0"] = "frequency_hz,amplitude,stiffness_real,stiffness_imag\n" + "".join(
        f"{f!r},{a!r},{m / np.hypot(1, eta):.17g},{m * eta / np.hypot(1, eta):.17g}\n" for f, a, m, eta in polar
    ) + "1000,1e-4,-2500000,300000\n"
    for case, text in files.items():
        path = tmp_path / "m.csv"
        path.write_text(text)
        for command in ("fit", "diagnose"):
            r = bushing(command, path, "--design", EXAMPLES / "paper_b_true.json")
            assert r.returncode == 0, (case, command, r.stderr)
            assert all(line.startswith("bushing fit: warning: ") for line in r.stderr.splitlines()), r.stderr
            report = json.loads(r.stdout, parse_constant=lambda c: pytest.fail(f"{c} in a report"))
            points = report["fit"]["points"] if command == "fit" else report["points"]
            assert points == rows, (case, command, points)


def _loop_rows(change):
    t = np.arange(400) / 2000.0  # 2 periods at 10 Hz
    x = 1e-4 * np.sin(2 * np.pi * 10 * t)
    f = 400.0 * np.sin(2 * np.pi * 10 * t + 0.2)
    return change(t, x, f)


LOOPS = {
    "a time step of 1e-300 s": (lambda t, x, f: (t * 1e-300, x, f), "frequency"),
    "displacements times 1e300": (lambda t, x, f: (t, x * 1e300, f), "at most"),
    "displacements of 1e-16 m": (lambda t, x, f: (t, x * 1e-12, f), "at least"),
    "a third of a period": (lambda t, x, f: (t[:67], x[:67], f[:67]), "period"),
    "a drive that is no sine": (lambda t, x, f: (t, np.sign(np.sin(37 * t)) * np.abs(x) ** 0.5 * 1e-2, f),
                                "not a steady sine"),
    # 1e302 N at 0.1 mm: no bushing; the message names the force (a fit would only fail)
    "a force of 1e300 N": (lambda t, x, f: (t, x, f * 1e300), "force"),
}


@pytest.mark.parametrize("case", list(LOOPS))
def test_hostile_loop_files(case, tmp_path):
    change, needle = LOOPS[case]
    t, x, f = _loop_rows(change)
    path = tmp_path / "loop.csv"
    path.write_text("time_s,displacement,force\n" + "".join(f"{a:.17g},{b:.17g},{c:.17g}\n" for a, b, c in zip(t, x, f)))
    r = bushing("fit", EXAMPLES / "paper_b_stiffness.csv", "--design", EXAMPLES / "paper_b_guess.json", "--loop", path)
    assert "Traceback" not in r.stderr and "internal error" not in r.stderr, (case, r.stderr)
    assert r.returncode == 2 and r.stdout == "", (case, r.stderr)
    assert r.stderr.count("\n") == 1 and needle in r.stderr, (case, r.stderr)


def test_a_full_standard_output_is_a_message_not_a_traceback():
    with open("/dev/full", "w") as full:
        r = bushing("stiffness", EXAMPLES / "paper_b_true.json", "--freq", 1, 100, 3, "--amp", 1e-4, stdout=full)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "standard output" in r.stderr


def test_a_fit_to_one_point_repeated_writes_valid_json(tmp_path):
    """150 copies of one point cannot determine five parameters, but they are valid data: the fit
    finishes, says which parameters are undetermined, and its file is strict JSON."""
    k = 4.2e6 * (1 + 0.14j) / np.sqrt(1 + 0.14**2)
    data = MeasuredStiffness(np.full(150, 10.0), np.full(150, 1e-4), np.full(150, k))
    data.to_csv(tmp_path / "same.csv")
    r = bushing("fit", tmp_path / "same.csv", "--design", EXAMPLES / "paper_b_true.json")
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout, parse_constant=lambda c: pytest.fail(f"{c} in the fit file"))
    assert set(report["fit"]["standard_errors"]) == {"shear_modulus", "fractional_coefficient", "fractional_order",
                                                      "friction_stress_max", "friction_strain_half"}
    # one point is two numbers: at least three of the five parameters stay undetermined
    assert len(report["fit"]["undetermined"]) >= 3
    assert all(line.startswith("bushing fit: warning: ") for line in r.stderr.splitlines())


def test_no_warning_reaches_the_user_on_success(tmp_path):
    design = tmp_path / "d.json"
    write_design(PAPER_B.replace(effects={"wave_effects": {"density": 1200.0}}), design)
    r = bushing("stiffness", design, "--freq", 1, 5000, 50, "--log", "--amp", 1e-6, 1e-3, 0.05)
    assert r.returncode == 0 and r.stderr == ""
    assert "nan" not in r.stdout.lower() and "inf" not in r.stdout.lower()
