"""The two implementations of the time-domain element give the same numbers (issue #30): the
Python element (:mod:`core.element`) and the FMU's C kernel (fmu/c/bushing_kernel.c, through
ctypes), built from the same coefficients (:func:`core.element.coefficients`) and driven with one
history, agree to 1e-9 relative at every step. The history moves all six channels at once with
reversals, varying steps and amplitudes across the Fletcher–Gent range; the designs have slices,
strain stiffening, viscosity and a bulk spring."""

from __future__ import annotations

import numpy as np
import pytest

from core import PAPER_B
from core.element import CHANNELS, Element, coefficients
from tests.fmu_helpers import Kernel, compile_kernel


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    return compile_kernel(tmp_path_factory.mktemp("kernel"))


def history(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(x (n, 6), h (n,)): every channel a sum of two sines with a slow envelope (reversals at
    several amplitudes: strains 1e-5 … 1e-2), steps varying ±40 % around 0.2 ms."""
    rng = np.random.default_rng(seed)
    h = 2e-4 * (1.0 + 0.4 * rng.uniform(-1, 1, n))
    t = np.cumsum(h)
    scale = np.array([1e-3, 1e-3, 1e-3, 2e-2, 2e-2, 5e-2])  # m (dx, dy, dz), rad (rx, ry, rz)
    f1, f2 = rng.uniform(5, 40, 6), rng.uniform(60, 200, 6)
    envelope = 0.01 + np.abs(np.sin(2 * np.pi * 3 * t))[:, None]
    x = scale * envelope * (np.sin(2 * np.pi * f1 * t[:, None]) + 0.3 * np.sin(2 * np.pi * f2 * t[:, None]))
    return x, h


DESIGNS = {
    "Paper B, 1 slice": (PAPER_B, 1),
    "Paper B, 3 slices": (PAPER_B, 3),
    "stiffening and viscosity, 2 slices": (PAPER_B.replace(effects={"strain_stiffening": {"stiffening": 40.0},
                                                                    "viscous": {"viscosity": 30.0}}), 2),
    "a bulk modulus, finite length": (PAPER_B.replace(shape="finite", bulk_modulus=2.0e8), 1),
}


@pytest.mark.filterwarnings("ignore::core.element.ElementWarning")  # the comparison, not the step's accuracy
@pytest.mark.parametrize("name", DESIGNS)
def test_the_python_element_and_the_c_kernel_agree(library, name):
    design, slices = DESIGNS[name]
    co = coefficients(design, slices=slices)
    element, kernel = Element(co), Kernel(library, co)
    x, h = history(600, seed=len(name))
    worst = 0.0
    for xi, hi in zip(x, h):
        trial = kernel.step(xi, hi, commit=False)  # a trial first: the kernel's state unchanged
        fp, fc = element.commit(xi, hi), kernel.step(xi, hi)
        np.testing.assert_array_equal(trial, fc)
        scale = np.maximum(np.abs(fp), 1e-12 * np.max(np.abs(fp)) + 1e-300)
        worst = max(worst, float(np.max(np.abs(fc - fp) / scale)))
    assert worst < 1e-9, f"largest relative difference {worst:.2e}"
    assert CHANNELS == ("dx", "dy", "dz", "rx", "ry", "rz")
