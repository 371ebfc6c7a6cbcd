"""Work bounded by the data's size: time and peak memory of `bushing fit` and `bushing diagnose`
at 150, 1 500, 15 000 and 100 000 measured points, each run as the command a user types (a fresh
process: reading the file, the work, writing the result). Prints figures, asserts nothing.

    python benchmarks/scaling.py [--sizes 150 1500 15000 100000]

Targets (issue 14): a few seconds for real measurement sizes (hundreds to a few thousand
points) and gentle growth beyond; data denser than core.data.MAX_FIT_POINTS are binned, so time
and memory beyond it grow only with reading the file and evaluating the model at every point.
The data: Paper B with an apparent mass of 0.5 kg hidden (the diagnosis must find it), five
amplitudes, log-spaced frequencies 1–100 Hz, 0.5 % complex noise.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from core import PAPER_B, write_design
from core.synthetic import synthetic_stiffness

AMPLITUDES = [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3]


def measure(argv: list[str]) -> tuple[float, float, int]:
    """Wall time (s) and peak resident memory (MB) of one process, and its exit status."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    seconds = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    proc.stderr.close()
    return seconds, usage.ru_maxrss / 1024.0, proc.returncode


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[150, 1500, 15000, 100000])
    args = parser.parse_args()
    bushing = [sys.executable, "-m", "cli.commands"]
    with tempfile.TemporaryDirectory() as tmp:
        design = Path(tmp) / "guess.json"
        write_design(PAPER_B.replace(shear_modulus=1.5e6, fractional_coefficient=1e6, fractional_order=0.4,
                                     friction_stress_max=4e4, friction_strain_half=1e-3), design)
        print(f"{'points':>8} {'fit s':>7} {'fit MB':>7} {'diagnose s':>11} {'diagnose MB':>12}")
        rows = []
        for n in args.sizes:
            data = synthetic_stiffness(PAPER_B.replace(effects={"inertia": {"mass": 0.5}}),
                                       np.geomspace(1, 100, max(n // 5, 1)), AMPLITUDES, noise=0.005, seed=1)
            path = Path(tmp) / f"measured_{n}.csv"
            data.to_csv(path)
            fit = measure([*bushing, "fit", str(path), "--design", str(design)])
            diag = measure([*bushing, "diagnose", str(path), "--design", str(design)])
            failed = [name for name, m in (("fit", fit), ("diagnose", diag)) if m[2] != 0]
            rows.append((n, fit, diag))
            print(f"{n:>8} {fit[0]:7.2f} {fit[1]:7.0f} {diag[0]:11.2f} {diag[1]:12.0f}"
                  + (f"  FAILED: {', '.join(failed)}" if failed else ""))
        if len(rows) > 1:
            (n0, f0, d0), (n1, f1, d1) = rows[0], rows[-1]
            print(f"from {n0} to {n1} points ({n1 / n0:.0f}x): fit time x{f1[0] / f0[0]:.1f}, "
                  f"diagnosis time x{d1[0] / d0[0]:.1f}, diagnosis memory x{d1[1] / d0[1]:.1f}")


if __name__ == "__main__":
    main()
