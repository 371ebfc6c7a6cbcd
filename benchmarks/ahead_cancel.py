"""How long work asked for waits for a diagnosis started ahead to give way (app.work.start_ahead,
docs/serving.md): prints figures, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/ahead_cancel.py [--cancels 24]

One worker process; ``--cancels`` times: the diagnosis of 150 points (diagnose_stages.py's data)
is started ahead, and after a delay spread from 0.05 to 1.2 s (its stages) a task that does
nothing is asked for: the wait, from the asking to its result, is the time the worker took to
stop the diagnosis at its next progress report, plus the round trip of a task.
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from diagnose_stages import browser_data  # the same 150 points

from app import work
from core import PAPER_B
from core.identify.diagnose import diagnose


def nothing(progress=None):
    return 0


async def waits(cancels: int) -> list[float]:
    task = work.Task(diagnose, (PAPER_B, browser_data()), {"baseline": ["elastic", "fractional", "friction"]})
    await work.in_thread(task)  # the worker warm
    out = []
    for delay in np.linspace(0.05, 1.2, cancels):
        assert work.start_ahead(task) is not None
        await asyncio.sleep(delay)
        start = time.perf_counter()
        await work.in_thread(work.Task(nothing))
        out.append(time.perf_counter() - start)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cancels", type=int, default=24)
    args = parser.parse_args()
    work.use_processes(1)
    try:
        out = asyncio.run(waits(args.cancels))
    finally:
        work.stop_processes()
    print(f"work asked for while a diagnosis started ahead ran: waited a median of {statistics.median(out) * 1000:.0f} ms, "
          f"at most {max(out) * 1000:.0f} ms ({len(out)} cancels)")


if __name__ == "__main__":
    main()
