"""Seeded Latin hypercubes: the starting points of the fit and of the design search."""

from __future__ import annotations

import numpy as np


def latin_hypercube(count: int, dimensions: int, seed: int = 0) -> np.ndarray:
    """``count`` points in the unit cube of ``dimensions`` dimensions, shape (count,
    dimensions): each column holds one point in each of ``count`` equal strata of [0, 1), at a
    uniform place within it, the strata in a random order. NumPy's default generator seeded
    with ``seed`` draws each column in turn (the strata's places, then their order): the same
    seed gives the same points."""
    rng = np.random.default_rng(seed)
    columns = [rng.permutation((np.arange(count) + rng.random(count)) / count) for _ in range(dimensions)]
    return np.array(columns).T.reshape(count, dimensions)
