"""A hostile corpus for the command line: design files, measured stiffness and loop files and
options broken in every way a hurried or hostile user manages, generated systematically.

Each case is an argv for ``bushing`` (files written into a folder) and is run in this process
through :func:`app.cli.main`, standard output and error captured, with a time limit. The outcome
of a run is one of:

* ``ok``: exit 0, and the output is clean: CSV without nan or inf, strict JSON; standard error
  empty or only ``bushing fit: warning:`` lines;
* ``refused``: exit 2 (bad input) or 1 (a computation the formulas cannot give), nothing on
  standard output, exactly one line on standard error, no "internal error";
* a failure: ``traceback`` (an exception escaped), ``internal error``, ``hang`` (over the time
  limit), ``nan output``, ``noise`` (more than the one line, or warnings, on standard error).
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import signal
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from app.cli import main

DESIGN = {
    "name": "corpus",
    "mode": "axial",
    "geometry": {"inner_radius": 0.02, "outer_radius": 0.035, "length": 0.09},
    "material": {"shear_modulus": 2420000.0, "fractional_coefficient": 600000.0, "fractional_order": 0.2,
                 "friction_stress_max": 19200.0, "friction_strain_half": 0.004},
}
# JSON texts put in place of a number
BAD_NUMBERS = ["0", "-1", "-0.0", "1e-300", "1e300", "1" + "0" * 400, "NaN", "Infinity", "-Infinity", '"2.4e6"',
               "null", "true", "[]", "{}", "1e-12", "4_858_578", "0x10", '""']
# CSV cells put in place of a number
BAD_CELLS = ["", "abc", "nan", "inf", "-inf", "-1", "0", "1e300", "1e-300", "1_0", "0x10", "1,5", '"1"', "１", " 7 "]
TIME_LIMIT_S = 60


@dataclass(frozen=True)
class Case:
    name: str
    argv: tuple[str, ...]


def _design_text(change) -> str:
    data = json.loads(json.dumps(DESIGN))
    change(data)
    return json.dumps(data)


def design_cases(folder: Path) -> list[Case]:
    texts: dict[str, str] = {}
    for section in ("geometry", "material"):
        for key in DESIGN[section]:
            for bad in BAD_NUMBERS:
                text = json.dumps(DESIGN).replace(f'"{key}": {json.dumps(DESIGN[section][key])}', f'"{key}": {bad}')
                texts[f"{section}.{key} = {bad[:20]}"] = text
    for eid, pname in (("inertia", "mass"), ("viscous_damping", "viscosity"), ("strain_stiffening", "stiffening")):
        for bad in BAD_NUMBERS[:10]:
            texts[f"effects.{eid}.{pname} = {bad[:20]}"] = json.dumps(DESIGN)[:-1] + f', "effects": {{"{eid}": {{"{pname}": {bad}}}}}}}'
    texts.update({
        "empty": "",
        "not JSON": "mode: axial",
        "a JSON list": "[1, 2, 3]",
        "nested deep": "[" * 50000 + "]" * 50000,
        "a key twice": json.dumps(DESIGN).replace('"mode": "axial"', '"mode": "axial", "mode": "torsion"'),
        "unknown mode": _design_text(lambda d: d.update(mode="radial-ish")),
        "mode a number": _design_text(lambda d: d.update(mode=3)),
        "no geometry": _design_text(lambda d: d.pop("geometry")),
        "extra key": _design_text(lambda d: d["material"].update(colour="black")),
        "outer radius inside inner": _design_text(lambda d: d["geometry"].update(outer_radius=0.01)),
        "unknown effect": _design_text(lambda d: d.update(effects={"magic": {"x": 1}})),
        "effects a list": _design_text(lambda d: d.update(effects=[1])),
        "a BOM": "\ufeff" + json.dumps(DESIGN),
        "binary": "\x00\x01\x02" * 100,
        "a 5 MB name": _design_text(lambda d: d.update(name="x" * 5_000_000)),
        "geometry a string": _design_text(lambda d: d.update(geometry="big")),
    })
    cases = []
    for i, (name, text) in enumerate(texts.items()):
        path = folder / f"design_{i}.json"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        cases.append(Case(f"design: {name}: stiffness", ("stiffness", str(path), "--freq", "1", "100", "4", "--amp", "1e-4")))
        cases.append(Case(f"design: {name}: loop", ("loop", str(path), "--freq", "10", "--amp", "1e-4", "--points", "64")))
    return cases


def _stiffness_rows():
    return [[f"{f:g}", f"{a:g}", "4200000", "0.14"] for f in (1, 10, 100) for a in (1e-5, 1e-4, 1e-3)]


def measured_cases(folder: Path, design: Path) -> list[Case]:
    header = ["frequency_hz", "amplitude", "magnitude", "loss_factor"]
    texts: dict[str, str] = {}
    for col in range(4):
        for bad in BAD_CELLS:
            rows = _stiffness_rows()
            rows[4][col] = bad
            texts[f"{header[col]} = {bad!r}"] = ",".join(header) + "\n" + "".join(",".join(r) + "\n" for r in rows)
    good = "".join(",".join(r) + "\n" for r in _stiffness_rows())
    texts.update({
        "empty": "",
        "header only": ",".join(header) + "\n",
        "no header": good,
        "an unknown column": ",".join(header) + ",temperature\n" + good.replace("\n", ",20\n"),
        "semicolons": (",".join(header) + "\n" + good).replace(",", ";"),
        "a short row": ",".join(header) + "\n" + good + "10,1e-4\n",
        "a long row": ",".join(header) + "\n" + good + "10,1e-4,4e6,0.1,9\n",
        "binary": "\x00\xff" * 200,
        "one point": ",".join(header) + "\n10,1e-4,4200000,0.14\n",
        "one point 150 times": ",".join(header) + "\n" + "10,1e-4,4200000,0.14\n" * 150,
        "a loss factor of 1e6": ",".join(header) + "\n" + good + "10,1e-4,4200000,1e6\n",
        "stiffness 1e300": ",".join(header) + "\n" + good.replace("4200000", "1e300"),
        "stiffness 1e-300": ",".join(header) + "\n" + good.replace("4200000", "1e-300"),
        "210 000 rows": ",".join(header) + "\n" + "10,1e-4,4200000,0.14\n" * 210_000,
        "real and imaginary, zero": "frequency_hz,amplitude,stiffness_real,stiffness_imag\n" + "10,1e-4,0,0\n" * 3,
        "both column pairs": ",".join(header) + ",stiffness_real,stiffness_imag\n" + good.replace("\n", ",1,1\n"),
    })
    cases = []
    for i, (name, text) in enumerate(texts.items()):
        path = folder / f"measured_{i}.csv"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        cases.append(Case(f"measured: {name}: fit", ("fit", str(path), "--design", str(design))))
        if name in ("one point 150 times", "a loss factor of 1e6", "stiffness 1e300"):
            cases.append(Case(f"measured: {name}: diagnose", ("diagnose", str(path), "--design", str(design))))
    return cases


def loop_cases(folder: Path, design: Path, measured: Path) -> list[Case]:
    t = np.arange(400) / 2000.0
    x = 1e-4 * np.sin(2 * np.pi * 10 * t)
    f = 400.0 * np.sin(2 * np.pi * 10 * t + 0.2)

    def text(tt, xx, ff):
        return "time_s,displacement,force\n" + "".join(f"{a:.17g},{b:.17g},{c:.17g}\n" for a, b, c in zip(tt, xx, ff))

    texts = {
        "a time step of 1e-300 s": text(t * 1e-300, x, f),
        "a time step of 1e300 s": text(t * 1e300, x, f),
        "times in ms": text(t * 1000, x, f),
        "displacements x1e300": text(t, x * 1e300, f),
        "displacements x1e-12": text(t, x * 1e-12, f),
        "forces x1e300": text(t, x, f * 1e300),
        "forces zero": text(t, x, f * 0),
        "a third of a period": text(t[:67], x[:67], f[:67]),
        "15 rows": text(t[:15], x[:15], f[:15]),
        "a square drive": text(t, 1e-4 * np.sign(np.sin(2 * np.pi * 10 * t + 0.1)), f),
        "noise only": text(t, 1e-4 * np.random.default_rng(0).standard_normal(t.size), f),
        "time backwards": text(t[::-1], x, f),
        "a repeated time": text(np.r_[t[:10], t[9:399]], x, f),
        "columns swapped": "force,time_s,displacement\n" + "".join(f"{c!r},{a!r},{b!r}\n" for a, b, c in zip(t, x, f)),
        "a nan": text(t, np.r_[x[:5], np.nan, x[6:]], f),
        "empty": "",
    }
    cases = []
    for i, (name, body) in enumerate(texts.items()):
        path = folder / f"loop_{i}.csv"
        path.write_text(body.replace("np.float64(", "").replace(")", ""))
        cases.append(Case(f"loop: {name}: fit", ("fit", str(measured), "--design", str(design), "--loop", str(path))))
    return cases


def option_cases(folder: Path, design: Path, measured: Path) -> list[Case]:
    d, m = str(design), str(measured)
    argvs = {
        "no command": (),
        "unknown command": ("fly",),
        "stiffness without --amp": ("stiffness", d, "--freq", "1", "10", "3"),
        "--freq with two numbers": ("stiffness", d, "--freq", "1", "10", "--amp", "1e-4"),
        "--freq count 0": ("stiffness", d, "--freq", "1", "10", "0", "--amp", "1e-4"),
        "--freq count 2.5": ("stiffness", d, "--freq", "1", "10", "2.5", "--amp", "1e-4"),
        "--freq count 1e7": ("stiffness", d, "--freq", "1", "10", "10000000", "--amp", "1e-4"),
        "--freq reversed": ("stiffness", d, "--freq", "100", "1", "3", "--amp", "1e-4"),
        "--freq nan": ("stiffness", d, "--freq", "nan", "10", "3", "--amp", "1e-4"),
        "--freq 1e400": ("stiffness", d, "--freq", "1", "1e400", "3", "--amp", "1e-4"),
        "--freq 1e300": ("stiffness", d, "--freq", "1", "1e300", "3", "--amp", "1e-4"),
        "--amp negative": ("stiffness", d, "--freq", "1", "10", "3", "--amp", "-1e-3"),
        "--amp 0": ("stiffness", d, "--freq", "1", "10", "3", "--amp", "0"),
        "--amp 1e300 continuum": ("stiffness", d, "--freq", "1", "10", "3", "--amp", "1e300", "--continuum"),
        "--amp 1e-300": ("stiffness", d, "--freq", "1", "10", "3", "--amp", "1e-300"),
        "--amp x 2000": ("stiffness", d, "--freq", "1", "1000", "1000", "--amp", *["1e-4"] * 2000),
        "--slices 0": ("stiffness", d, "--freq", "1", "10", "3", "--amp", "1e-4", "--slices", "0"),
        "--slices 1e9": ("stiffness", d, "--freq", "1", "10", "3", "--amp", "1e-4", "--slices", "1000000000"),
        "--slices and --continuum": ("stiffness", d, "--freq", "1", "10", "3", "--amp", "1e-4", "--slices", "3",
                                     "--continuum"),
        "--route unknown": ("stiffness", d, "--freq", "1", "10", "3", "--amp", "1e-4", "--route", "guess"),
        "time domain over 1e5 Hz": ("stiffness", d, "--freq", "1e5", "1e5", "1", "--amp", "1e-4", "--route",
                                    "time-domain"),
        "time domain, 2000 points": ("stiffness", d, "--freq", "1", "100", "2000", "--amp", "1e-4", "--route",
                                     "time-domain"),
        "time domain, continuum": ("stiffness", d, "--freq", "1", "100", "100", "--amp", "1e-4", "1e-3", "--continuum",
                                   "--route", "time-domain"),
        "1000 slices on a million points": ("stiffness", d, "--freq", "1", "100", "100000", "--amp", *["1e-4"] * 10,
                                            "--slices", "1000"),
        "loop --points 1e14": ("loop", d, "--freq", "1", "--amp", "1e-3", "--points", "99999999999999"),
        "loop --points 1": ("loop", d, "--freq", "1", "--amp", "1e-3", "--points", "1"),
        "loop --freq 1e-300": ("loop", d, "--freq", "1e-300", "--amp", "1e-3"),
        "loop --freq 1e300": ("loop", d, "--freq", "1e300", "--amp", "1e-3"),
        "a missing design file": ("loop", str(folder / "nothing.json"), "--freq", "1", "--amp", "1e-3"),
        "a folder as design": ("loop", str(folder), "--freq", "1", "--amp", "1e-3"),
        "-o into a missing folder": ("loop", d, "--freq", "1", "--amp", "1e-3", "-o", str(folder / "no" / "x.csv")),
        "-o /dev/full": ("loop", d, "--freq", "1", "--amp", "1e-3", "-o", "/dev/full"),
        "fit without --design": ("fit", m),
        "fit a missing loop": ("fit", m, "--design", d, "--loop", str(folder / "none.csv")),
        "diagnose --baseline nothing": ("diagnose", m, "--design", d, "--baseline", ""),
        "diagnose --baseline magic": ("diagnose", m, "--design", d, "--baseline", "elastic,magic"),
        "serve --port 70000": ("serve", "--port", "70000"),
        "serve --port -1": ("serve", "--port", "-1"),
        "an unknown option": ("loop", d, "--freq", "1", "--amp", "1e-3", "--colour", "red"),
        "card without --amp-rad": ("card", d, "--freq", "10", "--amp-mm", "0.1"),
        "card at 1e300 mm": ("card", d, "--freq", "10", "--amp-mm", "1e300", "--amp-rad", "0.01"),
        "export, an unknown format": ("export", d, "--format", "abaqus", "--freq", "1", "10", "2", "--amp", "1e-4"),
        "export, a million points": ("export", d, "--format", "table", "--freq", "1", "10", "100000", "--amp",
                                     *["1e-4"] * 11),
        "export at 1e300 m": ("export", d, "--format", "nastran", "--freq", "1", "10", "2", "--amp", "1e300"),
        "fit on nothing": ("fit", m, "--design", d, "--fit-on", "mode=axial,amplitude=7"),
        "fit on a bad key": ("fit", m, "--design", d, "--fit-on", "colour=red"),
        "fit on a huge selection text": ("fit", m, "--design", d, "--fit-on", "mode=" + "+".join(["axial"] * 5000)),
        "fit with 25 files": ("fit", *[m] * 25, "--design", d),
        "a number with underscores": ("loop", d, "--freq", "1_0", "--amp", "1e-3"),
    }
    return [Case(f"options: {name}", tuple(argv)) for name, argv in argvs.items()]


TOLERANCES = {"tolerances": {"shear_modulus": "10%", "length": 0.0005}, "samples": 50, "seed": 1}
TARGETS = {"design": DESIGN, "targets": [{"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": 4e6}],
           "limits": {"outer_radius": {"max": 0.04}}}


def _changed(base: dict, change) -> str:
    data = json.loads(json.dumps(base))
    change(data)
    return json.dumps(data)


def _put(path: tuple, text: str):
    """A change that puts the JSON ``text`` at ``path`` (its last key replaced)."""
    def change(data):
        holder = data
        for key in path[:-1]:
            holder = holder[key]
        holder[path[-1]] = "<<HERE>>"
    return change, text


def whatif_cases(folder: Path, design: Path) -> list[Case]:
    """Tolerance files for ``stiffness --tolerance`` and targets files for ``design``, broken."""
    d = str(design)
    texts: dict[str, tuple[str, str]] = {}  # name → (kind, text)
    for where in (("tolerances", "shear_modulus"), ("tolerances", "length"), ("samples",), ("seed",),
                  ("distribution",), ("percentiles",), ("fit_covariance",)):
        for bad in BAD_NUMBERS:
            change, text = _put(where, bad)
            texts[f"tolerance {'.'.join(where)} = {bad[:20]}"] = (
                "tolerance", _changed(TOLERANCES, change).replace('"<<HERE>>"', text))
    for where in (("targets", 0, "frequency_hz"), ("targets", 0, "amplitude"), ("targets", 0, "magnitude"),
                  ("limits", "outer_radius", "max"), ("solutions",), ("targets", 0, "mode"), ("targets",)):
        for bad in BAD_NUMBERS:
            change, text = _put(where, bad)
            texts[f"targets {'.'.join(map(str, where))} = {bad[:20]}"] = (
                "targets", _changed(TARGETS, change).replace('"<<HERE>>"', text))
    texts.update({
        "tolerance: nested 100 000 deep": ("tolerance", "[" * 100_000 + "]" * 100_000),
        "targets: nested 100 000 deep": ("targets", "[" * 100_000 + "]" * 100_000),
        "tolerance: 2 MB": ("tolerance", json.dumps({"tolerances": {"length": "1%"}, "pad": "x" * 2_000_000})),
        "targets: 2 MB": ("targets", json.dumps({**TARGETS, "pad": "x" * 2_000_000})),
        "tolerance: empty": ("tolerance", ""),
        "targets: empty": ("targets", ""),
        "targets: 5000 targets": ("targets", json.dumps({**TARGETS, "targets": TARGETS["targets"] * 5000})),
        "targets: contradicting": ("targets", json.dumps({**TARGETS, "targets": [
            {"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": {"min": 5e6}},
            {"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": {"max": 4e6}}]})),
        "targets: 1e30 N/m in a millimetre": ("targets", json.dumps({**TARGETS, "targets": [
            {"mode": "torsion", "frequency_hz": 1e5, "amplitude": 1.0, "magnitude": 1e30}],
            "limits": {"length": {"max": 0.001}}})),
        "targets: a ratio of one mode": ("targets", json.dumps({**TARGETS, "targets": [
            {"ratio": ["axial", "axial"], "frequency_hz": 10, "amplitude": 1e-4, "magnitude": 2}]})),
        "targets: every material free": ("targets", json.dumps({**TARGETS, "free_material": {
            n: {"min": 1e-30, "max": 1e30} for n in DESIGN["material"]}})),
        "tolerance: 5000 samples on a big grid": ("tolerance", json.dumps({**TOLERANCES, "samples": 5000})),
        "tolerance: 99 % of b": ("tolerance", json.dumps({"tolerances": {"outer_radius": "89%"}})),
    })
    cases = []
    for name, (kind, text) in texts.items():
        path = folder / f"whatif_{len(cases)}.json"
        path.write_text(text, encoding="utf-8")
        if kind == "tolerance":
            freq = ("1", "100", "5000") if "big grid" in name else ("1", "100", "5")
            argv = ("stiffness", d, "--freq", *freq, "--amp", "1e-4", "1e-3", "--tolerance", str(path))
        else:
            argv = ("design", str(path))
        cases.append(Case(f"what-ifs: {name}", argv))
    bad_bytes = folder / "whatif_latin1.json"
    bad_bytes.write_bytes('{"tolerances": {"length": "1%"}, "x": "é"}'.encode("latin-1"))
    cases.append(Case("what-ifs: a tolerance file not UTF-8", ("stiffness", d, "--freq", "1", "10", "2", "--amp",
                                                             "1e-4", "--tolerance", str(bad_bytes))))
    cases.append(Case("what-ifs: a missing targets file", ("design", str(folder / "none.json"))))
    cases.append(Case("what-ifs: a folder as tolerance file", ("stiffness", d, "--freq", "1", "10", "2", "--amp",
                                                               "1e-4", "--tolerance", str(folder))))
    return cases


def corpus(folder: Path) -> list[Case]:
    folder.mkdir(parents=True, exist_ok=True)
    design = folder / "good_design.json"
    design.write_text(json.dumps(DESIGN))
    measured = folder / "good_measured.csv"
    measured.write_text("frequency_hz,amplitude,magnitude,loss_factor\n"
                        + "".join(",".join(r) + "\n" for r in _stiffness_rows()))
    return (design_cases(folder) + measured_cases(folder, design) + loop_cases(folder, design, measured)
            + option_cases(folder, design, measured) + whatif_cases(folder, design))


class _Hang(Exception):
    pass


def _alarm(_signum, _frame):
    raise _Hang


def run(case: Case) -> tuple[str, str]:
    """Run one case; its outcome (see the module's docstring) and standard error."""
    out, err = io.StringIO(), io.StringIO()
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(TIME_LIMIT_S)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                status = main(list(case.argv))
            except SystemExit as exc:
                status = exc.code
    except _Hang:
        return "hang", err.getvalue()
    except BaseException as exc:  # noqa: BLE001 - what the corpus looks for
        return "traceback", f"{type(exc).__name__}: {exc}"
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    stdout, stderr = out.getvalue(), err.getvalue()
    if "internal error" in stderr or "Traceback" in stderr:
        return "internal error", stderr
    if status == 0:
        if any(not line.startswith("bushing fit: warning: ") for line in stderr.splitlines()):
            return "noise", stderr
        return ("nan output", stderr) if _not_clean(stdout) else ("ok", stderr)
    if status in (1, 2) and stdout == "" and stderr.count("\n") == 1 and stderr.startswith("bushing"):
        return "refused", stderr
    return "noise", stderr


def _not_clean(stdout: str) -> bool:
    text = stdout.strip()
    if text.startswith("{"):
        try:
            json.loads(text, parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
        except ValueError:
            return True
        return False
    for row in text.splitlines()[1:]:
        for cell in row.split(","):
            try:
                if not math.isfinite(float(cell)):
                    return True
            except ValueError:
                if cell.strip().lower() in ("nan", "inf", "-inf"):
                    return True
    return False


def run_corpus(folder: Path) -> tuple[Counter, dict[str, list[tuple[str, str]]], dict[str, float]]:
    """Every case: the count of each outcome, per outcome the cases with their stderr, and the
    seconds each case took."""
    counts: Counter = Counter()
    examples: dict[str, list[tuple[str, str]]] = {}
    seconds: dict[str, float] = {}
    for case in corpus(folder):
        t0 = time.perf_counter()
        outcome, stderr = run(case)
        seconds[case.name] = time.perf_counter() - t0
        counts[outcome] += 1
        examples.setdefault(outcome, []).append((case.name, stderr.strip()))
    return counts, examples, seconds
