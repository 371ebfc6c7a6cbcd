"""Measured data (docs/files.md): dynamic-stiffness tables and hysteresis loops, read strictly.

Every refusal names the line (the header is line 1) and the reason; no row is ever dropped
silently. All numbers are SI: Hz, m or rad, N/m or N·m/rad, s, N or N·m.
"""

from __future__ import annotations

import csv
import functools
import io
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .design import MODES

MAX_BYTES = 20 * 1024 * 1024
MAX_ROWS = 200_000
# fits and the diagnosis work on at most about this many stiffness points (denser data binned)
# and loop samples (denser loops folded onto one period's phase bins)
MAX_FIT_POINTS = 2000
MAX_FIT_SAMPLES = 2000
# measured frequencies: from creep-like tests to the acoustic range; beyond, the time base or
# the units are wrong
MEASURED_FREQUENCY_HZ = (1e-4, 1e5)
# measured |K| (N/m or N·m/rad) and a loop's force per displacement: from a thread to a bridge
# bearing; beyond, the units are wrong (and a fit's relative misfit loses every digit)
STIFFNESS_RANGE = (1e-6, 1e15)
# a loop's drive must be a steady sine: the RMS departure from the best sine, relative to its
# amplitude, is at most this
LOOP_SINE_DEPARTURE = 0.1
# a number in a data file: plain ASCII decimal notation
DECIMAL = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)

STIFFNESS_KEYS = ("frequency_hz", "amplitude")
# the three forms of complex stiffness a file may give; only the last two carry the sign of Re K
STIFFNESS_PAIRS = (("magnitude", "loss_factor"), ("stiffness_real", "stiffness_imag"), ("magnitude", "phase_deg"))
PHASE_DEG = (-180.0, 180.0)  # the phase of K = |K| e^{iφ} in degrees, as test rigs write it
LOOP_COLUMNS = ("time_s", "displacement", "force")


class DataError(ValueError):
    """A measured-data file breaks a rule; the message names the line and the reason."""


def magnitude_residual_pct(k_model, k_data) -> np.ndarray:
    """|K| of a model against data, in % of the data's: 100 (|K_model| / |K_data| − 1)."""
    return 100.0 * (np.abs(k_model) / np.abs(k_data) - 1.0)


def loss_factor(k) -> np.ndarray:
    """η = Im K / Re K of complex stiffness (docs/model.md), with its sign: negative where
    Im K < 0 or Re K < 0; ±inf where Re K = 0 exactly (no warning)."""
    k = np.asarray(k)
    with np.errstate(divide="ignore", invalid="ignore"):
        return k.imag / k.real


class ComplexStiffness:
    """Magnitude and loss factor of a ``stiffness`` attribute holding complex K."""

    stiffness: np.ndarray

    @property
    def magnitude(self) -> np.ndarray:
        return np.abs(self.stiffness)

    @property
    def loss_factor(self) -> np.ndarray:
        return loss_factor(self.stiffness)


@dataclass(frozen=True, eq=False)
class MeasuredStiffness(ComplexStiffness):
    """Measured complex dynamic stiffness, one entry per (frequency, amplitude) point.

    ``count`` is set on binned data (:meth:`binned`): how many measured points each entry is the
    mean of. A fit weighs an entry's residual by √count, so that its noise is that of one
    measured point and the sums of squares are those of all the points."""

    frequency_hz: np.ndarray
    amplitude: np.ndarray
    stiffness: np.ndarray  # complex
    count: np.ndarray | None = None
    mode: np.ndarray | None = None  # per row (the file's `mode` column); None: the design's mode

    def __len__(self):
        return self.frequency_hz.size

    @property
    def weight(self) -> np.ndarray | float:
        """√count per entry (1 for measured points)."""
        return 1.0 if self.count is None else np.sqrt(self.count)

    @property
    def measured_points(self) -> int:
        return len(self) if self.count is None else int(np.sum(self.count))

    def select(self, mask) -> MeasuredStiffness:
        mask = np.asarray(mask)
        count = None if self.count is None else self.count[mask]
        mode = None if self.mode is None else self.mode[mask]
        return MeasuredStiffness(self.frequency_hz[mask], self.amplitude[mask], self.stiffness[mask], count, mode)

    def of_mode(self, mode: str) -> MeasuredStiffness | None:
        """The rows in ``mode``, as data of one direction (no mode column); all rows of data
        without a mode column; None if no row is in ``mode``."""
        if self.mode is None:
            return self
        rows = self.mode == mode
        if not rows.any():
            return None
        one = self.select(rows)
        return MeasuredStiffness(one.frequency_hz, one.amplitude, one.stiffness, one.count)

    def modes(self, default: str) -> np.ndarray:
        """The mode of every row: the file's, or ``default`` (the design's) without a column."""
        return np.full(len(self), default, dtype=object) if self.mode is None else self.mode

    def binned(self, max_points: int = MAX_FIT_POINTS) -> MeasuredStiffness:
        """Dense data reduced to about ``max_points`` entries, each the mean complex stiffness of
        neighbouring points at their geometric-mean frequency and amplitude (``count`` set);
        the data themselves if they are not larger. Points are grouped by amplitude (each
        distinct amplitude, or with many of them bands of equal count in amplitude), and within
        a group into runs of equal count along the frequency, each group's share of
        ``max_points`` in proportion to its size: a sweep keeps its shape at every amplitude."""
        n = len(self)
        if n <= max_points:
            return self
        levels, group = np.unique(self.amplitude, return_inverse=True)
        exact = levels.size <= max_points // 20
        if not exact:  # scattered amplitudes: bands of equal count
            bands = max(1, int(math.sqrt(max_points)))
            group = (np.argsort(np.argsort(self.amplitude, kind="stable"), kind="stable") * bands) // n
        if self.mode is not None:  # never a bin across two modes
            _, mode_index = np.unique(self.mode.astype(str), return_inverse=True)
            group = group + (int(group.max()) + 1) * mode_index
        groups, sizes = np.unique(group, return_counts=True)
        share = max_points * sizes / n  # each group's bins: largest remainders, at least one
        shares = np.maximum(np.floor(share).astype(np.int64), 1)
        spare = max_points - int(shares.sum())
        if spare > 0:
            shares[np.argsort(-(share - np.floor(share)), kind="stable")[:spare]] += 1
        label = np.empty(n, dtype=np.int64)
        offset = 0
        for g, bins in zip(groups, shares):
            members = np.flatnonzero(group == g)
            order = members[np.argsort(self.frequency_hz[members], kind="stable")]
            label[order] = offset + (np.arange(members.size) * bins) // members.size
            offset += bins
        _, label = np.unique(label, return_inverse=True)
        count = np.bincount(label).astype(float)

        def mean(values):
            return np.bincount(label, weights=values) / count

        stiffness = mean(self.stiffness.real) + 1j * mean(self.stiffness.imag)
        if exact:  # each bin holds one amplitude: keep it exactly (runs along frequency stay runs)
            amplitude = np.zeros(count.size)
            amplitude[label] = self.amplitude
        else:
            amplitude = np.exp(mean(np.log(self.amplitude)))
        mode = None
        if self.mode is not None:
            mode = np.empty(count.size, dtype=object)
            mode[label] = self.mode
        return MeasuredStiffness(np.exp(mean(np.log(self.frequency_hz))), amplitude, stiffness, count, mode)

    def amplitudes(self) -> np.ndarray:
        """The distinct amplitudes, the most frequent first (ties in increasing order)."""
        values, counts = np.unique(self.amplitude, return_counts=True)
        return values[np.argsort(-counts, kind="stable")]

    def to_csv(self, path: str | Path | None = None, polar: bool = True) -> str:
        cols = {} if self.mode is None else {"mode": list(self.mode)}
        cols.update({"frequency_hz": self.frequency_hz, "amplitude": self.amplitude})
        if polar:
            cols.update(magnitude=self.magnitude, loss_factor=self.loss_factor)
        else:
            cols.update(stiffness_real=self.stiffness.real, stiffness_imag=self.stiffness.imag)
        return _written(csv_text(cols, FILE_NUMBER_FORMAT), path)


# numbers in the measured-data files this package writes (examples, demos, synthetic data)
FILE_NUMBER_FORMAT = "{:.10g}"


def csv_text(columns: dict[str, np.ndarray], number_format: str = "{:.12g}") -> str:
    """CSV text with a header row of the column names and one row per index (SI numbers)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in zip(*columns.values()):
        writer.writerow([v if isinstance(v, str) else number_format.format(v) for v in row])
    return buf.getvalue()


def _written(text: str, path: str | Path | None) -> str:
    if path is not None:
        Path(path).write_text(text, encoding="utf-8")
    return text


@dataclass(frozen=True, eq=False)
class MeasuredLoop:
    """A measured steady harmonic test: displacement (m or rad) and force (N or N·m) in time."""

    time_s: np.ndarray
    displacement: np.ndarray
    force: np.ndarray

    def to_csv(self, path: str | Path | None = None) -> str:
        """The loop file of docs/files.md: time_s, displacement, force."""
        cols = {"time_s": self.time_s, "displacement": self.displacement, "force": self.force}
        return _written(csv_text(cols, FILE_NUMBER_FORMAT), path)

    def check_force(self) -> None:
        """The force's scale (checked after the amplitude's, whose rule names a wrong unit more
        plainly): its peak over the displacement's within :data:`STIFFNESS_RANGE`."""
        force = self.force - np.mean(self.force)
        ratio = float(np.max(np.abs(force))) / self.harmonic()[1]
        lo, hi = STIFFNESS_RANGE
        if not lo <= ratio <= hi:
            raise DataError(f"loop file: the peak force per peak displacement ({ratio:.3g} N/m or N·m/rad) "
                            f"must be within {lo:g}–{hi:g}; are the units of force and displacement right?")

    def harmonic(self):
        """Frequency (Hz), peak amplitude and the phase θ(t) of the drive x ≈ x̂ sin θ, from a
        least-squares sine fit (frequency refined around the spectral peak); computed once."""
        return self._harmonic

    @functools.cached_property
    def _harmonic(self):
        t, x = self.time_s, self.displacement - np.mean(self.displacement)
        scale = float(np.max(np.abs(x))) or 1.0  # fitted in units of its peak: no overflow
        x = x / scale
        dt = np.median(np.diff(t))
        spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
        freqs = np.fft.rfftfreq(x.size, dt)
        f0 = freqs[1 + int(np.argmax(spec[1:]))]

        def fit(f):
            basis = np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t), np.ones_like(t)])
            coef, *_ = np.linalg.lstsq(basis, x, rcond=None)
            return coef, float(np.sum((basis @ coef - x) ** 2))

        from scipy.optimize import minimize_scalar

        span = max(freqs[1], 1e-12)
        best = minimize_scalar(lambda f: fit(f)[1], bounds=(f0 - span, f0 + span), method="bounded",
                               options={"xatol": span * 1e-9})
        f = float(best.x)
        (a, b, _), _ = fit(f)
        amp = math.hypot(a, b) * scale
        phase0 = math.atan2(b, a)  # x = amp sin(ωt + phase0)
        return f, amp, 2 * np.pi * f * t + phase0


def _file_text(path, what: str) -> str:
    path = Path(path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise DataError(f"cannot read {what} file {str(path)!r}: {exc.strerror}") from None
    if size > MAX_BYTES:
        raise DataError(f"{what} file is too large ({size} bytes; at most {MAX_BYTES})")
    try:
        return path.read_text(encoding="utf-8-sig")  # a byte-order mark (Excel) is not data
    except UnicodeDecodeError:
        raise DataError(f"{what} file {str(path)!r} is not UTF-8 text") from None
    except OSError as exc:
        raise DataError(f"cannot read {what} file {str(path)!r}: {exc.strerror}") from None


def _table(text: str | bytes, what: str) -> pd.DataFrame:
    """A CSV as strings (nothing converted or dropped yet), refusing empty or oversized text."""
    if isinstance(text, bytes):
        if len(text) > MAX_BYTES:
            raise DataError(f"{what} file is too large ({len(text)} bytes; at most {MAX_BYTES})")
        try:
            text = text.decode("utf-8-sig")
        except UnicodeDecodeError:
            raise DataError(f"{what} file is not UTF-8 text") from None
    text = text.removeprefix("\ufeff")
    if len(text) > MAX_BYTES:
        raise DataError(f"{what} file is too large (at most {MAX_BYTES} bytes)")
    if not text.strip():
        raise DataError(f"{what} file is empty")
    try:
        with warnings.catch_warnings():
            # pandas would drop a row's extra fields (or take them for an index): refuse instead
            warnings.simplefilter("error", pd.errors.ParserWarning)
            df = pd.read_csv(io.StringIO(text), dtype=str, keep_default_na=False, skip_blank_lines=False,
                             skipinitialspace=True, index_col=False)
    except pd.errors.ParserWarning:
        raise DataError(f"{what} file: {_longer_row(text)}") from None
    except pd.errors.ParserError as exc:
        raise DataError(f"{what} file is not a valid CSV table: {' '.join(str(exc).split())}") from None
    except pd.errors.EmptyDataError:
        raise DataError(f"{what} file is empty") from None
    df.columns = [str(c).strip() for c in df.columns]
    if len(df) > MAX_ROWS:
        raise DataError(f"{what} file has too many rows ({len(df)}; at most {MAX_ROWS})")
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
        raise DataError(f"{what} file has a header but no data rows")


def _numbers(df: pd.DataFrame, columns, what: str) -> dict[str, np.ndarray]:
    """Convert columns to finite floats, refusing the first bad cell with its line number."""
    out = {}
    for col in columns:
        values = np.empty(len(df))
        for i, cell in enumerate(df[col].tolist()):
            line = i + 2
            text = str(cell).strip()
            if text == "":
                raise DataError(f"line {line}: {col} is missing")
            if text.lower().lstrip("+-") in ("nan", "inf", "infinity"):
                raise DataError(f"line {line}: {col} is not finite ({text!r})")
            if not DECIMAL.fullmatch(text):  # no 1_000, no non-ASCII digits, no hex: what float() forgives
                hint = "; numbers are written like 4.2e6 or 0.0001" if any(c.isdigit() for c in text) else ""
                raise DataError(f"line {line}: {col} is not a number ({text!r}){hint}")
            v = float(text)
            if not math.isfinite(v):
                raise DataError(f"line {line}: {col} is too large for a number ({text!r})")
            values[i] = v
        out[col] = values
    return out


def _positive(values: dict, col: str):
    bad = np.flatnonzero(values[col] <= 0)
    if bad.size:
        raise DataError(f"line {bad[0] + 2}: {col} must be positive, got {values[col][bad[0]]:g}")


def read_stiffness(path) -> MeasuredStiffness:
    """Read a measured-stiffness CSV file (see :func:`parse_stiffness`)."""
    return parse_stiffness(_file_text(path, "stiffness"))


def read_loop(path) -> MeasuredLoop:
    """Read a measured-loop CSV file (see :func:`parse_loop`)."""
    return parse_loop(_file_text(path, "loop"))


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
        raise DataError(f"line 1: the header must name frequency_hz, amplitude and either {need}"
                        f" (found: {', '.join(df.columns)})")
    if len(pairs) > 1:  # loss_factor beside phase_deg, or both polar and Cartesian: which one holds?
        raise DataError(f"line 1: give one form of the stiffness, not {' and '.join(' + '.join(p) for p in pairs)}")
    pair = pairs[0]
    extra = cols - set(STIFFNESS_KEYS) - set(pair) - {"mode"}
    if extra:
        raise DataError(f"line 1: unknown column(s) {', '.join(sorted(extra))}")
    _rows(df, "stiffness")
    mode = None
    if "mode" in cols:
        mode = np.array([str(m).strip() for m in df["mode"].tolist()], dtype=object)
        bad = [i for i, m in enumerate(mode) if m not in MODES]
        if bad:
            raise DataError(f"line {bad[0] + 2}: mode must be one of {', '.join(MODES)}, got {mode[bad[0]]!r}")
    v = _numbers(df, (*STIFFNESS_KEYS, *pair), "stiffness")
    _positive(v, "frequency_hz")
    _positive(v, "amplitude")
    lo, hi = MEASURED_FREQUENCY_HZ
    outside = np.flatnonzero((v["frequency_hz"] < lo) | (v["frequency_hz"] > hi))
    if outside.size:
        raise DataError(f"line {outside[0] + 2}: frequency_hz must be within {lo:g}–{hi:g} Hz, got "
                        f"{v['frequency_hz'][outside[0]]:g}")
    k = _complex_stiffness(v, pair)
    # any finite complex stiffness is a possible measurement: Im K < 0 (a negative loss factor)
    # is a blocked transfer stiffness above a wave resonance, Re K < 0 a mass-dominated one
    with np.errstate(over="ignore"):
        size = np.abs(k)
    bad = np.flatnonzero(~np.isfinite(size) | (size == 0))
    if bad.size:
        raise DataError(f"line {bad[0] + 2}: the stiffness is zero or too large for a number")
    lo, hi = STIFFNESS_RANGE
    bad = np.flatnonzero((size < lo) | (size > hi))
    if bad.size:
        raise DataError(f"line {bad[0] + 2}: the stiffness magnitude |K| = {size[bad[0]]:.3g} must be within "
                        f"{lo:g}–{hi:g} N/m or N·m/rad; are the units right?")
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
        raise DataError(f"line {bad[0] + 2}: phase_deg must be within {lo:g}…{hi:g} degrees, got {phase[bad[0]]:g}")
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
        raise DataError(f"line 1: the header must be {', '.join(LOOP_COLUMNS)} (found: {', '.join(cols)})")
    _rows(df, "loop")
    v = _numbers(df, LOOP_COLUMNS, "loop")
    if len(df) < 16:
        raise DataError(f"loop file has {len(df)} rows; at least 16 are needed for one period")
    step = np.diff(v["time_s"])
    bad = np.flatnonzero(step <= 0)
    if bad.size:
        raise DataError(f"line {bad[0] + 3}: time_s must increase (after {v['time_s'][bad[0]]:g})")
    if np.ptp(v["displacement"]) == 0:
        raise DataError("loop file: the displacement never moves")
    if np.ptp(v["force"]) == 0:
        raise DataError("loop file: the force never moves")
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
        raise DataError("loop file: time_s does not span a usable interval")
    with np.errstate(all="ignore"):
        f, amp, phase = loop.harmonic()
        x = loop.displacement / amp if amp > 0 else loop.displacement * math.inf
        departure = float(np.sqrt(np.mean((x - np.mean(x) - np.sin(phase)) ** 2)))
    lo, hi = MEASURED_FREQUENCY_HZ
    if not (math.isfinite(f) and lo <= f <= hi):
        found = f"{f:.3g} Hz" if math.isfinite(f) and f > 0 else "none found"
        raise DataError(f"loop file: its frequency ({found}, from a time step of {dt:.3g} s) must be within "
                        f"{lo:g}–{hi:g} Hz; is time_s in seconds?")
    if f * (span + dt) < 0.99:
        raise DataError(f"loop file: it holds {f * (span + dt):.2f} of a period at {f:.3g} Hz; at least one "
                        "whole period is needed")
    if not departure <= LOOP_SINE_DEPARTURE:
        raise DataError(f"loop file: the displacement is not a steady sine (its RMS departure from the best "
                        f"sine is {departure:.0%} of the amplitude; at most {LOOP_SINE_DEPARTURE:.0%})")

