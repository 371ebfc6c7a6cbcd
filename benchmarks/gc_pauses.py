"""The server's full garbage collections during pages' work, CPython's own rule against
:class:`app.collector.QuietCollector` (issue #27, item 16; the classroom): prints figures,
asserts nothing.

    PYTHONPATH=$PWD python benchmarks/gc_pauses.py [--pages 10] [--think 0.3]

A class joins one server process: in process, as a served explorer does (the startup objects
frozen first, :func:`app.collector.freeze_startup_objects`), ``--pages`` pages are built one after the
other (each a session's Explorer, as ``benchmarks/mode_switch_cpu.py`` builds it), and after each
new page every page open switches its mode to torsion and back (two changes per page, under the
document's hold, as a click is). Between two of these ``--think`` seconds pass (the users reading);
the collector, when on, looks once a second at such moments, as the server's event loop calls it.
Each arm runs in its own process. Printed per arm: the full collections that ran inside a page
build or a change (how many, their total and longest pause) and those between them, the CPU time of
the whole run, and the objects of the oldest generation at its end (memory stays bounded).
"""

from __future__ import annotations

import argparse
import gc
import json
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def run(arm: str, pages: int, think: float) -> dict:
    from mode_switch_cpu import session  # the app's imports: in the arm's own process only

    from app import collector

    collector.freeze_startup_objects()
    quiet = collector.QuietCollector()
    if arm == "quiet":
        quiet.start()
    inside = [False]
    pauses = {"inside": [], "between": []}
    started = [0.0]

    def watch(phase, info):
        if info["generation"] != 2:
            return
        if phase == "start":
            started[0] = time.perf_counter()
        else:
            pauses["inside" if inside[0] else "between"].append(time.perf_counter() - started[0])

    gc.callbacks.append(watch)
    last_look = [time.monotonic()]

    def work(step):
        inside[0] = True
        try:
            step()
        finally:
            inside[0] = False
        deadline = time.monotonic() + think
        while time.monotonic() < deadline:  # the users think; the event loop's periodic look
            if arm == "quiet" and time.monotonic() - last_look[0] >= collector.CHECK_S:
                last_look[0] = time.monotonic()
                quiet.look()
            time.sleep(0.02)

    cpu = time.process_time()
    open_pages = []
    for _ in range(pages):
        work(lambda: open_pages.append(session()))
        for app, doc, hold, set_curdoc in open_pages:
            for mode in ("torsion", "axial"):
                def change(app=app, doc=doc, hold=hold, set_curdoc=set_curdoc, mode=mode):
                    with set_curdoc(doc), hold(doc):
                        app.state.mode = mode
                work(change)
    gc.callbacks.remove(watch)
    quiet.stop()
    return {"inside": pauses["inside"], "between": pauses["between"], "cpu": time.process_time() - cpu,
            "oldest": len(gc.get_objects(2))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pages", type=int, default=10)
    parser.add_argument("--think", type=float, default=0.3)
    parser.add_argument("--arm", choices=("cpython", "quiet"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.arm:
        print(json.dumps(run(args.arm, args.pages, args.think)))
        return
    print(f"{args.pages} pages joining one server process, each page open switching its mode twice after each "
          f"new page, {args.think} s between two of these")
    for arm, name in (("cpython", "CPython's rule"), ("quiet", "quiet collector")):
        out = subprocess.run([sys.executable, __file__, "--arm", arm, "--pages", str(args.pages), "--think",
                              str(args.think)], capture_output=True, text=True, check=True)
        r = json.loads(out.stdout.strip().splitlines()[-1])
        inside, between = r["inside"], r["between"]
        print(f"  {name:<16} inside a page build or a change: {len(inside):2d} full collections, "
              f"{sum(inside):.3f} s in all, longest {max(inside, default=0):.3f} s; between: {len(between):2d}, "
              f"{sum(between):.3f} s; CPU {r['cpu']:.1f} s; oldest generation at the end {r['oldest']:,} objects")


if __name__ == "__main__":
    main()
