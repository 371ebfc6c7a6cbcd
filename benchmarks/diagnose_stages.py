"""Where the diagnosis of 150 points spends its work (issue #27, item 16): prints, per stage of
:func:`core.identify.diagnose.diagnose`, the evaluations of the model (calls of
:func:`core.bushing.stiffness_points`, each over the fit's points, and the parameter sets of each call of
:class:`core.points.PointsModel`, a finite-difference Jacobian's columns at once) and the CPU seconds
(``time.process_time``: the machine's load does not change them much, the wall clock's does).
Asserts nothing.

    PYTHONPATH=$PWD python benchmarks/diagnose_stages.py [--runs 3]

The data are those of ``benchmarks/diagnose_browser.py``: Paper B with a hidden 0.5 kg fixture
mass, 30 frequencies × 5 amplitudes, 0.5 % noise, seed 3.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections import defaultdict

import numpy as np

import core.identify.fit as fit_module
from core import PAPER_B
from core.identify.diagnose import diagnose, summary
from core.synthetic import synthetic_stiffness


def browser_data():
    """The 150 points the browser benchmark uploads."""
    hidden = PAPER_B.replace(effects={"inertia": {"mass": 0.5}})
    return synthetic_stiffness(hidden, np.linspace(1, 100, 30), [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3],
                               noise=0.005, seed=3)


def stage_of(message: str) -> str:
    """A progress message's stage: "step 1, candidate 3 of 9: viscous damping" → "step 1: viscous damping"."""
    if message.startswith("step "):
        step, _, rest = message.partition(",")
        return f"{step}: {rest.partition(': ')[2]}"
    return message


def measure(data):
    """One diagnosis: {stage: [evaluations, cpu s]} in the order met, and the result."""
    counts: dict[str, list[float]] = defaultdict(lambda: [0, 0.0])
    current = ["start"]
    clock = [time.process_time()]
    original, original_many = fit_module.stiffness_points, fit_module.PointsModel.__call__

    def counted(*args, **kwargs):
        counts[current[0]][0] += 1
        return original(*args, **kwargs)

    def counted_many(*args, **kwargs):
        k = original_many(*args, **kwargs)
        counts[current[0]][0] += len(k)
        return k

    def progress(_fraction, message):
        now = time.process_time()
        counts[current[0]][1] += now - clock[0]
        clock[0] = now
        current[0] = stage_of(message)

    fit_module.stiffness_points, fit_module.PointsModel.__call__ = counted, counted_many
    try:
        result = diagnose(PAPER_B, data, progress=progress)
    finally:
        fit_module.stiffness_points, fit_module.PointsModel.__call__ = original, original_many
    progress(1.0, "end")
    counts.pop("end", None)
    return dict(counts), result


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    data = browser_data()
    runs = [measure(data) for _ in range(args.runs)]
    stages, result = runs[0]
    print(f"diagnosis of {len(data)} points (median CPU of {args.runs} runs)")
    print(f"  {'stage':<58} {'evaluations':>11} {'CPU s':>7}")
    for name, (evaluations, _) in stages.items():
        cpu = statistics.median(r[0].get(name, [0, 0.0])[1] for r in runs)
        print(f"  {name:<58} {evaluations:>11d} {cpu:7.3f}")
    total_e = sum(e for e, _ in stages.values())
    total_cpu = statistics.median(sum(c for _, c in r[0].values()) for r in runs)
    print(f"  {'total':<58} {total_e:>11d} {total_cpu:7.3f}")
    print(summary(result))


if __name__ == "__main__":
    main()
