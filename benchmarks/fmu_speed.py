"""µs per step of the bushing's FMU: the C kernel alone (a loop in C, compiled here) and through
FMPy (an FMU2Slave stepped from Python). CPU time (the machine may be shared).

    PYTHONPATH=$PWD python benchmarks/fmu_speed.py

Aim (issue 30): the C kernel ≤ 0.5 µs a step for 1–3 slices (six channels, the default band's 13 exponentials).
Needs a C compiler and, for the FMPy figure, fmpy.
"""

from __future__ import annotations

import ctypes
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from core import PAPER_B
from core.element import coefficients
from tests.fmu_helpers import Kernel, compile_kernel
from tests.fmu_helpers import _ptr as ptr

LOOP = r"""
#include <math.h>
#include "bushing_kernel.h"
/* n steps of a sine drive of every channel: the forces summed (so nothing is optimised away) */
double bk_bench(const bk_sizes *z, const double *p, double *state, double *work, long n, double h,
                const double *amp, double w, long *evaluations)
{
    double x[BK_CHANNELS], f[BK_CHANNELS], total = 0.0;
    char message[BK_MESSAGE];
    for (long i = 0; i < n; i++) {
        for (int c = 0; c < BK_CHANNELS; c++) x[c] = amp[c] * sin(w * (double)(i + 1) * h + c);
        if (bk_advance(z, p, state, state, x, h, f, work, evaluations, message, sizeof message)) return NAN;
        total += f[0] + f[5];
    }
    return total;
}
"""


# bands whose fits (core.element.fit_power, α = 0.2) take 7, 13 and 19 exponentials
BANDS = ((10.0, 100.0), (0.1, 2000.0), (1e-3, 1e5))


def kernel_us(library, slices, band, strain=2e-3, steps=200_000):
    """(µs per step, exponentials) of the kernel alone over Paper B's coefficients."""
    k = Kernel(library, coefficients(PAPER_B, slices, band))
    amp = np.array([strain / PAPER_B.in_mode(m).strain_factor
                    for m in ("radial", "radial", "axial", "conical", "conical", "torsion")])
    bench = k.lib.bk_bench
    bench.restype = ctypes.c_double
    h = 1.0 / (20.0 * 400)
    args = (ctypes.byref(k.sizes), ptr(k.p), ptr(k.state), ptr(k.work))
    bench(*args, ctypes.c_long(1000), ctypes.c_double(h), ptr(amp), ctypes.c_double(2 * np.pi * 20),
          ctypes.byref(k.evaluations))  # warm
    start = time.process_time()
    total = bench(*args, ctypes.c_long(steps), ctypes.c_double(h), ptr(amp), ctypes.c_double(2 * np.pi * 20),
                  ctypes.byref(k.evaluations))
    cpu = time.process_time() - start
    assert np.isfinite(total)
    return 1e6 * cpu / steps, k.sizes.exponentials


def fmpy_us(slices, steps=20_000):
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    from fmu import write_fmu

    with tempfile.TemporaryDirectory() as tmp:
        result = write_fmu(coefficients(PAPER_B, slices), Path(tmp) / "bench.fmu")
        md = fmpy.read_model_description(str(result.path))
        s = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(str(result.path), str(Path(tmp) / "u")),
                      modelIdentifier=md.coSimulation.modelIdentifier)
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        h, inputs, outputs = 1.0 / 8000, list(range(6)), list(range(6, 12))
        start = time.process_time()
        for i in range(steps):
            s.setReal(inputs, [1e-4 * np.sin(0.05 * i)] * 6)
            s.doStep(i * h, h)
            s.getReal(outputs)
        cpu = time.process_time() - start
        s.terminate()
        s.freeInstance()
    return 1e6 * cpu / steps


def main() -> int:
    if shutil.which("cc") is None:
        print("no C compiler (cc): nothing to measure")
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        library = compile_kernel(Path(tmp), extra=LOOP)
        print("C kernel alone, six channels, per step (CPU time; aim ≤ 0.5 µs for 1–3 slices):")
        for slices in (1, 3, 10):
            for band in BANDS:
                us, exponentials = kernel_us(library, slices, band)
                print(f"  {slices:2d} slices, {exponentials:2d} exponentials (band {band[0]:g}–{band[1]:g} Hz): "
                      f"{us:6.3f} µs")
    try:
        import fmpy  # noqa: F401
    except ImportError:
        print("through FMPy: fmpy is not installed")
        return 0
    for slices in (1, 3):
        print(f"through FMPy (setReal, doStep, getReal from Python), {slices} slice(s): {fmpy_us(slices):6.1f} µs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
