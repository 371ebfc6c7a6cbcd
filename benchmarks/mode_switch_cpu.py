"""The server's CPU time of one mode switch in the explorer, in process (issue #27, item 16):
prints figures, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/mode_switch_cpu.py [--switches 10] [--profile]

It builds a session's page into a Bokeh document (as a server would, the Explorer tab shown),
switches ``state.mode`` axial → torsion → axial … (``--switches`` each way, after two warm-up
switches each way), each under Panel's document hold as a click on the mode buttons is, and
prints the CPU time (``time.process_time``: this process only, so other jobs on the machine do
not count) per switch, each way, median and maximum. ``--profile`` adds cProfile's 25 costliest
functions (cumulative) over the measured switches.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import statistics
import time


def session():
    from bokeh.document import Document
    from panel.io.document import hold
    from panel.io.state import set_curdoc

    from app.main import App

    app = App()
    doc = Document()
    with set_curdoc(doc):
        app.template().server_doc(doc)
    return app, doc, hold, set_curdoc


def main(n: int, profile: bool) -> dict:
    app, doc, hold, set_curdoc = session()
    times = {"torsion": [], "axial": []}
    prof = cProfile.Profile() if profile else None

    def switch(mode: str, record: bool):
        with set_curdoc(doc):
            t0 = time.process_time()
            if record and prof:
                prof.enable()
            with hold(doc):
                app.state.mode = mode
            if record and prof:
                prof.disable()
            if record:
                times[mode].append(1e3 * (time.process_time() - t0))

    for i in range(2 + n):
        switch("torsion", i >= 2)
        switch("axial", i >= 2)
    for mode, ms in times.items():
        print(f"  mode switch → {mode:8s} server CPU median {statistics.median(ms):6.1f} ms  "
              f"max {max(ms):6.1f} ms  ({len(ms)} switches)")
    both = times["torsion"] + times["axial"]
    print(f"  mode switch (both ways)   server CPU median {statistics.median(both):6.1f} ms")
    if prof:
        pstats.Stats(prof).sort_stats("cumulative").print_stats(25)
    return times


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--switches", type=int, default=10)
    parser.add_argument("--profile", action="store_true")
    args = parser.parse_args()
    main(args.switches, args.profile)
