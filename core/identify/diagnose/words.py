"""Plain words: where on the frequency and amplitude axes a model and the data disagree."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ...data import MeasuredStiffness
from ...parameters import MODE
from ...response import loss_factor, magnitude_residual_pct


def _bins(values: np.ndarray, most: int = 8) -> tuple[np.ndarray, list[tuple[float, float]]]:
    """Bin labels over ln(values): the distinct values if few, else equal-count bins."""
    distinct = np.unique(np.round(values, 12))
    if distinct.size <= most:
        labels = np.searchsorted(distinct, np.round(values, 12))
        return labels, [(v, v) for v in distinct]
    edges = np.quantile(np.log(values), np.linspace(0, 1, most + 1))
    labels = np.clip(np.searchsorted(edges, np.log(values), side="right") - 1, 0, most - 1)
    ranges = []
    for b in range(most):
        sel = values[labels == b]
        ranges.append((float(sel.min()), float(sel.max())) if sel.size else (math.nan, math.nan))
    return labels, ranges


def _fmt_freq(f: float) -> str:
    return f"{f:.3g} Hz"


def _amplitude_formatter(mode: str) -> Callable[[float], str]:
    """An amplitude (SI) of ``mode`` in the unit people read: mm, or rad."""
    unit = MODE[mode].amplitude
    per_si = 1.0 / unit.factor  # display units per SI unit, 1000 mm per m: exact, as x / 1e-3 is not
    return lambda x: f"{x * per_si:.3g} {unit.display}"


def _growth(centres: np.ndarray, means: np.ndarray, what: str) -> str:
    """'growing with frequency squared' and the like, from a power-law fit of |misfit|."""
    if centres.size < 2 or np.ptp(np.log(centres)) < math.log(2.0):
        return ""
    p = np.polyfit(np.log(centres), np.log(np.abs(means)), 1)[0]
    if p > 1.6:
        return f"growing with {what} squared" if p < 2.6 else f"growing steeply with {what} (as {what}^{p:.1f})"
    if p > 0.6:
        return f"growing in proportion to {what}" if p < 1.4 else f"growing with {what} (as {what}^{p:.1f})"
    if p > 0.2:
        return f"growing slowly with {what}"
    if p < -0.2:
        return f"shrinking as the {what} grows"
    return ""


def _extent(ranges, significant: np.ndarray, fmt, noun: str) -> str:
    """'from 60 Hz up', 'at every amplitude', 'from … to …' from the significant bins."""
    idx = np.flatnonzero(significant)
    n = len(ranges)
    lo, hi = idx.min(), idx.max()
    if lo == hi and ranges[lo][0] == ranges[lo][1]:
        return f"at {fmt(ranges[lo][0])}"
    if lo == 0 and hi == n - 1:
        return f"at every {noun}"
    if hi == n - 1:
        return f"from {fmt(ranges[lo][0])} up"
    if lo == 0:
        return f"up to {fmt(ranges[hi][1])}"
    return f"from {fmt(ranges[lo][0])} to {fmt(ranges[hi][1])}"


def _profile(values, labels, n_bins, scale, mask):
    """Mean of ``values`` per bin over the points in ``mask``, and its standard error."""
    means, se = np.full(n_bins, np.nan), np.full(n_bins, np.inf)
    for b in range(n_bins):
        sel = values[(labels == b) & mask]
        if sel.size:
            means[b] = sel.mean()
            se[b] = scale / math.sqrt(sel.size)
    return means, se


def _region(values, axes, scale, level):
    """The frequency and amplitude bins where ``values`` is significantly positive: the
    frequency profile over all points, the amplitude profile over the points in the significant
    frequency bins, then the frequency profile again over those amplitudes."""
    (fl, fr), (al, ar) = axes
    everywhere = np.ones(values.size, bool)
    fm, fse = _profile(values, fl, len(fr), scale, everywhere)
    f_sig = fm > level * fse
    if not f_sig.any():
        return None
    am, ase = _profile(values, al, len(ar), scale, f_sig[fl])
    a_sig = am > level * ase
    if not a_sig.any():
        return None
    fm, fse = _profile(values, fl, len(fr), scale, a_sig[al])
    f_sig = fm > level * fse
    if not f_sig.any():
        return None
    return (fm, f_sig), (am, a_sig)


def describe(data: MeasuredStiffness, model_k: np.ndarray, mode: str, noise_sd: float,
             level: float = 3.0) -> str:
    """The misfit in plain words: for |K| and the loss factor, which way the model is off,
    where on the frequency and amplitude axes, and how it grows. ``noise_sd`` is the standard
    deviation of the relative noise in one part (real or imaginary).

    A bin of the frequency (amplitude) axis counts where the mean misfit over it is more than
    ``level`` standard errors from zero (see :func:`_region`). If nothing counts at 3 standard
    errors, 2 are tried before the misfit is called noise.
    """
    quantities = (
        ("|K|", magnitude_residual_pct(model_k, data.stiffness) / 100.0, ("too stiff", "too soft"), noise_sd),
        ("loss factor", loss_factor(model_k) - data.loss_factor, ("too high", "too low"),
         noise_sd * float(np.sqrt(np.mean(1.0 + data.loss_factor**2)))),
    )
    axes = (_bins(data.frequency_hz), _bins(data.amplitude))
    centres = [np.array([math.sqrt(lo * hi) for lo, hi in ranges]) for _, ranges in axes]
    fmt_amp = _amplitude_formatter(mode)
    phrases = []
    for name, misfit, (over, under), scale in quantities:
        parts = []
        for sign, word in ((1.0, over), (-1.0, under)):
            region = _region(sign * misfit, axes, scale, level)
            if region is None:
                continue
            (fm, f_sig), (am, a_sig) = region
            size = float(np.max(fm[f_sig]))
            text = (f"model {word} {_extent(axes[0][1], f_sig, _fmt_freq, 'frequency')}, "
                    f"{_extent(axes[1][1], a_sig, fmt_amp, 'amplitude')}")
            growth = [g for g in (_growth(centres[0][f_sig], fm[f_sig], "frequency"),
                                  _growth(centres[1][a_sig], am[a_sig], "amplitude")) if g]
            if growth:
                text += ", " + " and ".join(growth)
            amount = f"{size:.3f}" if name == "loss factor" else f"{100 * size:.2g} %"
            parts.append((size / scale, f"{text} (by up to {amount})"))
        if parts:
            parts.sort(reverse=True)
            phrases.append((parts[0][0], f"{name}: " + "; ".join(p for _, p in parts)))
    if not phrases:
        if level > 2.0:
            return describe(data, model_k, mode, noise_sd, level=2.0)
        return "no misfit above the noise."
    phrases.sort(reverse=True)
    texts = [p for _, p in phrases]  # a sentence each; the first follows the caller's colon
    return ". ".join([texts[0], *(t[:1].upper() + t[1:] for t in texts[1:])]) + "."
