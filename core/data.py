"""Measured data (docs/files.md): dynamic-stiffness tables and hysteresis loops, as the fits
and the diagnosis take them. Their files are read by :mod:`core.io.measured`; ``to_csv`` writes
them (the CSV of :mod:`core.io.table`).

All numbers are SI: Hz, m or rad, N/m or N·m/rad, s, N or N·m.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from .io.table import FILE_NUMBER_FORMAT, csv_text, written
from .response import ComplexStiffness
from .rules import OUT_OF_RANGE, RuleError

# fits and the diagnosis work on at most about this many stiffness points (denser data binned)
# and loop samples (denser loops folded onto one period's phase bins)
MAX_FIT_POINTS = 2000
MAX_FIT_SAMPLES = 2000
# measured |K| (N/m or N·m/rad) and a loop's force per displacement: from a thread to a bridge
# bearing; beyond, the units are wrong (and a fit's relative misfit loses every digit)
STIFFNESS_RANGE = (1e-6, 1e15)


class DataError(RuleError):
    """A measured-data file breaks a rule; the message names the line (``key``) and the reason."""


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
        return written(csv_text(cols, FILE_NUMBER_FORMAT), path)


@dataclass(frozen=True, eq=False)
class MeasuredLoop:
    """A measured steady harmonic test: displacement (m or rad) and force (N or N·m) in time."""

    time_s: np.ndarray
    displacement: np.ndarray
    force: np.ndarray

    def to_csv(self, path: str | Path | None = None) -> str:
        """The loop file of docs/files.md: its columns are this record's fields (time_s,
        displacement, force)."""
        cols = {f.name: getattr(self, f.name) for f in fields(self)}
        return written(csv_text(cols, FILE_NUMBER_FORMAT), path)

    def check_force(self) -> None:
        """The force's scale (checked after the amplitude's, whose rule names a wrong unit more
        plainly): its peak over the displacement's within :data:`STIFFNESS_RANGE`."""
        force = self.force - np.mean(self.force)
        ratio = float(np.max(np.abs(force))) / self.harmonic()[1]
        lo, hi = STIFFNESS_RANGE
        if not lo <= ratio <= hi:
            raise DataError("", f"loop file: the peak force per peak displacement ({ratio:.3g} N/m or N·m/rad) "
                            f"must be within {lo:g}–{hi:g}; are the units of force and displacement right?",
                            OUT_OF_RANGE)

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


