"""A hostile corpus for the command line: design, measured, loop, tolerance and targets files
and options broken in every way a hurried or hostile user manages, generated systematically.
Each case carries its expected outcome, decided where it is generated from the rules of
docs/files.md, never read from a run: :class:`Refused` (exit status 2, or 1 for a computation
the formulas cannot give; nothing on standard output; one line on standard error holding each
of ``words``: the key, column or option and the rule broken) or :class:`Accepted` (exit 0 and a
correct result, checked by tests/test_hostile_corpus.py by its ``output`` kind: the documented
columns or keys, finite numbers, the relations the physics fixes; ``same_as``: a run that must
give the same result, the input without its harmless variation; ``words``: in the output).
Those outcomes, the good design and the bad JSON numbers are tests/hostile_cases.py's.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from core.parameters import MATERIAL
from tests.hostile_cases import (
    BAD_NUMBERS,
    DESIGN,
    NOT_JSON,
    STRAIN_FACTOR,
    Accepted,
    Case,
    Refused,
    finite,
    no,
    parsed,
)

# CSV cells put in place of a number: what a reader of docs/files.md takes each for
BAD_CELLS = {"": "missing", "abc": "not a number", "nan": "not finite", "inf": "not finite",
             "-inf": "not finite", "-1": -1.0, "0": 0.0, "1e300": 1e300, "1e-300": 1e-300, "1_0": "not a number",
             "0x10": "not a number", "1,5": "fields", '"1"': 1.0, "１": "not a number", " 7 ": 7.0}
# the effects the corpus breaks, by their ids in core/effects.py, and one parameter of each
EFFECT_CASES = (("inertia", "mass"), ("viscous", "viscosity"), ("strain_stiffening", "stiffening"))
# |K| and loss factor of DESIGN by its own model (bushing stiffness --freq 1 100 3 --log --amp
# 1e-5 1e-4 1e-3), 10 digits: a measurement the model can fit; the corpus breaks its row 4
GOOD_ROWS = [(1, 1e-5, 4968330.029, 0.0529464822), (10, 1e-5, 5216133.896, 0.06567226339),
             (100, 1e-5, 5610398.290, 0.0835702671), (1, 1e-4, 3955181.093, 0.1265571202),
             (10, 1e-4, 4207003.498, 0.138149288), (100, 1e-4, 4607075.406, 0.1539815814),
             (1, 1e-3, 3056397.762, 0.1107686922), (10, 1e-3, 3307576.764, 0.1266628995),
             (100, 1e-3, 3707041.056, 0.1475293568)]
FORMS = {"polar": ("magnitude", "loss_factor"), "cartesian": ("stiffness_real", "stiffness_imag"),
         "phase": ("magnitude", "phase_deg")}
TOLERANCES = {"tolerances": {"shear_modulus": "10%", "length": 0.0005}, "samples": 50, "seed": 1}
TARGETS = {"design": DESIGN, "targets": [{"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": 4e6}],
           "limits": {"outer_radius": {"max": 0.04}}}


def _number_rule(key: str, text: str, rule) -> tuple[str, ...] | None:
    """The refusal words of JSON ``text`` as the number ``key``, None if valid; ``rule`` gives
    the rule's word for a finite number (None: valid)."""
    value = parsed(text)
    if value is NOT_JSON:
        return ("not valid JSON", "line 1 column")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return (key, "must be a number")
    v = finite(value)
    word = "finite" if v is None else rule(v)
    return word and (key, word)


def _within(low, high, word):
    return lambda v: "positive" if v <= 0 else (None if low <= v <= high else word)


# docs/files.md: sizes 1 µm – 1 km, moduli positive (at most 1 TPa), α in (0, 1], ε½ in 1e-9 – 10
DESIGN_RULES = {**dict.fromkeys(DESIGN["geometry"], _within(1e-6, 1e3, "between")),
                **dict.fromkeys(("shear_modulus", "fractional_coefficient", "friction_stress_max"),
                                _within(0, 1e12, "at most")),
                "fractional_order": lambda v: None if 0 < v <= 1 else "(0, 1]",
                "friction_strain_half": _within(1e-9, 10.0, "between"),
                # K: positive, at most 1 TPa, and 50 to 10⁶ times µ
                "bulk_modulus": lambda v: ("positive" if v <= 0 else "at most" if v > 1e12 else
                                           None if 50 <= v / DESIGN["material"]["shear_modulus"] <= 1e6
                                           else "times the shear modulus")}


def design_cases(folder: Path, files: dict, good: Path) -> list[Case]:
    """Every number of the design file and of three effects set to each bad number, and broken
    structure; each file run by ``stiffness`` and by ``loop``."""
    texts: dict[str, tuple[str, object]] = {}  # name → (text, refusal words | "harmless" | None)
    for section in ("geometry", "material"):
        for key in DESIGN[section]:
            for bad in BAD_NUMBERS:
                text = json.dumps(DESIGN).replace(f'"{key}": {json.dumps(DESIGN[section][key])}', f'"{key}": {bad}')
                rule = _number_rule(f"{section}.{key}", bad, DESIGN_RULES[key])
                texts[f"{section}.{key} = {bad[:20]}"] = (text, rule)
    with_bulk = {**DESIGN, "material": {**DESIGN["material"], "bulk_modulus": 2.0e9}}  # the optional K
    for bad in BAD_NUMBERS:
        text = json.dumps(with_bulk).replace('"bulk_modulus": 2000000000.0', f'"bulk_modulus": {bad}')
        texts[f"material.bulk_modulus = {bad[:20]}"] = (
            text, _number_rule("material.bulk_modulus", bad, DESIGN_RULES["bulk_modulus"]))
    for eid, pname in EFFECT_CASES:
        for bad in BAD_NUMBERS[:10]:
            words = _number_rule(f"effects.{eid}.{pname}", bad, lambda v: "≥ 0" if v < 0 else None)
            harmless = words is None and finite(json.loads(bad)) < 1e-200  # a zero effect
            texts[f"effects.{eid}.{pname} = {bad[:20]}"] = (
                json.dumps(DESIGN)[:-1] + f', "effects": {{"{eid}": {{"{pname}": {bad}}}}}}}',
                "harmless" if harmless else words)
    texts.update({
        "empty": ("", ("not valid JSON",)), "not JSON": ("mode: axial", ("not valid JSON",)),
        "a JSON list": ("[1, 2, 3]", ("must be an object", "mode")),
        "nested deep": ("[" * 50000 + "]" * 50000, ("nested too deeply",)),
        "a key twice": (json.dumps(DESIGN).replace('"mode": "axial"', '"mode": "axial", "mode": "torsion"'),
                        ("mode", "given twice")),
        "unknown mode": (_changed(mode="radial-ish"), ("mode", "must be one of")),
        "mode a number": (_changed(mode=3), ("mode", "must be one of")),
        "no geometry": (_changed(geometry=None), ("geometry", "missing")),
        "extra key": (_changed(material={**DESIGN["material"], "colour": "black"}), ("material.colour", "unknown key")),
        "outer radius inside inner": (_changed(geometry={**DESIGN["geometry"], "outer_radius": 0.01}),
                                      ("geometry.outer_radius", "larger than")),
        "unknown effect": (_changed(effects={"magic": {"x": 1}}), ("effects.magic", "unknown effect")),
        "effects a list": (_changed(effects=[1]), ("effects", "must be an object")),
        "a BOM": ("\ufeff" + json.dumps(DESIGN), "harmless"),
        "binary": ("\x00\x01\x02" * 100, ("not valid JSON",)),
        "a 5 MB name": (_changed(name="x" * 5_000_000), ("design file", "too large")),
        "geometry a string": (_changed(geometry="big"), ("geometry", "must be an object")),
    })
    cases = []
    for i, (name, (text, rule)) in enumerate(texts.items()):
        files[path := folder / f"design_{i}.json"] = text
        for command, options in (("stiffness", ("--freq", "1", "100", "4", "--amp", "1e-4")),
                                 ("loop", ("--freq", "10", "--amp", "1e-4", "--points", "64"))):
            same = (command, str(good), *options) if rule == "harmless" else None
            expect = (Refused(rule) if isinstance(rule, tuple) else no("effects.inertia", "not available")
                      if command == "loop" and '"inertia"' in text else Accepted(command, same))  # no loop of a rig
            cases.append(Case(f"design: {name}: {command}", (command, str(path), *options), expect))
    return cases


def _changed(**changes) -> str:
    """DESIGN as JSON with top-level keys changed (None: left out)."""
    return json.dumps({k: v for k, v in {**DESIGN, **changes}.items() if v is not None})


def _form_row(row, form: str) -> list[str]:
    """One good row in a form of docs/files.md: |K| and η, Re K and Im K, or |K| and its phase."""
    f, a, mag, eta = row
    values = {"polar": (mag, eta), "cartesian": (mag / math.hypot(1, eta), eta * mag / math.hypot(1, eta)),
              "phase": (mag, math.degrees(math.atan(eta)))}[form]
    return [f"{f:g}", f"{a:g}", *(f"{v:.10g}" for v in values)]


def measured_text(form: str = "polar", row4: tuple[int, str] | None = None, extra: str = "",
                  magnitude: str | None = None) -> str:
    """GOOD_ROWS in ``form``; ``row4``: (column index, text) put in row 4 (line 6); ``extra``:
    lines added; ``magnitude``: put in every row."""
    rows = [_form_row(r, form) for r in GOOD_ROWS]
    if row4:
        rows[4][row4[0]] = row4[1]
    for row in rows if magnitude else ():
        row[2] = magnitude
    head = ",".join(("frequency_hz", "amplitude", *FORMS[form]))
    return head + "\n" + "".join(",".join(r) + "\n" for r in rows) + extra


def _with_column(text: str, name: str, value: str) -> str:
    lines = text.splitlines()
    return "\n".join([f"{lines[0]},{name}", *(f"{line},{value}" for line in lines[1:])]) + "\n"


def _both_forms() -> str:
    """GOOD_ROWS as ``bushing stiffness`` writes them: both forms of each K, 12 digits."""
    rows = []
    for f, x, m, eta in GOOD_ROWS:
        re = m / math.hypot(1.0, eta)
        rows.append(f"{f},{x},{re:.12g},{eta * re:.12g},{m},{eta}\n")
    return "frequency_hz,amplitude,stiffness_real,stiffness_imag,magnitude,loss_factor\n" + "".join(rows)


def _cell_rule(column: str, value) -> tuple[str, ...] | None:
    """The refusal words of a cell of line 6 read as ``value`` (BAD_CELLS), or None: valid (any
    finite complex K with |K| > 0, Re K < 0 and Im K < 0 too)."""
    if isinstance(value, str):
        return ("line 6", "fields") if value == "fields" else ("line 6", column, value)
    if column in ("frequency_hz", "amplitude", "magnitude") and value <= 0:
        return ("line 6", column, "positive")
    if column == "frequency_hz" and not 1e-4 <= value <= 1e5:
        return ("line 6", column, "within")
    if column == "amplitude" and not 1e-9 <= STRAIN_FACTOR * value <= 10:  # equivalent strains 1e-9 – 10
        return ("amplitude", "at most" if STRAIN_FACTOR * value > 10 else "at least")
    # |K| within 1e-6–1e15 N/m (docs/files.md); the row's other Cartesian part is about 5e5
    if column in ("magnitude", "stiffness_real", "stiffness_imag") and not abs(value) <= 1e15:
        return ("line 6", "magnitude", "units")
    if column == "magnitude" and value < 1e-6:
        return ("line 6", "magnitude", "units")
    return ("line 6", "phase_deg", "180") if column == "phase_deg" and abs(value) > 180 else None


def measured_cases(folder: Path, files: dict, design: Path) -> list[Case]:
    texts: dict[str, tuple[str, object]] = {}  # name → (text, refusal words or the commands that accept it)
    for form, pair in FORMS.items():
        for column in ("frequency_hz", "amplitude", *pair) if form == "polar" else pair:
            at = ("frequency_hz", "amplitude", *pair).index(column)
            for cell, value in BAD_CELLS.items():
                if form == "polar" or cell not in ('"1"', " 7 "):  # a cell's quotes and spaces: once
                    texts[f"{form} {column} = {cell!r}"] = (measured_text(form, row4=(at, cell)),
                                                            _cell_rule(column, value) or ("fit",))
    header = "frequency_hz,amplitude,magnitude,loss_factor\n"
    point = "10,1e-4,4207003.498,0.138149288\n"
    big = measured_text(magnitude="1e300")
    texts.update({
        **{f"the good file, {form}": (measured_text(form), ("fit",)) for form in FORMS},
        "empty": ("", ("stiffness file", "empty")),
        "header only": (header, ("no data rows",)),
        "no header": (measured_text().split("\n", 1)[1], ("line 1", "header")),
        "an unknown column": (_with_column(measured_text(), "temperature", "20"), ("line 1", "temperature")),
        "semicolons": (measured_text().replace(",", ";"), ("line 1", "header")),
        "a short row": (measured_text(extra="10,1e-4\n"), ("line 11", "missing")),
        "a long row": (measured_text(extra="10,1e-4,4e6,0.1,9\n"), ("line 11", "fields")),
        "binary": ("\x00\xff" * 200, ("line 1", "header")),
        "one point": (header + point, ("points", "parameters")),
        "one point 150 times": (header + point * 150, ("fit", "diagnose")),
        "a loss factor of 1e6": (measured_text(extra="10,1e-4,4200000,1e6\n"), ("fit", "diagnose")),
        "stiffness 1e300": (big, ("line 2", "magnitude", "units")),
        "stiffness 1e-300": (big.replace("1e300", "1e-300"), ("line 2", "magnitude", "units")),
        "210 000 rows": (header + point * 210_000, ("too many rows",)),
        "real and imaginary, zero": ("frequency_hz,amplitude,stiffness_real,stiffness_imag\n" + "10,1e-4,0,0\n" * 3,
                                     ("line 2", "zero")),
        "both column pairs, disagreeing": (_with_column(measured_text(), "stiffness_real,stiffness_imag", "1,1"),
                                           ("line 2", "disagree", "magnitude")),
        # the CSV of `bushing stiffness` gives both forms, of the same K: read back as it is
        "both column pairs, as bushing stiffness writes them": (_both_forms(), ("fit",)),
        # a blocked transfer stiffness above a wave resonance: Im K < 0 is measured, and valid
        "a negative loss factor above a wave resonance": (measured_text(extra="800,0.008,7950.23,-0.0075\n"),
                                                          ("fit", "diagnose")),
        "a mass-dominated point (Re K < 0)": (measured_text("cartesian", extra="1000,1e-4,-2500000,300000\n"),
                                              ("fit",)),
        **{f"a phase of {p}°": (measured_text("phase", extra=f"1000,1e-4,2500000,{p}\n"), ("fit",))
           for p in (180, -180)},
        "a phase of 180.5°": (measured_text("phase", extra="1000,1e-4,2500000,180.5\n"),
                              ("line 11", "phase_deg", "180")),
        "a phase column without its unit": (measured_text("phase").replace("phase_deg", "phase"),
                                            ("line 1", "phase_deg")),
        "loss factor and phase both, disagreeing": (_with_column(measured_text(), "phase_deg", "7.9"),
                                                    ("line 2", "disagree", "loss_factor")),
    })
    cases = []
    for i, (name, (text, rule)) in enumerate(texts.items()):
        files[path := folder / f"measured_{i}.csv"] = text
        commands = [w for w in rule if w in ("fit", "diagnose")]
        for command in commands or ["fit"]:
            expect = Accepted(command) if commands else Refused(rule)
            cases.append(Case(f"measured: {name}: {command}", (command, str(path), "--design", str(design)), expect))
    return cases


def loop_text(tt, xx, ff) -> str:
    return "time_s,displacement,force\n" + "".join(f"{a:.17g},{b:.17g},{c:.17g}\n" for a, b, c in zip(tt, xx, ff))


def loop_cases(folder: Path, files: dict, design: Path, measured: Path) -> list[Case]:
    t = np.arange(400) / 2000.0  # two periods at 10 Hz, of DESIGN's K at 10 Hz and 0.1 mm
    x, f = 1e-4 * np.sin(20 * np.pi * t), 416.74233465 * np.sin(20 * np.pi * t) + 57.5726568295 * np.cos(20 * np.pi * t)

    texts = {
        "a clean loop": (loop_text(t, x, f), None),
        "a time step of 1e-300 s": (loop_text(t * 1e-300, x, f), ("loop file", "frequency", "within")),
        "a time step of 1e300 s": (loop_text(t * 1e300, x, f), ("loop file", "frequency", "within")),
        "times in ms": (loop_text(t * 1000, x, f), None),  # a 0.01 Hz test: valid
        "displacements x1e300": (loop_text(t, x * 1e300, f), ("amplitude", "at most")),
        "displacements x1e-12": (loop_text(t, x * 1e-12, f), ("amplitude", "at least")),
        "forces x1e300": (loop_text(t, x, f * 1e300), ("force",)),
        "forces zero": (loop_text(t, x, f * 0), ("force",)),
        "a third of a period": (loop_text(t[:67], x[:67], f[:67]), ("loop file", "period")),
        "15 rows": (loop_text(t[:15], x[:15], f[:15]), ("loop file", "16")),
        "a square drive": (loop_text(t, 1e-4 * np.sign(np.sin(20 * np.pi * t + 0.1)), f), ("not a steady sine",)),
        "noise only": (loop_text(t, 1e-4 * np.random.default_rng(0).standard_normal(400), f), ("not a steady sine",)),
        "time backwards": (loop_text(t[::-1], x, f), ("line 3", "time_s", "increase")),
        "a repeated time": (loop_text(np.r_[t[:10], t[9:399]], x, f), ("line 12", "time_s", "increase")),
        "columns swapped": ("force,time_s,displacement\n" + "".join(f"{c!r},{a!r},{b!r}\n" for a, b, c in
                                                                     zip(t.tolist(), x.tolist(), f.tolist())), None),
        "a nan": (loop_text(t, np.r_[x[:5], np.nan, x[6:]], f), ("line 7", "displacement", "not finite")),
        "empty": ("", ("loop file", "empty")),
    }
    cases = []
    for i, (name, (body, rule)) in enumerate(texts.items()):
        files[folder / f"loop_{i}.csv"] = body
        argv = ("fit", str(measured), "--design", str(design), "--loop", str(folder / f"loop_{i}.csv"))
        same = (*argv[:-1], str(folder / "loop_0.csv")) if name == "columns swapped" else None  # the clean loop
        cases.append(Case(f"loop: {name}: fit", argv, Refused(rule) if rule else Accepted("fit", same)))
    return cases


def option_cases(folder: Path, design: Path, measured: Path) -> list[Case]:
    fill = {"d": str(design), "m": str(measured), "f": str(folder)}

    def argv(text: str) -> tuple[str, ...]:
        return tuple(text.format(**fill).split())

    st, grid = "stiffness {d} --freq", "stiffness {d} --freq 1 10 3 --amp"
    lp, fit, td = "loop {d} --freq 1 --amp 1e-3", "fit {m} --design {d}", "--route time-domain"
    stiffness, loop = Accepted("stiffness"), Accepted("loop")
    table = [
        ("the good design", f"{st} 1 100 3 --log --amp 1e-5 1e-4 1e-3", stiffness),
        ("the good design's loop", "loop {d} --freq 10 --amp 1e-4", loop),
        ("no command", "", no("required", "command")), ("unknown command", "fly", no("invalid choice", "fly")),
        ("stiffness without --amp", f"{st} 1 10 3", no("--amp", "required")),
        ("--freq with two numbers", f"{st} 1 10 --amp 1e-4", no("--freq", "expected 3")),
        ("--freq count 0", f"{st} 1 10 0 --amp 1e-4", no("--freq N", "at least 1")),
        ("--freq count 2.5", f"{st} 1 10 2.5 --amp 1e-4", no("--freq N", "whole number")),
        ("--freq count 1e7", f"{st} 1 10 10000000 --amp 1e-4", no("--freq N", "at most")),
        ("--freq reversed", f"{st} 100 1 3 --amp 1e-4", Accepted("stiffness", argv(f"{st} 1 100 3 --amp 1e-4"))),
        ("--freq nan", f"{st} nan 10 3 --amp 1e-4", no("--freq F1", "number")),
        ("--freq 1e400", f"{st} 1 1e400 3 --amp 1e-4", no("--freq F2", "finite")),
        ("--freq 1e300", f"{st} 1 1e300 3 --amp 1e-4", no("--freq F2", "within", "Hz")),
        ("--freq over 1e5", f"{st} 1 100001 3 --amp 1e-4", no("--freq F2", "within", "100000")),
        ("--freq 1e5", f"{st} 1 1e5 3 --amp 1e-4", stiffness),
        ("--freq under 1e-4", f"{st} 5e-5 10 3 --amp 1e-4", no("--freq F1", "within", "0.0001")),
        ("--amp negative", f"{grid} -1e-3", no("--amp", "positive")), ("--amp 0", f"{grid} 0", no("--amp", "positive")),
        ("--amp 1e300 continuum", f"{grid} 1e300 --continuum", no("amplitude", "at most")),
        ("--amp 1e-300", f"{grid} 1e-300", stiffness),
        ("--amp x 2000", f"{st} 1 1000 1000 --amp" + " 1e-4" * 2000, no("amplitudes", "1000000")),
        ("--slices 0", f"{grid} 1e-4 --slices 0", no("--slices", "at least 1")),
        ("--slices 1e9", f"{grid} 1e-4 --slices 1000000000", no("--slices", "at most")),
        ("--slices and --continuum", f"{grid} 1e-4 --slices 3 --continuum", no("--continuum", "--slices", "not allowed")),
        ("--route unknown", f"{grid} 1e-4 --route guess", no("--route", "invalid choice")),
        # the thesis' simulation against the closed form: they agree to its accuracy (2e-6 here)
        ("time domain over 1e5 Hz", f"{st} 1e5 1e5 1 --amp 1e-4 {td}",
         Accepted("stiffness", argv(f"{st} 1e5 1e5 1 --amp 1e-4"), rtol=1e-4)),
        ("time domain, 2000 points", f"{st} 1 100 2000 --amp 1e-4 {td}", no("time-domain", "600")),
        ("time domain, continuum", f"{st} 1 100 100 --amp 1e-4 1e-3 --continuum {td}", no("time-domain", "600")),
        ("1000 slices on a million points", f"{st} 1 100 100000 --amp" + " 1e-4" * 10 + " --slices 1000",
         no("slices", "20000000")),
        ("loop --points 1e14", f"{lp} --points 99999999999999", no("--points", "at most")),
        ("loop --points 1", f"{lp} --points 1", no("--points", "at least 4")),
        ("loop --freq 1e-300", "loop {d} --freq 1e-300 --amp 1e-3", no("--freq", "within", "Hz")),
        ("loop --freq 1e300", "loop {d} --freq 1e300 --amp 1e-3", no("--freq", "within", "Hz")),
        ("loop --freq 1e-4", "loop {d} --freq 1e-4 --amp 1e-3", loop),
        ("card --freq 1e6", "card {d} --freq 1e6 --amp-mm 0.1 --amp-rad 0.01", no("--freq", "within", "100000")),
        ("a missing design file", "loop {f}/nothing.json --freq 1 --amp 1e-3", no("design file", "No such file")),
        ("a folder as design", "loop {f} --freq 1 --amp 1e-3", no("cannot read design file", "directory")),
        ("-o into a missing folder", f"{lp} -o {{f}}/no/x.csv", no("cannot write", "No such file")),
        ("-o /dev/full", f"{lp} -o /dev/full", no("cannot write", "No space")),
        ("fit without --design", "fit {m}", no("--design", "required")),
        ("fit a missing loop", f"{fit} --loop {{f}}/none.csv", no("loop file", "No such file")),
        ("diagnose --baseline nothing", "diagnose {m} --design {d} --baseline=", no("--baseline")),
        ("diagnose --baseline magic", "diagnose {m} --design {d} --baseline elastic,magic", no("--baseline", "magic")),
        ("serve --port 70000", "serve --port 70000", no("--port", "at most 65535")),
        ("serve --port -1", "serve --port -1", no("--port", "positive")),
        ("serve --max-sessions 0", "serve --max-sessions 0", no("--max-sessions", "at least 1")),
        ("serve --max-sessions lots", "serve --max-sessions lots", no("--max-sessions", "whole number")),
        ("an unknown option", f"{lp} --colour red", no("unrecognized arguments", "--colour")),
        ("card without --amp-rad", "card {d} --freq 10 --amp-mm 0.1", no("--amp-rad", "required")),
        ("card at 1e300 mm", "card {d} --freq 10 --amp-mm 1e300 --amp-rad 0.01", no("amplitude", "at most")),
        ("export, an unknown format", "export {d} --format abaqus --freq 1 10 2 --amp 1e-4", no("--format", "invalid")),
        ("export, a million points", "export {d} --format table --freq 1 10 100000 --amp" + " 1e-4" * 11,
         no("export", "100000")),
        ("export at 1e300 m", "export {d} --format nastran --freq 1 10 2 --amp 1e300", no("amplitude", "at most")),
        ("fit on nothing", f"{fit} --fit-on mode=axial,amplitude=7", no("--fit-on", "none of")),
        ("fit on a bad key", f"{fit} --fit-on colour=red", no("--fit-on", "colour")),
        ("fit on a huge selection text", f"{fit} --fit-on mode=" + "+".join(["axial"] * 5000),
         Accepted("fit", argv(f"{fit} --fit-on mode=axial"))),
        ("fit with 25 files", "fit" + " {m}" * 25 + " --design {d}", no("at most 20", "measured files")),
        ("a number with underscores", "loop {d} --freq 1_0 --amp 1e-3", no("--freq", "number")),
    ]
    return [Case(f"options: {name}", argv(text), expect) for name, text, expect in table]


def _put(data: dict, where: tuple, text: str) -> str:
    """``data`` as JSON with the JSON ``text`` at ``where`` (its last key replaced)."""
    data = holder = json.loads(json.dumps(data))
    for key in where[:-1]:
        holder = holder[key]
    holder[where[-1]] = "<<HERE>>"
    return json.dumps(data).replace('"<<HERE>>"', text)


def _tolerance_rule(where: tuple, text: str):
    """docs/files.md's tolerance file: the refusal words of ``text`` at ``where``, or None."""
    value, name = parsed(text), where[-1]
    if value is NOT_JSON:
        return ("tolerance file", "not valid JSON")
    if where[0] == "tolerances":
        key, h = f"tolerances.{name}", finite(value)
        if h is None:
            return (key, "number")
        nominal = {**DESIGN["geometry"], **DESIGN["material"]}[name]
        return (key, "≥ 0") if h < 0 else (key, "outside its range") if h >= nominal else None
    whole = isinstance(value, int) and not isinstance(value, bool)
    return {"samples": None if whole and 10 <= value <= 5000 else ("samples", "whole number"),
            "seed": None if whole and 0 <= value < 2**63 else ("seed", "whole number"),
            "distribution": None if value in ("uniform", "normal") else ("distribution", "uniform"),
            "percentiles": ("percentiles", "0 to 100"),  # none of BAD_NUMBERS is a list of percentiles
            "fit_covariance": None if value is False else ("fit_covariance", "fit report") if value is True
            else ("fit_covariance", "true or false")}[name]


def _target_rule(where: tuple, text: str):
    """docs/files.md's targets file: the refusal words of ``text`` at ``where``, or what the
    report of a valid one holds (a |K| a millionfold off cannot be met)."""
    value = parsed(text)
    if value is NOT_JSON:
        return ("targets file", "not valid JSON")
    key = "targets[0]." + where[-1] if where[0] == "targets" and len(where) == 3 else ".".join(where)
    if where[-1] in ("mode", "targets", "solutions"):  # none of BAD_NUMBERS is a mode, a list, 1–10
        return {"mode": ("targets[0]", "mode"), "targets": ("targets", "1 to 20"),
                "solutions": ("solutions", "whole number")}[where[-1]]
    v = finite(value)
    if v is None:
        return (key, "min") if where[-1] == "magnitude" and isinstance(value, dict) else (key, "number")
    if v <= 0:
        return (key, "positive")
    if where[-1] == "frequency_hz" and not 1e-4 <= v <= 1e5:
        return (key, "100000")
    if where[-1] == "amplitude" and STRAIN_FACTOR * v > 10:
        return ("targets[0]", "amplitude", "at most")
    if where[-1] == "max" and not 2e-3 < v <= 1e3:  # limits.outer_radius: default minimum 2 mm, 1 km
        return ("limits.outer_radius", "min < max")
    off = where[-1] == "magnitude" and not 1e-3 < v / 4e6 < 1e3
    return Accepted("design", words=("cannot be met",) if off else ())


def whatif_cases(folder: Path, files: dict, design: Path) -> list[Case]:
    """Tolerance files for ``stiffness --tolerance`` and targets files for ``design``, broken."""
    d = str(design)
    texts: dict[str, tuple[str, str, object]] = {  # name → (kind, text, refusal words or Accepted)
        "tolerance: as given": ("tolerance", json.dumps(TOLERANCES), Accepted("band")),
        "tolerance: no seed": ("tolerance", json.dumps(TOLERANCES).replace(', "seed": 1', ""), Accepted("band")),
        "targets: as given": ("targets", json.dumps(TARGETS), Accepted("design"))}
    for where in (("tolerances", "shear_modulus"), ("tolerances", "length"), ("samples",), ("seed",),
                  ("distribution",), ("percentiles",), ("fit_covariance",)):
        for bad in BAD_NUMBERS:
            rule = _tolerance_rule(where, bad)
            same = (where == ("seed",)) * ("<<SEED>>",)  # seed 0 is the default: the file without it
            texts[f"tolerance {'.'.join(where)} = {bad[:20]}"] = (
                "tolerance", _put(TOLERANCES, where, bad), rule or Accepted("band", same_as=same or None))
    for where in (("targets", 0, "frequency_hz"), ("targets", 0, "amplitude"), ("targets", 0, "magnitude"),
                  ("limits", "outer_radius", "max"), ("solutions",), ("targets", 0, "mode"), ("targets",)):
        for bad in BAD_NUMBERS:
            texts[f"targets {'.'.join(map(str, where))} = {bad[:20]}"] = (
                "targets", _put(TARGETS, where, bad), _target_rule(tuple(map(str, where)), bad))
    deep = "[" * 100_000 + "]" * 100_000
    texts.update({
        "tolerance: nested 100 000 deep": ("tolerance", deep, ("tolerance file", "larger than")),
        "targets: nested 100 000 deep": ("targets", deep, ("targets file", "nested")),
        "tolerance: 2 MB": ("tolerance", json.dumps({"tolerances": {"length": "1%"}, "pad": "x" * 2_000_000}),
                            ("tolerance file", "larger than")),
        "targets: 2 MB": ("targets", json.dumps({**TARGETS, "pad": "x" * 2_000_000}), ("targets file", "larger than")),
        "tolerance: empty": ("tolerance", "", ("tolerance file", "not valid JSON")),
        "targets: empty": ("targets", "", ("targets file", "not valid JSON")),
        "targets: 5000 targets": ("targets", json.dumps({**TARGETS, "targets": TARGETS["targets"] * 5000}),
                                  ("targets", "1 to 20")),
        "targets: contradicting": ("targets", json.dumps({**TARGETS, "targets": [
            {"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": {"min": 5e6}},
            {"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": {"max": 4e6}}]}),
            Accepted("design", words=("cannot be met", "contradict"))),
        "targets: 1e30 N/m in a millimetre": ("targets", json.dumps({**TARGETS, "targets": [
            {"mode": "torsion", "frequency_hz": 1e5, "amplitude": 1.0, "magnitude": 1e30}],
            "limits": {"length": {"max": 0.001}}}), ("limits.length", "min < max")),
        "targets: a ratio of one mode": ("targets", json.dumps({**TARGETS, "targets": [
            {"ratio": ["axial", "axial"], "frequency_hz": 10, "amplitude": 1e-4, "magnitude": 2}]}),
            ("targets[0].ratio", "two different modes")),
        "targets: every material free": ("targets", json.dumps({**TARGETS, "free_material": {
            n: {"min": 1e-30, "max": 1e30} for n in DESIGN["material"] if n in MATERIAL}}), Accepted("design")),
        "tolerance: 5000 samples on a big grid": ("tolerance", json.dumps({**TOLERANCES, "samples": 5000}),
                                                  ("samples", "20000000")),
        "tolerance: 89 % of b": ("tolerance", json.dumps({"tolerances": {"outer_radius": "89%"}}),
                                 ("tolerances", "b ≤ a")),
    })
    cases = []
    for name, (kind, text, rule) in texts.items():
        files[path := folder / f"whatif_{len(cases)}.json"] = text
        grid = ("--freq", "1", "100", "5000" if "big grid" in name else "5", "--amp", "1e-4", "1e-3")
        argv = ("stiffness", d, *grid, "--tolerance", str(path)) if kind == "tolerance" else ("design", str(path))
        if isinstance(rule, Accepted) and rule.same_as:  # the file without its seed
            rule = Accepted("band", same_as=(*argv[:-1], str(folder / "whatif_1.json")))
        cases.append(Case(f"what-ifs: {name}", argv, rule if isinstance(rule, Accepted) else Refused(rule)))
    bad_bytes = folder / "whatif_latin1.json"
    files[bad_bytes] = '{"tolerances": {"length": "1%"}, "x": "é"}'.encode("latin-1")
    tol = ("stiffness", d, "--freq", "1", "10", "2", "--amp", "1e-4", "--tolerance")
    cases += [Case("what-ifs: a tolerance file not UTF-8", (*tol, str(bad_bytes)), no("tolerance file", "UTF-8")),
              Case("what-ifs: a missing targets file", ("design", str(folder / "none.json")),
                   no("targets file", "No such file")),
              Case("what-ifs: a folder as tolerance file", (*tol, str(folder)), no("tolerance file", "directory"))]
    return cases


def corpus(folder: Path) -> tuple[list[Case], dict[Path, str | bytes]]:
    """Every case, and the files they read (path → text or bytes) to be written into ``folder``."""
    files: dict[Path, str | bytes] = {}
    design, measured = folder / "good_design.json", folder / "good_measured.csv"
    files[design], files[measured] = json.dumps(DESIGN), measured_text()
    cases = (design_cases(folder, files, design) + measured_cases(folder, files, design)
             + loop_cases(folder, files, design, measured) + option_cases(folder, design, measured)
             + whatif_cases(folder, files, design))
    return cases, files
