"""Results of costly pure functions remembered by their exact arguments: a fit's finite-difference
Jacobian changes one parameter at a time, so most pieces of the model come again with the same
inputs (:mod:`core.material` remembers the friction modulus and (iω)^α this way).
"""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

REMEMBERED = 64  # the last results kept, by their exact arguments
REMEMBERED_SIZE = 4096  # for a list of at most this many points (a fit's), not grids
MEMORY: OrderedDict = OrderedDict()
MEMORY_LOCK = threading.Lock()


def remembered(key, compute, x):
    """``compute(x)`` for the float array ``x``, from the last :data:`REMEMBERED` results when
    the same ``key`` and the same exact bytes of ``x`` come again: identical numbers, as a copy.
    A fit's finite-difference Jacobian changes one parameter at a time, so most pieces of the
    model repeat. Only a list of points is remembered (one dimension, at most
    :data:`REMEMBERED_SIZE` values: a fit's); single numbers, grids and the slices' layers are
    computed afresh."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size > REMEMBERED_SIZE:
        return compute(x)
    k = (key, x.shape, x.tobytes())
    with MEMORY_LOCK:
        hit = MEMORY.get(k)
        if hit is not None:
            MEMORY.move_to_end(k)
            return hit.copy()
    value = compute(x)
    with MEMORY_LOCK:
        MEMORY[k] = value
        if len(MEMORY) > REMEMBERED:
            MEMORY.popitem(last=False)
    return value.copy()
