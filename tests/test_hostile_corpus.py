"""The hostile corpus (tests/hostile_corpus.py), run in this process case by case: each case is
refused with the right reason or accepted with a correct result, as its expectation says.

A refusal: the expected exit status, nothing on standard output, one line on standard error
holding the words of the expectation (the key, column or option and the rule). An acceptance:
exit 0, standard error empty (a fit's warnings excepted), the documented columns or keys, only
finite numbers, and what the physics fixes apart from the implementation (CHECKS):

* stiffness: removing the closed-form branches of the long axial bushing from K, K/S − µ(1 +
  ¾βε̂²) − m(iω)^α/2 − iωc/2 + ω²M/S (S = 2πL/ln(b/a), eq 18; ε̂ = c·x̂, eq 15; the fractional
  branch eq 5 over 2), leaves the friction modulus µ_f(ε̂): the same at every frequency (the
  friction is rate independent), 0 ≤ Re µ_f ≤ σ_fmax/(2ε½), Im µ_f ≥ 0, σ_fmax/(2ε½) at
  vanishing amplitude;
* loop: the branches add up to the force (eq 1), the elastic and viscoelastic ones are those
  closed forms along x̂ sin θ, and the first harmonic of the force is `bushing stiffness`'s K;
* band: every percentile lies within the corners of the tolerance box (K = (L/L₀)(K₀ + S₀Δµ));
* fit, diagnose: the report's gap recomputed from its design by `bushing stiffness` at every
  measured point; design: every value reported is |K| of that design by `bushing stiffness`,
  and `met` agrees with it.

No case has a time limit (a slow machine is not a failure); HANG_GUARD_S is a guard against a
real hang of the whole module, not a speed check.
"""

from __future__ import annotations

import contextlib
import csv
import functools
import io
import json
import os
import shutil
import signal
import tempfile
from collections import Counter
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import pytest

from cli.main import main
from tests.hostile_cases import DESIGN, Accepted, Refused
from tests.hostile_corpus import EFFECT_CASES, TOLERANCES, corpus

FOLDER = Path(tempfile.gettempdir()) / f"bushing-hostile-corpus-{os.getpid()}"
CASES, FILES = corpus(FOLDER)
HANG_GUARD_S = 3600  # the whole module takes a few minutes; only a hang takes an hour
STIFFNESS_COLUMNS = ("frequency_hz", "amplitude", "stiffness_real", "stiffness_imag", "magnitude", "loss_factor")
LOOP_COLUMNS = ("displacement", "force", "force_elastic", "force_viscoelastic", "force_friction")
FIT_KEYS = {"standard_errors", "correlation", "confidence", "intervals", "undetermined", "gap", "points",
            "method", "starts"}
DIAGNOSIS_KEYS = {"baseline", "added", "steps", "gap_baseline", "gap_final", "unexplained", "points", "design",
                  "uncertainty"}


class Hang(Exception):
    pass


@pytest.fixture(scope="module", autouse=True)
def corpus_files():
    """The corpus' files, written once; the hang guard armed over the module's run."""
    FOLDER.mkdir(parents=True, exist_ok=True)
    for path, text in FILES.items():
        if isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(text, encoding="utf-8", errors="surrogatepass")

    def hang(_signum, _frame):
        raise Hang(f"hang guard: the corpus has not finished after {HANG_GUARD_S} s (a hang, not a speed check)")

    previous = signal.signal(signal.SIGALRM, hang)
    signal.alarm(HANG_GUARD_S)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)
    shutil.rmtree(FOLDER, ignore_errors=True)


@dataclass(frozen=True)
class Run:
    status: object
    stdout: str
    stderr: str


def run(argv) -> Run:
    """``bushing ARGV`` in this process; an exception that escapes main() fails the test."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            status = main([str(a) for a in argv])
        except SystemExit as exc:
            status = exc.code
    return Run(status, out.getvalue(), err.getvalue())


@functools.cache
def reference(argv: tuple) -> Run:
    """A run another case's result is compared with: it must succeed."""
    r = run(argv)
    assert r.status == 0, (argv, r.stderr)
    return r


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_each_case_is_refused_with_its_reason_or_gives_a_correct_result(case):
    r = run(case.argv)
    if isinstance(case.expect, Refused):
        line = r.stderr.rstrip("\n")
        assert (r.status, r.stdout) == (case.expect.status, ""), f"exit {r.status}: {r.stderr.strip()!r}"
        assert r.stderr.count("\n") == 1 and r.stderr.endswith("\n") and line.startswith("bushing"), r.stderr
        assert "internal error" not in line and "Traceback" not in line, line
        missing = [w for w in case.expect.words if w not in line]
        assert not missing, f"{line!r} does not name {missing}"
        return
    expect = case.expect
    assert r.status == 0, f"exit {r.status}: {r.stderr.strip()!r}"
    allowed = "bushing fit: warning: " if expect.output == "fit" else "\0"
    assert all(line.startswith(allowed) for line in r.stderr.splitlines()), r.stderr
    CHECKS[expect.output](case.argv, r.stdout)
    missing = [w for w in expect.words if w not in r.stdout]
    assert not missing, f"the output does not say {missing}"
    if expect.same_as:
        same(expect.output, r.stdout, reference(expect.same_as).stdout, expect.rtol)


# ---- reading the runs ---------------------------------------------------------------------------


def option(argv, name: str, count: int = 1) -> list[str]:
    i = argv.index(name)
    return list(argv[i + 1:i + 1 + count])


def amplitudes(argv) -> list[float]:
    i, out = argv.index("--amp") + 1, []
    while i < len(argv) and not argv[i].startswith("--"):
        out.append(float(argv[i]))
        i += 1
    return out


def table(text: str) -> tuple[tuple[str, ...], np.ndarray]:
    rows = list(csv.reader(io.StringIO(text)))
    values = np.array([[float(cell) for cell in row] for row in rows[1:]])
    assert values.size and np.all(np.isfinite(values)), "a number that is not finite in the output"
    return tuple(rows[0]), values


def strict_json(text: str):
    def refuse(constant):
        raise AssertionError(f"{constant} in the JSON output")

    return json.loads(text, parse_constant=refuse)


def design_of(path) -> dict:
    return json.loads(Path(path).read_text(encoding="utf-8-sig"))


def measured_rows(paths) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frequency, amplitude and complex K of every row of measured files, read from docs/files.md's
    three forms: |K| and η (K = |K|(1 + iη)/√(1 + η²)), Re K and Im K, |K| and its phase."""
    f, a, k = [], [], []
    for path in paths:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            rows = list(csv.reader(fh, skipinitialspace=True))
        cols = {name.strip(): i for i, name in enumerate(rows[0])}
        for row in rows[1:]:
            v = {name: float(row[i].strip()) for name, i in cols.items()}
            f.append(v["frequency_hz"])
            a.append(v["amplitude"])
            if "loss_factor" in v:
                k.append(v["magnitude"] * (1 + 1j * v["loss_factor"]) / np.hypot(1, v["loss_factor"]))
            elif "phase_deg" in v:
                k.append(v["magnitude"] * np.exp(1j * np.radians(v["phase_deg"])))
            else:
                k.append(v["stiffness_real"] + 1j * v["stiffness_imag"])
    return np.array(f), np.array(a), np.array(k)


def stiffness_at(design, frequency_hz: float, amplitude: float) -> complex:
    """K of a design (a file, or a design object written to one) by `bushing stiffness`."""
    if isinstance(design, dict):
        path = FOLDER / f"checked_{abs(hash(json.dumps(design, sort_keys=True)))}.json"
        path.write_text(json.dumps(design))
        design = path
    f, x = repr(float(frequency_hz)), repr(float(amplitude))
    out = reference(("stiffness", str(design), "--freq", f, f, "1", "--amp", x)).stdout
    _, v = table(out)
    return complex(v[0, 2], v[0, 3])


def gap_of(design: dict, rows) -> float:
    """docs/files.md's gap, √(mean |K_model − K_data|² / |K_data|²), over every measured row."""
    f, a, k = rows
    model = np.array([stiffness_at(design, fi, ai) for fi, ai in zip(f, a)])
    return float(np.sqrt(np.mean(np.abs(model / k - 1) ** 2)))


# ---- the closed forms of the long axial bushing ----------------------------------------------


def factors(design: dict) -> tuple[float, float]:
    """S = 2πL/ln(b/a) (eq 18: K = S·µ_eq) and c with ε̂ = c·x̂ (eq 15) of a long axial bushing."""
    assert design["mode"] == "axial" and design.get("shape", "long") == "long", "no closed form for this design"
    g = design["geometry"]
    a, b, length = g["inner_radius"], g["outer_radius"], g["length"]
    return 2 * np.pi * length / np.log(b / a), 1 / np.sqrt(2 * (b * b - a * a) * np.log(b / a))


def effect(design: dict, eid: str, name: str) -> float:
    assert set(design.get("effects", {})) <= {"inertia", "viscous", "strain_stiffening"}
    return design.get("effects", {}).get(eid, {}).get(name, 0.0)


def elastic_and_viscous(design: dict, frequency_hz, strain):
    """µ(1 + ¾βε̂²) (the cubic stiffening's first harmonic) and m(iω)^α/2 + iωc/2 (eq 5 over 2,
    σ = 2µε; a viscous stress c dε/dt), in Pa."""
    m, w = design["material"], 2 * np.pi * np.asarray(frequency_hz, dtype=float)
    elastic = m["shear_modulus"] * (1 + 0.75 * effect(design, "strain_stiffening", "stiffening") * strain ** 2)
    viscous = m["fractional_coefficient"] * (1j * w) ** m["fractional_order"] / 2
    return elastic, viscous + 1j * w * effect(design, "viscous", "viscosity") / 2


def check_stiffness(argv, stdout: str, extra=()) -> np.ndarray:
    header, v = table(stdout)
    assert header == (*STIFFNESS_COLUMNS, *extra), header
    f1, f2, n = option(argv, "--freq", 3)
    freqs = (np.geomspace if "--log" in argv else np.linspace)(float(f1), float(f2), int(n))
    want = sorted((a, f) for a in amplitudes(argv) for f in freqs)  # one row per amplitude and frequency
    np.testing.assert_allclose(sorted(zip(v[:, 1], v[:, 0])), want, rtol=1e-11)  # 12 digits written
    k = v[:, 2] + 1j * v[:, 3]
    np.testing.assert_allclose(v[:, 4], np.abs(k), rtol=1e-10)
    np.testing.assert_allclose(v[:, 5], k.imag / k.real, rtol=1e-10)
    design = design_of(argv[1])
    s, c = factors(design)
    elastic, viscous = elastic_and_viscous(design, v[:, 0], c * v[:, 1])
    mass = effect(design, "inertia", "mass")
    inertia = (2 * np.pi * v[:, 0]) ** 2 * mass if mass else 0.0  # K − ω²M
    friction = (k + inertia) / s - elastic - viscous
    # the written digits (1e-12 of |K|), or the simulation's accuracy on the time-domain route
    slack = np.max(np.abs(k)) / s * (1e-4 if "time-domain" in argv else 1e-9)
    m = design["material"]
    top = m["friction_stress_max"] / (2 * m["friction_strain_half"])  # µ_f at vanishing amplitude
    assert np.all(friction.real >= -slack) and np.all(friction.real <= top + slack), friction
    assert np.all(friction.imag >= -slack), friction
    for amp in np.unique(v[:, 1]):  # rate-independent friction: one µ_f per amplitude
        at = friction[v[:, 1] == amp]
        assert np.ptp(at.real) <= 2 * slack and np.ptp(at.imag) <= 2 * slack, (amp, at)
    tiny = c * v[:, 1] / m["friction_strain_half"] < 1e-12
    np.testing.assert_allclose(friction[tiny], top, rtol=1e-9, atol=slack)
    return v


def check_band(argv, stdout: str) -> None:
    """Percentiles in order, within the corners of the tolerance box: K = (L/L₀)(K₀ + S₀Δµ), as
    K = S·µ_eq with S ∝ L (eq 18) and ε̂ independent of L (eq 15)."""
    spec = json.loads(Path(option(argv, "--tolerance")[0]).read_text())
    qs = [f"{q:g}".replace(".", "_") for q in spec.get("percentiles", [5, 50, 95])]
    v = check_stiffness(argv, stdout, [f"magnitude_p{q}" for q in qs] + [f"loss_factor_p{q}" for q in qs])
    n, design = len(qs), design_of(argv[1])
    mag, eta = v[:, 6:6 + n], v[:, 6 + n:6 + 2 * n]
    assert np.all(np.diff(mag, axis=1) >= 0) and np.all(np.diff(eta, axis=1) >= 0)
    assert set(spec["tolerances"]) <= {"shear_modulus", "length"}
    nominal = {"shear_modulus": design["material"]["shear_modulus"], "length": design["geometry"]["length"]}
    h = {name: float(t[:-1]) / 100 * nominal[name] if isinstance(t, str) else t for name, t in spec["tolerances"].items()}
    k0, (s, _) = v[:, 2] + 1j * v[:, 3], factors(design)
    corners = np.array([(1 + dl / nominal["length"]) * (k0 + s * dmu)
                        for dmu in (-h.get("shear_modulus", 0), h.get("shear_modulus", 0))
                        for dl in (-h.get("length", 0), h.get("length", 0))])
    for values, ends in ((mag, np.abs(corners)), (eta, corners.imag / corners.real)):
        low, high = ends.min(axis=0)[:, None], ends.max(axis=0)[:, None]
        assert np.all(values >= low - 1e-9 * np.abs(low)) and np.all(values <= high + 1e-9 * np.abs(high))


def check_loop(argv, stdout: str) -> None:
    header, v = table(stdout)
    assert header == LOOP_COLUMNS, header
    f, amp = float(option(argv, "--freq")[0]), float(option(argv, "--amp")[0])
    n = int(option(argv, "--points")[0]) if "--points" in argv else 256
    theta = 2 * np.pi * np.arange(n) / n
    assert v.shape == (n, 5)
    x, force, el, ve, fr = v.T
    np.testing.assert_allclose(x, amp * np.sin(theta), rtol=0, atol=1e-11 * amp)
    np.testing.assert_allclose(force, el + ve + fr, rtol=0, atol=1e-10 * np.max(np.abs(force)))  # eq 1
    design = design_of(argv[1])
    s, c = factors(design)
    mu, beta = design["material"]["shear_modulus"], effect(design, "strain_stiffening", "stiffening")
    elastic = s * mu * x * (1 + beta * (c * x) ** 2)  # σ = 2µε(1 + βε²) with ε = c·x, F = S·σ/(2c)
    np.testing.assert_allclose(el, elastic, rtol=0, atol=1e-10 * np.max(np.abs(elastic)))
    k_ve = s * elastic_and_viscous(design, f, 0.0)[1]
    np.testing.assert_allclose(ve, amp * np.imag(k_ve * np.exp(1j * theta)), rtol=0, atol=1e-10 * amp * abs(k_ve))
    harmonic = 2 / (n * amp) * (np.sum(force * np.sin(theta)) + 1j * np.sum(force * np.cos(theta)))
    k = stiffness_at(argv[1], f, amp)
    # the sampled loop's harmonic against the closed form: the friction's reversals are kinks
    # (1e-7 apart at 64 points)
    assert abs(harmonic - k) <= 1e-5 * abs(k), (harmonic, k)


def check_fit(argv, stdout: str) -> None:
    report, given = strict_json(stdout), design_of(option(argv, "--design")[0])
    assert (report["mode"], report["geometry"]) == (given["mode"], given["geometry"])  # kept
    assert set(report["material"]) == set(given["material"])
    fit = report["fit"]
    assert FIT_KEYS <= set(fit), sorted(fit)
    rows = measured_rows(argv[1:argv.index("--design")])
    assert fit["points"] == len(rows[0])
    if "--loop" in argv:
        assert 0 <= fit["loop_rms"] < np.inf
    if "--fit-on" in argv:  # the corpus' selections choose every row
        assert fit["prediction"]["points_fitted"] == len(rows[0])
    np.testing.assert_allclose(fit["gap"], gap_of(report, rows), rtol=1e-6, atol=1e-9)  # |K| to 12 digits


def check_diagnosis(argv, stdout: str) -> None:
    report = strict_json(stdout)
    assert DIAGNOSIS_KEYS <= set(report), sorted(report)
    rows = measured_rows(argv[1:argv.index("--design")])
    assert report["points"] == len(rows[0])
    # docs/diagnosis.md: one amplitude (or frequency) left out in turn, given three of them
    assert ("held_out" in report) == (len(set(rows[1])) >= 3 or len(set(rows[0])) >= 3)
    # the final model holds the baseline: fitted by least squares, it cannot fit worse
    assert report["gap_final"] <= report["gap_baseline"] * (1 + 1e-9) + 1e-12
    np.testing.assert_allclose(report["gap_final"], gap_of(report["design"], rows), rtol=1e-6, atol=1e-9)


def check_design(argv, stdout: str) -> None:
    report, problem = strict_json(stdout), json.loads(Path(argv[1]).read_text())
    assert isinstance(report["statement"], str) and report["feasible"] is bool(report["solutions"])
    entries = report["solutions"] + ([report["closest"]] if "closest" in report else [])
    assert entries and (report["feasible"] or not all(t["met"] for t in report["closest"]["targets"]))
    limit = problem.get("limits", {}).get("outer_radius", {}).get("max", 1.0)
    assert all(t["met"] for entry in report["solutions"] for t in entry["targets"])
    for entry in entries:
        assert entry["design"]["geometry"]["outer_radius"] <= limit * (1 + 1e-9)
        for target, got in zip(problem["targets"], entry["targets"], strict=True):
            assert target["mode"] == entry["design"]["mode"]
            value = abs(stiffness_at(entry["design"], target["frequency_hz"], target["amplitude"]))
            np.testing.assert_allclose(got["value"], value, rtol=1e-9)  # |K| written to 12 digits
            goal, tol = target["magnitude"], problem.get("tolerance", 0.01)
            low, high = (goal.get("min"), goal.get("max")) if isinstance(goal, dict) else (goal * (1 - tol),
                                                                                           goal * (1 + tol))
            inside = (low is None or value >= low * (1 - 1e-5)) and (high is None or value <= high * (1 + 1e-5))
            outside = (low is not None and value < low) or (high is not None and value > high)
            assert inside if got["met"] else outside, (target, got, value)


CHECKS = {"stiffness": check_stiffness, "band": check_band, "loop": check_loop, "fit": check_fit,
          "diagnose": check_diagnosis, "design": check_design}


def same(output: str, got: str, want: str, rtol: float) -> None:
    """The result equals another run's: reports as objects (a fit's selection text apart),
    tables row by row (sorted by frequency and amplitude)."""
    if output in ("fit", "diagnose", "design"):
        a, b = strict_json(got), strict_json(want)
        for report in (a, b):
            report.get("fit", {}).get("prediction", {}).pop("fit_on", None)
        assert a == b
        return
    (ha, va), (hb, vb) = table(got), table(want)
    assert ha == hb
    order_a, order_b = np.lexsort((va[:, 0], va[:, 1])), np.lexsort((vb[:, 0], vb[:, 1]))
    np.testing.assert_allclose(va[order_a], vb[order_b], rtol=rtol, atol=0)


# ---- the table itself ---------------------------------------------------------------------------


def test_the_corpus_names_only_real_keys():
    """An effect, parameter or key misspelt in the corpus tests nothing (it is refused as unknown
    whatever the value): every name it uses is one the core knows."""
    from core.effects import EFFECTS
    from core.parts import Geometry, Material

    for eid, parameter in EFFECT_CASES:
        assert eid in EFFECTS and parameter in [p.name for p in EFFECTS[eid].parameters], (eid, parameter)
    assert list(DESIGN["geometry"]) == [f.name for f in fields(Geometry)]
    assert list(DESIGN["material"]) == [f.name for f in fields(Material) if f.default is not None]
    assert [f.name for f in fields(Material) if f.default is None] == ["bulk_modulus"]  # its cases are added
    assert set(TOLERANCES["tolerances"]) <= {*DESIGN["geometry"], *DESIGN["material"]}


def test_every_case_carries_its_expectation(capsys):
    assert len({c.name for c in CASES}) == len(CASES) >= 800
    for case in CASES:
        assert isinstance(case.expect, (Refused, Accepted)), case.name
        if isinstance(case.expect, Refused):
            assert case.expect.words and case.expect.status in (1, 2), case.name
        else:
            assert case.expect.output in CHECKS, case.name
    counts = Counter(type(c.expect).__name__ for c in CASES)
    with capsys.disabled():
        print(f"\nhostile corpus: {len(CASES)} runs, {counts['Refused']} to be refused, "
              f"{counts['Accepted']} to give a checked result")
