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
import warnings
from dataclasses import fields
from pathlib import Path

import numpy as np
import pandas as pd

from ..data import STIFFNESS_RANGE, DataError, MeasuredLoop, MeasuredStiffness
from ..parameters import MODES
from ..rules import (
    BAD_CHOICE,
    BAD_SIGNAL,
    BAD_TABLE,
    CONFLICT,
    EMPTY,
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
    read_text,
)

MAX_BYTES = 20 * 1024 * 1024
MAX_ROWS = 200_000
# measured frequencies: from creep-like tests to the acoustic range; beyond, the time base or
# the units are wrong
MEASURED_FREQUENCY_HZ = (1e-4, 1e5)
# a loop's drive must be a steady sine: the RMS departure from the best sine, relative to its
# amplitude, is at most this
LOOP_SINE_DEPARTURE = 0.1

# the column format
STIFFNESS_KEYS = ("frequency_hz", "amplitude")
# the three forms of complex stiffness a file may give; only the last two carry the sign of Re K
STIFFNESS_PAIRS = (("magnitude", "loss_factor"), ("stiffness_real", "stiffness_imag"), ("magnitude", "phase_deg"))
PHASE_DEG = (-180.0, 180.0)  # the phase of K = |K| e^{iφ} in degrees, as test rigs write it
LOOP_COLUMNS = tuple(f.name for f in fields(MeasuredLoop))  # time_s, displacement, force


def _words(what: str, path: bool = True) -> Words:
    """How a ``what`` file's refusals are worded: read from a path, or uploaded (no path)."""
    return Words(too_large=f"{what} file is too large ({{size}} bytes; at most {{limit}})",
                 unreadable=f"cannot read {what} file {{path!r}}: {{reason}}",
                 not_utf8=f"{what} file {{path!r}} is not UTF-8 text" if path else f"{what} file is not UTF-8 text")


def _table(text: str | bytes, what: str) -> pd.DataFrame:
    """A CSV as strings (nothing converted or dropped yet), refusing empty or oversized text."""
    text = decoded(text, MAX_BYTES, _words(what, path=False), DataError).removeprefix("\ufeff")
    if len(text) > MAX_BYTES:
        raise DataError("", f"{what} file is too large (at most {MAX_BYTES} bytes)", TOO_LARGE)
    if not text.strip():
        raise DataError("", f"{what} file is empty", EMPTY)
    try:
        with warnings.catch_warnings():
            # pandas would drop a row's extra fields (or take them for an index): refuse instead
            warnings.simplefilter("error", pd.errors.ParserWarning)
            df = pd.read_csv(io.StringIO(text), dtype=str, keep_default_na=False, skip_blank_lines=False,
                             skipinitialspace=True, index_col=False)
    except pd.errors.ParserWarning:
        raise DataError("", f"{what} file: {_longer_row(text)}", BAD_TABLE) from None
    except pd.errors.ParserError as exc:
        raise DataError("", f"{what} file is not a valid CSV table: {' '.join(str(exc).split())}", BAD_TABLE) from None
    except pd.errors.EmptyDataError:
        raise DataError("", f"{what} file is empty", EMPTY) from None
    df.columns = [str(c).strip() for c in df.columns]
    if len(df) > MAX_ROWS:
        raise DataError("", f"{what} file has too many rows ({len(df)}; at most {MAX_ROWS})", TOO_LARGE)
    return df


def _longer_row(text: str) -> str:
    rows = csv.reader(io.StringIO(text))
    width = len(next(rows))
    for line, row in enumerate(rows, start=2):
        if len(row) > width:
            return f"line {line} has {len(row)} fields, the header {width}"
    return "a row has more fields than the header"


def _rows(df: pd.DataFrame, what: str):
    if len(df) == 0:
        raise DataError("", f"{what} file has a header but no data rows", EMPTY)


def _numbers(df: pd.DataFrame, columns) -> dict[str, np.ndarray]:
    """Convert columns to finite floats (:func:`core.rules.decimal`), refusing the first bad
    cell with its line number."""
    out = {}
    for col in columns:
        values = np.empty(len(df))
        for i, cell in enumerate(df[col].tolist()):
            try:
                values[i] = decimal(cell)
            except RuleError as exc:
                text = str(cell).strip()
                hint = ("; numbers are written like 4.2e6 or 0.0001"
                        if exc.code == NOT_A_NUMBER and any(c.isdigit() for c in text) else "")
                raise DataError(f"line {i + 2}", f"{col} {exc.rule}{hint}", exc.code) from None
        out[col] = values
    return out


def _positive(values: dict, col: str):
    bad = np.flatnonzero(values[col] <= 0)
    if bad.size:
        raise DataError(f"line {bad[0] + 2}", f"{col} must be positive, got {values[col][bad[0]]:g}", NOT_POSITIVE)


def read_stiffness(path) -> MeasuredStiffness:
    """Read a measured-stiffness CSV file of at most :data:`MAX_BYTES` (see
    :func:`parse_stiffness`)."""
    return parse_stiffness(read_text(Path(path), MAX_BYTES, _words("stiffness"), DataError))


def read_loop(path) -> MeasuredLoop:
    """Read a measured-loop CSV file of at most :data:`MAX_BYTES` (see :func:`parse_loop`)."""
    return parse_loop(read_text(Path(path), MAX_BYTES, _words("loop"), DataError))


def parse_stiffness(text: str | bytes) -> MeasuredStiffness:
    """Parse a measured-stiffness CSV: columns frequency_hz, amplitude and one form of the complex
    stiffness (:data:`STIFFNESS_PAIRS`: magnitude + loss_factor, stiffness_real + stiffness_imag
    or magnitude + phase_deg); one row per point. Any finite, non-zero complex K is accepted."""
    df = _table(text, "stiffness")
    cols = set(df.columns)
    pairs = [p for p in STIFFNESS_PAIRS if set(p) <= cols]
    missing = [c for c in STIFFNESS_KEYS if c not in cols]
    if missing or not pairs:
        need = " or ".join(" + ".join(p) for p in STIFFNESS_PAIRS)
        raise DataError("line 1", f"the header must name frequency_hz, amplitude and either {need}"
                        f" (found: {', '.join(df.columns)})", MISSING_KEY)
    if len(pairs) > 1:  # loss_factor beside phase_deg, or both polar and Cartesian: which one holds?
        raise DataError("line 1", f"give one form of the stiffness, not {' and '.join(' + '.join(p) for p in pairs)}",
                        CONFLICT)
    pair = pairs[0]
    extra = cols - set(STIFFNESS_KEYS) - set(pair) - {"mode"}
    if extra:
        raise DataError("line 1", f"unknown column(s) {', '.join(sorted(extra))}", UNKNOWN_KEY)
    _rows(df, "stiffness")
    mode = None
    if "mode" in cols:
        mode = np.array([str(m).strip() for m in df["mode"].tolist()], dtype=object)
        bad = [i for i, m in enumerate(mode) if m not in MODES]
        if bad:
            raise DataError(f"line {bad[0] + 2}", f"mode must be one of {', '.join(MODES)}, got {mode[bad[0]]!r}",
                            BAD_CHOICE)
    v = _numbers(df, (*STIFFNESS_KEYS, *pair))
    _positive(v, "frequency_hz")
    _positive(v, "amplitude")
    lo, hi = MEASURED_FREQUENCY_HZ
    outside = np.flatnonzero((v["frequency_hz"] < lo) | (v["frequency_hz"] > hi))
    if outside.size:
        raise DataError(f"line {outside[0] + 2}", f"frequency_hz must be within {lo:g}–{hi:g} Hz, got "
                        f"{v['frequency_hz'][outside[0]]:g}", OUT_OF_RANGE)
    k = _complex_stiffness(v, pair)
    # any finite complex stiffness is a possible measurement: Im K < 0 (a negative loss factor)
    # is a blocked transfer stiffness above a wave resonance, Re K < 0 a mass-dominated one
    with np.errstate(over="ignore"):
        size = np.abs(k)
    bad = np.flatnonzero(~np.isfinite(size) | (size == 0))
    if bad.size:
        raise DataError(f"line {bad[0] + 2}", "the stiffness is zero or too large for a number", OUT_OF_RANGE)
    lo, hi = STIFFNESS_RANGE
    bad = np.flatnonzero((size < lo) | (size > hi))
    if bad.size:
        raise DataError(f"line {bad[0] + 2}", f"the stiffness magnitude |K| = {size[bad[0]]:.3g} must be within "
                        f"{lo:g}–{hi:g} N/m or N·m/rad; are the units right?", OUT_OF_RANGE)
    return MeasuredStiffness(v["frequency_hz"], v["amplitude"], k, None, mode)


def _complex_stiffness(v: dict[str, np.ndarray], pair: tuple[str, str]) -> np.ndarray:
    """Complex K from one of :data:`STIFFNESS_PAIRS` (columns already finite numbers)."""
    if pair[0] == "stiffness_real":
        return v["stiffness_real"] + 1j * v["stiffness_imag"]
    _positive(v, "magnitude")
    if pair[1] == "loss_factor":
        # η = Im K / Re K with Re K > 0: this form cannot say Re K < 0 (docs/files.md)
        eta = v["loss_factor"]
        return v["magnitude"] * ((1 + 1j * eta) / np.hypot(1.0, eta))
    phase = v["phase_deg"]
    lo, hi = PHASE_DEG
    bad = np.flatnonzero((phase < lo) | (phase > hi))
    if bad.size:
        raise DataError(f"line {bad[0] + 2}", f"phase_deg must be within {lo:g}…{hi:g} degrees, got "
                        f"{phase[bad[0]]:g}", OUT_OF_RANGE)
    return v["magnitude"] * np.exp(1j * np.deg2rad(phase))


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
        raise DataError("line 1", f"the header must be {', '.join(LOOP_COLUMNS)} (found: {', '.join(cols)})", code)
    _rows(df, "loop")
    v = _numbers(df, LOOP_COLUMNS)
    if len(df) < 16:
        raise DataError("", f"loop file has {len(df)} rows; at least 16 are needed for one period", BAD_SIGNAL)
    step = np.diff(v["time_s"])
    bad = np.flatnonzero(step <= 0)
    if bad.size:
        raise DataError(f"line {bad[0] + 3}", f"time_s must increase (after {v['time_s'][bad[0]]:g})", BAD_SIGNAL)
    if np.ptp(v["displacement"]) == 0:
        raise DataError("", "loop file: the displacement never moves", BAD_SIGNAL)
    if np.ptp(v["force"]) == 0:
        raise DataError("", "loop file: the force never moves", BAD_SIGNAL)
    loop = MeasuredLoop(v["time_s"], v["displacement"], v["force"])
    _check_harmonic(loop)
    return loop


def _check_harmonic(loop: MeasuredLoop) -> None:
    """A loop is a steady harmonic test: a frequency in :data:`MEASURED_FREQUENCY_HZ`, at least
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
    lo, hi = MEASURED_FREQUENCY_HZ
    if not (math.isfinite(f) and lo <= f <= hi):
        found = f"{f:.3g} Hz" if math.isfinite(f) and f > 0 else "none found"
        raise DataError("", f"loop file: its frequency ({found}, from a time step of {dt:.3g} s) must be within "
                        f"{lo:g}–{hi:g} Hz; is time_s in seconds?", OUT_OF_RANGE)
    if f * (span + dt) < 0.99:
        raise DataError("", f"loop file: it holds {f * (span + dt):.2f} of a period at {f:.3g} Hz; at least one "
                        "whole period is needed", BAD_SIGNAL)
    if not departure <= LOOP_SINE_DEPARTURE:
        raise DataError("", f"loop file: the displacement is not a steady sine (its RMS departure from the best "
                        f"sine is {departure:.0%} of the amplitude; at most {LOOP_SINE_DEPARTURE:.0%})", BAD_SIGNAL)
