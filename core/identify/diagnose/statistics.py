"""Misfit statistics: the information criterion, the noise estimate, what "explains" means."""

from __future__ import annotations

import math

import numpy as np

from ...data import MeasuredStiffness

BIC_THRESHOLD = 10.0
EXPLAINED_FRACTION = 0.8  # an effect is named when it explains 80 % of the misfit above the noise
NOISE_TOLERANCE = 0.15  # … or leaves no more than 15 % of the noise's variance (its estimate's spread)
NOISE_RATIO = 1.3  # a mean squared misfit above 1.3 × the noise's is "above the noise"
PRECISION = 1e-6  # relative misfits below this are numerical, not measured


def bic(residual: np.ndarray, n_parameters: int) -> float:
    """BIC over the real and imaginary parts of the residual. A misfit below
    :data:`PRECISION` (relative) counts as none: the models are computed to about 1e-11, and
    differences below that are the optimiser's, not the data's."""
    n = 2 * residual.size
    rss = float(np.sum(np.abs(residual) ** 2))
    return n * math.log(max(rss / n, PRECISION**2)) + n_parameters * math.log(n)


def runs(data: MeasuredStiffness):
    """Index triples (i, j, k) of neighbours along ln f at one amplitude and along ln amplitude
    at one frequency, with their log coordinates. Data on no such lines (scattered points) fall
    back on each point's two nearest neighbours in (ln f, ln amplitude), scaled to their ranges,
    weighted equally. Data of several modes: runs within each mode."""
    lf, la = np.log(data.frequency_hz), np.log(data.amplitude)
    # a run never crosses from one mode's rows to another's
    _, mode = (np.zeros(lf.size), np.zeros(lf.size, dtype=int)) if data.mode is None else \
        np.unique(data.mode.astype(str), return_inverse=True)
    triples = []
    for along, across in ((lf, la), (la, lf)):
        keys = np.round(across, 9) + 1e4 * mode  # ln values lie within ±1e3
        for key in np.unique(keys):
            idx = np.flatnonzero(keys == key)
            idx = idx[np.argsort(along[idx], kind="stable")]
            x = along[idx]
            for n in range(1, idx.size - 1):
                if x[n + 1] > x[n - 1]:
                    triples.append((idx[n - 1], idx[n], idx[n + 1], x[n - 1], x[n], x[n + 1]))
    if triples or lf.size < 3:
        return triples
    pts = np.column_stack([*((v - v.min()) / (np.ptp(v) or 1.0) for v in (lf, la)), 1e3 * mode])
    dist = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=-1)
    np.fill_diagonal(dist, np.inf)
    near = np.argsort(dist, axis=1)[:, :2]
    return [(int(a), j, int(b), 0.0, 1.0, 2.0) for j, (a, b) in enumerate(near)]


def noise_variance(residual: np.ndarray, data: MeasuredStiffness, triples=None) -> float | None:
    """Complex noise variance s² (E|n|²) estimated from the residual's roughness (at least
    :data:`PRECISION`²); ``None`` when the data have no run of three points to judge it by.
    ``triples``: :func:`runs` of the data, if already found."""
    triples = runs(data) if triples is None else triples
    if not triples:
        return None
    i, j, k, x0, x1, x2 = (np.array(c) for c in zip(*triples))
    i, j, k = i.astype(int), j.astype(int), k.astype(int)
    w0 = (x2 - x1) / (x2 - x0)
    w2 = (x1 - x0) / (x2 - x0)
    e = residual[j] - (w0 * residual[i] + w2 * residual[k])
    return max(float(np.mean(np.abs(e) ** 2 / (1.0 + w0**2 + w2**2))), PRECISION**2)


def explains(before, after, noise: float | None) -> tuple[bool, float | None]:
    """Whether ``after`` leaves at most a fifth of ``before``'s misfit above the noise (or no more
    than the noise estimate's own uncertainty, :data:`NOISE_TOLERANCE`); and the fraction of the
    misfit above the noise that it explains."""
    if noise is None:
        return True, None
    excess_before = before.mean_square - noise
    left = after.mean_square - noise
    fraction = None if excess_before <= 0 else min(max((excess_before - left) / excess_before, 0.0), 1.0)
    return left <= max((1.0 - EXPLAINED_FRACTION) * excess_before, NOISE_TOLERANCE * noise), fraction


def lower(noise: float | None, estimate: float | None) -> float | None:
    if estimate is None:
        return noise
    return estimate if noise is None else min(noise, estimate)
