"""The server's CPU time from a diagnosis' result to its report pushed, in process (issue #27,
item 16): prints figures, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/diagnosis_report_cpu.py [--runs 5] [--profile] [--walk]

It runs the diagnosis of the browser benchmark's 150 points (``benchmarks/diagnose_browser.py``:
Paper B with a hidden 0.5 kg fixture mass) once. Then ``--runs`` times, each in a new session
built into a Bokeh document as a server would (the *Find the missing effect* tab shown, the data
loaded, the document's pending work done): it stores that result as the tab does when its work
ends (one held change) and serializes the held changes as the server's ``PATCH-DOC`` message.
It prints the CPU time (``time.process_time``: this process only, other jobs on the machine do
not count) of the first report of a session (what every page pays) and of a second one in the
same session, with the Bokeh models each creates and the message's size, and the CPU time of
loading the data (what the tab makes ready for the report is made then). ``--profile`` adds
cProfile's 25 costliest functions (cumulative) over the first reports. The library hooks of
:func:`app.patches.install` are in place, as in a served explorer; ``--walk`` leaves out the one
that attaches the models a change added (:mod:`app.patches.model_graph`): each change that adds
models then walks the whole document, as Bokeh does.
"""

from __future__ import annotations

import argparse
import asyncio
import cProfile
import pstats
import statistics
import threading
import time

import numpy as np


def data_csv() -> str:
    from core import PAPER_B
    from core.synthetic import synthetic_stiffness

    hidden = PAPER_B.replace(effects={"inertia": {"mass": 0.5}})
    return synthetic_stiffness(hidden, np.linspace(1, 100, 30), [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3],
                               noise=0.005, seed=3).to_csv()


def session(csv: str):
    """A session's page in a Bokeh document, the diagnosis tab shown and the data loaded; the
    document's pending callbacks (work a page's load runs after its first push) run."""
    from bokeh.document import Document
    from panel.io.state import set_curdoc, state

    from app import patches
    from app.main import App

    patches.install()  # the process-wide hooks, as the server's first session installs them
    app = App()
    doc = Document()
    # as a server's session: a hold's end, on the session's thread, triggers the document's changes
    state._connected[doc] = True
    state._thread_id_[doc] = threading.get_ident()
    with set_curdoc(doc):
        app.template().server_doc(doc)
        app.tabs.active = next(i for i, (_t, name, _b) in enumerate(app.LAZY_TABS, 1) if name == "diagnosis")
        t0 = time.process_time()
        assert app.diagnosis.state.load_csv(csv, "inertia.csv")
        drain(doc)
        app.load_ms = 1e3 * (time.process_time() - t0)
    return app, doc


def drain(doc):
    """Run the document's pending next-tick callbacks (what the server's event loop would)."""
    for _ in range(10):
        callbacks = [cb for cb in list(doc.session_callbacks) if type(cb).__name__ == "NextTickCallback"]
        if not callbacks:
            return
        for cb in callbacks:
            doc.remove_next_tick_callback(cb)
            result = cb.callback()
            if asyncio.iscoroutine(result):
                asyncio.run(result)


def report(app, doc, result, prof=None) -> tuple[float, int, int]:
    """CPU ms to store ``result`` as the tab does and serialize the change; models created; bytes."""
    from bokeh.document.events import DocumentPatchedEvent
    from bokeh.protocol import Protocol
    from panel.io.state import set_curdoc

    from app.live import one_change

    state = app.diagnosis.state
    events = []

    def collect(event):
        if isinstance(event, DocumentPatchedEvent):  # what a server session sends to its page
            events.append(event)

    doc.on_change(collect)
    with set_curdoc(doc):
        state.param.update(running=True, result=None, progress=0.0, progress_message="fitting the baseline")
        drain(doc)
        events.clear()
        before = {m.id for m in doc.models}
        t0 = time.process_time()
        if prof:
            prof.enable()
        with one_change():
            state.param.update(result=result, running=False, progress=1.0)
        message = Protocol().create("PATCH-DOC", events) if events else None
        size = len(message.content_json) + sum(len(b.data) for b in message.buffers) if message else 0
        if prof:
            prof.disable()
        ms = 1e3 * (time.process_time() - t0)
    doc.remove_on_change(collect)
    after = {m.id for m in doc.models}
    return ms, len(after - before), size


def main(runs: int, profile: bool, walk: bool = False):
    if walk:
        from app import patches

        patches.track_reference_changes = lambda: None  # before the first session installs the hooks
    from app.main import App

    csv = data_csv()
    app = App()
    assert app.diagnosis.state.load_csv(csv, "inertia.csv")
    t0 = time.process_time()
    result = app.diagnosis.state.compute()
    print(f"diagnosis of 150 points: {time.process_time() - t0:.2f} s CPU (once; not counted below)")
    prof = cProfile.Profile() if profile else None
    first, second, load = [], [], []
    report(*session(csv), result)  # warm: imports and caches
    for _ in range(runs):
        app, doc = session(csv)
        load.append(app.load_ms)
        first.append(report(app, doc, result, prof))
        second.append(report(app, doc, result))
    print(f"  {'data loaded':<28} server CPU median {statistics.median(load):6.1f} ms (the upload's reading and "
          "judging, and whatever the tab makes ready then)")
    for name, rows in (("first report of a session", first), ("second report, same session", second)):
        ms = [r[0] for r in rows]
        print(f"  {name:<28} server CPU median {statistics.median(ms):6.1f} ms (max {max(ms):6.1f}); "
              f"{rows[0][1]} Bokeh models created; PATCH-DOC {rows[0][2] / 1024:.0f} KiB")
    if prof:
        pstats.Stats(prof).sort_stats("cumulative").print_stats(25)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--walk", action="store_true", help="no attaching of added models: Bokeh's walk")
    args = parser.parse_args()
    main(args.runs, args.profile, args.walk)
