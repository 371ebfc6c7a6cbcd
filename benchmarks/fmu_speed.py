"""µs per step of the bushing's FMU: the C kernel alone (a loop in C, compiled here) and through
FMPy (an FMU2Slave stepped from Python). CPU time (the machine may be shared).

    PYTHONPATH=$PWD python benchmarks/fmu_speed.py [--against DIR]

Aim (issue 30): the C kernel ≤ 0.5 µs a step for 1–10 slices (six channels; three bands whose fits take
7, 13 and 19 exponentials).
``--against DIR`` also times the kernel sources in DIR (bushing_kernel.c/.h, and bushing_series.c
if there) with the same loop, alternating, and prints the ratio: for instance an earlier
commit's, ``git show COMMIT:fmu/c/bushing_kernel.c > DIR/bushing_kernel.c`` (and the .h).
Needs a C compiler and, for the FMPy figure, fmpy.
"""

from __future__ import annotations

import argparse
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
/* n steps of a sine drive of every channel (phase c in channel c), the sines by a rotation
 * (no sin() in the loop: the kernel's cost is measured, not the libm's); the forces summed (so
 * nothing is optimised away). With `kernel` 0 the drive alone (the loop's own cost). */
double bk_bench(const bk_sizes *z, const double *p, double *state, double *work, long n, double h,
                const double *amp, double w, long *evaluations, int kernel)
{
    double x[BK_CHANNELS], f[BK_CHANNELS] = {0}, s[BK_CHANNELS], co[BK_CHANNELS], total = 0.0;
    double rc = cos(w * h), rs = sin(w * h);
    char message[BK_MESSAGE];
    for (int c = 0; c < BK_CHANNELS; c++) s[c] = sin(c), co[c] = cos(c);
    for (long i = 0; i < n; i++) {
        for (int c = 0; c < BK_CHANNELS; c++) {
            double t = s[c] * rc + co[c] * rs;
            co[c] = co[c] * rc - s[c] * rs;
            s[c] = t;
            x[c] = amp[c] * t;
        }
        if (kernel) {
            if (bk_advance(z, p, state, state, x, h, f, work, evaluations, message, sizeof message)) return NAN;
        } else {
            f[0] += x[0], f[5] += x[5];
        }
        total += f[0] + f[5];
    }
    return total;
}
"""


# bands whose fits (core.element.fit_power, α = 0.2) take 7, 13 and 19 exponentials
BANDS = ((10.0, 100.0), (0.1, 2000.0), (1e-3, 1e5))


def kernel_us(library, slices, band, strain=2e-3, steps=200_000, kernel=True):
    """CPU µs per step of the kernel (kernel=False: of the benchmark's loop alone), the
    layer-law evaluations per step and the exponentials, over Paper B's coefficients."""
    k = Kernel(library, coefficients(PAPER_B, slices, band))
    amp = np.array([strain / PAPER_B.in_mode(m).strain_factor
                    for m in ("radial", "radial", "axial", "conical", "conical", "torsion")])
    bench = k.lib.bk_bench
    bench.restype = ctypes.c_double
    h = 1.0 / (20.0 * 400)
    args = (ctypes.byref(k.sizes), ptr(k.p), ptr(k.state), ptr(k.work))
    w = ctypes.c_double(2 * np.pi * 20)
    bench(*args, ctypes.c_long(1000), ctypes.c_double(h), ptr(amp), w, ctypes.byref(k.evaluations), 1)  # warm
    k.evaluations.value = 0
    start = time.process_time()
    total = bench(*args, ctypes.c_long(steps), ctypes.c_double(h), ptr(amp), w, ctypes.byref(k.evaluations),
                  int(kernel))
    cpu = time.process_time() - start
    assert np.isfinite(total)
    return 1e6 * cpu / steps, k.evaluations.value / steps, k.sizes.exponentials


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


def compile_other(directory: Path, sources: Path) -> Path:
    """The kernel sources in ``sources`` with the benchmark's loop, as a shared library."""
    return compile_kernel(directory, LOOP, sources=sources, name="other")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", type=Path, help="a directory of other kernel sources to time alongside")
    args = parser.parse_args()
    if shutil.which("cc") is None:
        print("no C compiler (cc): nothing to measure")
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        library = compile_kernel(Path(tmp), extra=LOOP)
        other = compile_other(Path(tmp), args.against) if args.against else None
        print("C kernel alone, six channels, 400 steps a period of 20 Hz, per step (CPU time; the machine "
              "may be shared; aim ≤ 0.5 µs):")
        print(f"  (the benchmark's own loop, the drive without the kernel: "
              f"{kernel_us(library, 1, BANDS[0], steps=2_000_000, kernel=False)[0]:6.3f} µs, included below)")
        for slices in (1, 3, 10):
            for band in BANDS:
                us, evaluations, exponentials = kernel_us(library, slices, band)
                line = (f"  {slices:2d} slices, {exponentials:2d} exponentials (band {band[0]:g}–{band[1]:g} Hz): "
                        f"{us:6.3f} µs ({evaluations:5.1f} layer-law evaluations a step)")
                if other:
                    them, their, _ = kernel_us(other, slices, band)
                    line += f"; {args.against}: {them:6.3f} µs ({their:5.1f}), {them / us:4.1f}× this"
                print(line)
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
