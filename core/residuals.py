"""How far a model's stiffness is from measured stiffness: the misfits fits minimise and reports give.

The relative complex residual (K_model − K_data) / |K_data| is what fits minimise (its real and
imaginary parts); the gap of docs/files.md is its root mean square.
"""

from __future__ import annotations

import numpy as np

from .data import MeasuredStiffness


def relative_residual(model: np.ndarray, data: np.ndarray) -> np.ndarray:
    """(K_model − K_data) / |K_data|: complex, one per point (the gap's terms, what fits minimise)."""
    return (model - data) / np.abs(data)


def gap(model: np.ndarray, data: np.ndarray, count: np.ndarray | None = None) -> float:
    """docs/files.md's gap: sqrt(mean(|K_model − K_data|² / |K_data|²)); over binned data
    (``count`` points per entry) the mean counts each entry ``count`` times."""
    square = np.abs(relative_residual(model, data)) ** 2
    return float(np.sqrt(np.average(square, weights=count)))


def gaps_by_mode(k: np.ndarray, data: MeasuredStiffness) -> dict[str, float]:
    """The gap of each mode's rows of the model's K at ``data`` (empty without a `mode` column)."""
    if data.mode is None:
        return {}
    return {m: gap(k[data.mode == m], data.stiffness[data.mode == m],
                   None if data.count is None else data.count[data.mode == m])
            for m in np.unique(data.mode.astype(str))}
