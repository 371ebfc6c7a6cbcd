"""The measured-data files (docs/files.md): dynamic-stiffness tables and hysteresis loops, read
strictly into :class:`core.data.MeasuredStiffness` and :class:`core.data.MeasuredLoop`.

Every refusal is a :class:`core.data.DataError` naming the line (the header is line 1) and the
reason, with its rule's code (:mod:`core.rules`); no row is ever dropped silently. All numbers
are SI: Hz, m or rad, N/m or N·m/rad, s, N or N·m.
"""

from __future__ import annotations

import csv
import io
import math
from collections import Counter
from dataclasses import fields
from pathlib import Path

import numpy as np

from ..data import STIFFNESS_RANGE, DataError, MeasuredLoop, MeasuredStiffness
from ..numbers import format_number, format_outside
from ..parameters import FREQUENCY_HZ, MODES
from ..response import loss_factor
from ..rules import (
    BAD_CHOICE,
    BAD_SIGNAL,
    BAD_TABLE,
    CONFLICT,
    DUPLICATE_KEY,
    EMPTY,
    EXCERPT_CHARS,
    MISSING_KEY,
    NOT_A_NUMBER,
    NOT_POSITIVE,
    OUT_OF_RANGE,
    TOO_LARGE,
    UNKNOWN_KEY,
    RuleError,
    Words,
    decimal,
    decoded,
    excerpt,
    read_text,
)

MAX_BYTES = 20 * 1024 * 1024
MAX_ROWS = 200_000
# a loop's drive must be a steady sine: the RMS departure from the best sine, relative to its
# amplitude, is at most this
LOOP_SINE_DEPARTURE = 0.1

# the column format
STIFFNESS_KEYS = ("frequency_hz", "amplitude")
# the three forms of complex stiffness a file may give; only the last two carry the sign of Re K
STIFFNESS_PAIRS = (("magnitude", "loss_factor"), ("stiffness_real", "stiffness_imag"), ("magnitude", "phase_deg"))
# several forms in one file: K is read from the one that says most (the Cartesian, then the
# phase: both carry the sign of Re K), the others must agree with it within FORMS_AGREE
# (relative in |K| and K, absolute and relative in the loss factor). ``bushing stiffness`` writes
# 12 significant digits, each value within 5e-13 of its own: forms written with 10 digits or
# more agree to about 1e-10, while an edited or shifted column differs by far more
FORM_ORDER = (STIFFNESS_PAIRS[1], STIFFNESS_PAIRS[2], STIFFNESS_PAIRS[0])
FORMS_AGREE = 1e-9
PHASE_DEG = (-180.0, 180.0)  # the phase of K = |K| e^{iφ} in degrees, as test rigs write it
LOOP_COLUMNS = tuple(f.name for f in fields(MeasuredLoop))  # time_s, displacement, force


def _words(what: str, path: bool = True) -> Words:
    """How a ``what`` file's refusals are worded: read from a path, or uploaded (no path)."""
    return Words(too_large=f"{what} file is too large ({{size}} bytes; at most {{limit}})",
                 unreadable=f"cannot read {what} file {{path!r}}: {{reason}}",
                 not_utf8=f"{what} file {{path!r}} is not UTF-8 text" if path else f"{what} file is not UTF-8 text")


class _Table:
    """A CSV read as text, nothing converted or dropped yet: the header's column names and the
    data rows (each as long as the header), with the line each row starts on (the header is
    line 1)."""

    def __init__(self, columns: list[str], rows: list[list[str]], lines: list[int]):
        self.columns, self.rows, self.lines = columns, rows, lines

    def __len__(self):
        return len(self.rows)

    def cells(self, column: str) -> list[str]:
        j = self.columns.index(column)
        return [row[j] for row in self.rows]

    def line(self, i: int) -> int:
        return self.lines[i]


def _blank(row: list[str]) -> bool:
    """A line holding only blanks (no separator): no data."""
    return len(row) <= 1 and not "".join(row).strip()


def _table(text: str | bytes, what: str) -> _Table:
    """A CSV as strings, refusing empty or oversized text, a field the CSV rules cannot read
    (an open quote, a field over the csv module's limit), a row longer than the header and a
    column named twice. Blank lines at the end carry nothing and are left out; every other row
    is kept, a short one filled with empty cells (refused where its values are read)."""
    text = decoded(text, MAX_BYTES, _words(what, path=False), DataError).removeprefix("\ufeff")
    if len(text) > MAX_BYTES:
        raise DataError("", f"{what} file is too large (at most {MAX_BYTES} bytes)", TOO_LARGE)
    if not text.strip():
        raise DataError("", f"{what} file is empty", EMPTY)
    reader = csv.reader(io.StringIO(text, newline=""), skipinitialspace=True, strict=True)
    rows, lines, line, run = [], [], 1, 0  # run: the blank lines since the last row of data
    try:
        for row in reader:
            rows.append(row)
            lines.append(line)
            line = reader.line_num + 1
            run = run + 1 if _blank(row) else 0
            if len(rows) - run > MAX_ROWS + 1 or run > MAX_ROWS:
                raise DataError("", f"{what} file has too many rows (more than {MAX_ROWS})", TOO_LARGE)
    except csv.Error as exc:
        limit = csv.field_size_limit()
        said = f"a field holds more than {limit} characters" if f"({limit})" in str(exc) else str(exc)
        raise DataError("", f"{what} file is not a valid CSV table: line {line}: {said}", BAD_TABLE) from None
    del rows[len(rows) - run:], lines[len(lines) - run:]  # blank lines at the end: no data
    columns = [c.strip() for c in rows[0]]
    if not any(columns):
        raise DataError("line 1", "is blank: the header row (the column names) comes first", MISSING_KEY)
    repeated = [c for c, n in Counter(columns).items() if n > 1]
    if repeated:
        raise DataError("line 1", f"the column {excerpt(repeated[0])!r} is given twice; name each column once",
                        DUPLICATE_KEY)
    width = len(columns)
    for row, at in zip(rows[1:], lines[1:]):
        if len(row) > width:
            raise DataError("", f"{what} file is not a valid CSV table: line {at} has {len(row)} fields, "
                            f"the header {width}", BAD_TABLE)
        row.extend([""] * (width - len(row)))
    return _Table(columns, rows[1:], lines[1:])


def _columns(names) -> str:
    """A file's column names as a message quotes them, each in quotes (a blank one shows) and
    all within a few excerpts' length (:func:`core.rules.excerpt`)."""
    return excerpt(", ".join(repr(excerpt(n)) for n in names), 2 * EXCERPT_CHARS)


def _rows(df: _Table, what: str):
    if len(df) == 0:
        raise DataError("", f"{what} file has a header but no data rows", EMPTY)


def _numbers(df: _Table, columns) -> dict[str, np.ndarray]:
    """Convert columns to finite floats (:func:`core.rules.decimal`), refusing the first bad
    cell with its line number."""
    out = {}
    for col in columns:
        values = np.empty(len(df))
        for i, cell in enumerate(df.cells(col)):
            try:
                values[i] = decimal(cell)
            except RuleError as exc:
                text = str(cell).strip()
                hint = ("; numbers are written like 4.2e6 or 0.0001"
                        if exc.code == NOT_A_NUMBER and any(c.isdigit() for c in text) else "")
                raise DataError(f"line {df.line(i)}", f"{col} {exc.rule}{hint}", exc.code) from None
        out[col] = values
    return out


def _positive(df: _Table, values: dict, col: str):
    bad = np.flatnonzero(values[col] <= 0)
    if bad.size:
        raise DataError(f"line {df.line(bad[0])}", f"{col} must be positive, got {values[col][bad[0]]:g}",
                        NOT_POSITIVE)


def read_stiffness(path) -> MeasuredStiffness:
    """Read a measured-stiffness CSV file of at most :data:`MAX_BYTES` (see
    :func:`parse_stiffness`); a refusal of its content names the file, as a design file's does."""
    path = Path(path)
    return _named(path, parse_stiffness, read_text(path, MAX_BYTES, _words("stiffness"), DataError))


def read_loop(path) -> MeasuredLoop:
    """Read a measured-loop CSV file of at most :data:`MAX_BYTES` (see :func:`parse_loop`); a
    refusal of its content names the file."""
    path = Path(path)
    return _named(path, parse_loop, read_text(path, MAX_BYTES, _words("loop"), DataError))


def _named(path: Path, parse, text: str):
    """``parse(text)``, its refusal naming the file: ``line 8: … (in a.csv)``, as a design
    file's refusals say ``(in NAME.json)``; several files given together are told apart."""
    try:
        return parse(text)
    except DataError as exc:
        raise DataError(exc.key, f"{exc.rule} (in {path.name})", exc.code) from None


def parse_stiffness(text: str | bytes) -> MeasuredStiffness:
    """Parse a measured-stiffness CSV: columns frequency_hz, amplitude and one or more forms of
    the complex stiffness (:data:`STIFFNESS_PAIRS`: magnitude + loss_factor, stiffness_real +
    stiffness_imag or magnitude + phase_deg); one row per point. Any finite, non-zero complex K
    is accepted. Forms given together (the CSV of ``bushing stiffness`` gives the first two)
    must agree within :data:`FORMS_AGREE`; K is read from the one that says most (the
    Cartesian, then the phase, then the loss factor: only the first two carry the sign of
    Re K)."""
    df = _table(text, "stiffness")
    cols = set(df.columns)
    pairs = sorted((p for p in STIFFNESS_PAIRS if set(p) <= cols), key=FORM_ORDER.index)
    missing = [c for c in STIFFNESS_KEYS if c not in cols]
    if missing or not pairs:
        need = " or ".join(" + ".join(p) for p in STIFFNESS_PAIRS)
        raise DataError("line 1", f"the header must name frequency_hz, amplitude and either {need}"
                        f" (found: {_columns(df.columns)})", MISSING_KEY)
    given = {c for p in pairs for c in p}
    extra = cols - set(STIFFNESS_KEYS) - given - {"mode"}
    if extra:
        raise DataError("line 1", f"unknown column(s) {_columns(sorted(extra))}", UNKNOWN_KEY)
    _rows(df, "stiffness")
    mode = None
    if "mode" in cols:
        mode = np.array([str(m).strip() for m in df.cells("mode")], dtype=object)
        bad = [i for i, m in enumerate(mode) if m not in MODES]
        if bad:
            raise DataError(f"line {df.line(bad[0])}", f"mode must be one of {', '.join(MODES)}, got "
                            f"{excerpt(mode[bad[0]])!r}", BAD_CHOICE)
    v = _numbers(df, (*STIFFNESS_KEYS, *sorted(given, key=list(df.columns).index)))
    _positive(df, v, "frequency_hz")
    _positive(df, v, "amplitude")
    lo, hi = FREQUENCY_HZ
    outside = np.flatnonzero((v["frequency_hz"] < lo) | (v["frequency_hz"] > hi))
    if outside.size:
        raise DataError(f"line {df.line(outside[0])}", f"frequency_hz must be within {lo:g}–{hi:g} Hz, got "
                        f"{format_outside(v['frequency_hz'][outside[0]], lo, hi)}", OUT_OF_RANGE)
    k = _complex_stiffness(df, v, pairs[0])
    # any finite complex stiffness is a possible measurement: Im K < 0 (a negative loss factor)
    # is a blocked transfer stiffness above a wave resonance, Re K < 0 a mass-dominated one
    with np.errstate(over="ignore"):
        size = np.abs(k)
    bad = np.flatnonzero(~np.isfinite(size) | (size == 0))
    if bad.size:
        raise DataError(f"line {df.line(bad[0])}", "the stiffness is zero or too large for a number", OUT_OF_RANGE)
    lo, hi = STIFFNESS_RANGE
    bad = np.flatnonzero((size < lo) | (size > hi))
    if bad.size:
        raise DataError(f"line {df.line(bad[0])}", f"the stiffness magnitude |K| = "
                        f"{format_outside(size[bad[0]], lo, hi)} must be within {lo:g}–{hi:g} N/m or N·m/rad; "
                        "are the units right?", OUT_OF_RANGE)
    for other in pairs[1:]:
        _agree(df, v, k, pairs[0], other)
    return MeasuredStiffness(v["frequency_hz"], v["amplitude"], k, None, mode)


def _complex_stiffness(df: _Table, v: dict[str, np.ndarray], pair: tuple[str, str]) -> np.ndarray:
    """Complex K from one of :data:`STIFFNESS_PAIRS` (columns already finite numbers)."""
    if pair[0] == "stiffness_real":
        return v["stiffness_real"] + 1j * v["stiffness_imag"]
    _positive(df, v, "magnitude")
    if pair[1] == "loss_factor":
        # η = Im K / Re K with Re K > 0: this form cannot say Re K < 0 (docs/files.md)
        eta = v["loss_factor"]
        return v["magnitude"] * ((1 + 1j * eta) / np.hypot(1.0, eta))
    phase = v["phase_deg"]
    lo, hi = PHASE_DEG
    bad = np.flatnonzero((phase < lo) | (phase > hi))
    if bad.size:
        raise DataError(f"line {df.line(bad[0])}", f"phase_deg must be within {lo:g}…{hi:g} degrees, got "
                        f"{format_outside(phase[bad[0]], lo, hi)}", OUT_OF_RANGE)
    return v["magnitude"] * np.exp(1j * np.deg2rad(phase))


def _agree(df: _Table, v: dict[str, np.ndarray], k: np.ndarray, base: tuple[str, str], other: tuple[str, str]):
    """A second form of the stiffness, ``other``, says the K read from ``base``: its |K| within
    :data:`FORMS_AGREE` relative, its loss factor within that absolute and relative (the
    loss-factor form, whatever the sign of Re K, as ``bushing stiffness`` writes it), or its
    K within that relative (the phase form); else the first row that disagrees is refused."""
    cartesian = base[0] == "stiffness_real"
    said = "|stiffness_real + i stiffness_imag|" if cartesian else "magnitude"
    checks = [("magnitude", np.abs(k), said, FORMS_AGREE * np.abs(k))]
    if other[1] == "loss_factor":
        ratio = "stiffness_imag/stiffness_real" if cartesian else "tan(phase_deg)"
        eta = loss_factor(k)
        checks.append(("loss_factor", eta, ratio, FORMS_AGREE * (1.0 + np.abs(eta))))
    else:  # the phase form beside the Cartesian: the angle of K
        checks.append(("phase_deg", np.rad2deg(np.angle(k)), "the angle of stiffness_real + i stiffness_imag",
                       np.rad2deg(FORMS_AGREE)))
    for col, value, words, allowed in checks:
        with np.errstate(invalid="ignore"):
            off = ~(np.abs(v[col] - value) <= allowed)
        if col == "phase_deg":  # −180 and 180 are one angle
            off &= ~(np.abs(np.abs(v[col] - value) - 360.0) <= allowed)
        bad = np.flatnonzero(off)
        if bad.size:
            i = bad[0]
            raise DataError(f"line {df.line(i)}", f"the two forms of the stiffness disagree: {col} is "
                            f"{v[col][i]:.12g} but {words} is {value[i]:.12g} (they must agree within "
                            f"{FORMS_AGREE:g}); give one form, or both of the same K", CONFLICT)


def combined(parts: list[MeasuredStiffness], default_mode: str) -> MeasuredStiffness:
    """Several measured files as one: rows of a file without a `mode` column are in
    ``default_mode`` (the design's) when another file names its modes."""
    if len(parts) == 1:
        return parts[0]
    mode = None
    if any(p.mode is not None for p in parts):
        mode = np.concatenate([p.modes(default_mode) for p in parts])
    return MeasuredStiffness(*(np.concatenate([getattr(p, k) for p in parts])
                               for k in ("frequency_hz", "amplitude", "stiffness")), None, mode)


def parse_loop(text: str | bytes) -> MeasuredLoop:
    """Parse a measured-loop CSV: columns time_s, displacement, force, time strictly
    increasing."""
    df = _table(text, "loop")
    cols = list(df.columns)
    if sorted(cols) != sorted(LOOP_COLUMNS):
        code = UNKNOWN_KEY if set(cols) - set(LOOP_COLUMNS) else MISSING_KEY
        raise DataError("line 1", f"the header must be {', '.join(LOOP_COLUMNS)} (found: {_columns(cols)})", code)
    _rows(df, "loop")
    v = _numbers(df, LOOP_COLUMNS)
    if len(df) < 16:
        raise DataError("", f"loop file has {len(df)} rows; at least 16 are needed for one period", BAD_SIGNAL)
    step = np.diff(v["time_s"])
    bad = np.flatnonzero(step <= 0)
    if bad.size:
        raise DataError(f"line {df.line(bad[0] + 1)}", f"time_s must increase (after {v['time_s'][bad[0]]:g})", BAD_SIGNAL)
    if np.ptp(v["displacement"]) == 0:
        raise DataError("", "loop file: the displacement never moves", BAD_SIGNAL)
    if np.ptp(v["force"]) == 0:
        raise DataError("", "loop file: the force never moves", BAD_SIGNAL)
    loop = MeasuredLoop(v["time_s"], v["displacement"], v["force"])
    _check_harmonic(loop)
    return loop


def _check_harmonic(loop: MeasuredLoop) -> None:
    """A loop is a steady harmonic test: a frequency in :data:`core.parameters.FREQUENCY_HZ`, at least
    one period recorded, a drive close to a sine."""
    t = loop.time_s
    span = t[-1] - t[0]
    dt = float(np.median(np.diff(t)))
    if not (math.isfinite(span) and span > 0 and math.isfinite(dt) and dt > 0):
        raise DataError("", "loop file: time_s does not span a usable interval", BAD_SIGNAL)
    with np.errstate(all="ignore"):
        f, amp, phase = loop.harmonic()
        x = loop.displacement / amp if amp > 0 else loop.displacement * math.inf
        departure = float(np.sqrt(np.mean((x - np.mean(x) - np.sin(phase)) ** 2)))
    lo, hi = FREQUENCY_HZ
    if not (math.isfinite(f) and lo <= f <= hi):
        found = f"{format_outside(f, lo, hi, 3)} Hz" if math.isfinite(f) and f > 0 else "none found"
        raise DataError("", f"loop file: its frequency ({found}, from a time step of {dt:.3g} s) must be within "
                        f"{lo:g}–{hi:g} Hz; {_time_unit(f)}", OUT_OF_RANGE)
    if f * (span + dt) < 0.99:
        raise DataError("", f"loop file: it holds {f * (span + dt):.2f} of a period at {f:.3g} Hz; at least one "
                        "whole period is needed", BAD_SIGNAL)
    if not departure <= LOOP_SINE_DEPARTURE:
        raise DataError("", f"loop file: the displacement is not a steady sine (its RMS departure from the best "
                        f"sine is {departure:.0%} of the amplitude; at most {LOOP_SINE_DEPARTURE:.0%})", BAD_SIGNAL)


def _time_unit(frequency_hz: float) -> str:
    """The likely cause of a loop's frequency outside :data:`core.parameters.FREQUENCY_HZ`: a time base
    in ms or µs read as seconds, when that unit puts the frequency inside."""
    lo, hi = FREQUENCY_HZ
    for unit, scale in (("milliseconds", 1e3), ("microseconds", 1e6)):
        if math.isfinite(frequency_hz) and lo <= frequency_hz * scale <= hi:
            return (f"time_s looks like {unit}: in seconds it would be a test at "
                    f"{format_number(frequency_hz * scale, 3)} Hz")
    return "is time_s in seconds?"
