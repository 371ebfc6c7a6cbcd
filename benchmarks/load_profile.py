"""Where the explorer server's CPU goes under the load client: prints a profile, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/load_profile.py [--sessions 10] [--changes 6] [--top 25]

Starts ``bushing serve`` (``app.main.serve``, port 0) in a subprocess under cProfile, switched
on and off (through a file its IOLoop polls) at the load client's phases (``load_session.run_sessions``): from the
start to every session opened and quiet ("opens"), then to the end ("changes"). For each phase
it prints the server's own time (tottime) summed by where the code lives (the explorer's
``app``/``core``, HoloViews' plotting, the rest of HoloViews, Panel, Bokeh's serialisation and
protocol, the rest of Bokeh, param, NumPy, Tornado and asyncio, the rest) and the top functions
by cumulative time. cProfile sees the server's main thread, where Bokeh's server does its work,
and adds its own overhead (some ×1.5–2 on Python-heavy code): shares, not absolute times.
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from load_session import Plan, run_sessions, start_printing_url, stop

ROOT = str(Path(__file__).resolve().parents[1])
GROUPS = (  # (label, path fragments), the first that matches a function's file wins
    ("HoloViews plotting", ("holoviews/plotting",)),
    ("HoloViews core/streams", ("holoviews/",)),
    ("Panel", ("panel/",)),
    ("Bokeh serialisation+protocol", ("bokeh/core/serialization", "bokeh/protocol", "bokeh/document/json",
                                      "bokeh/server/protocol_handler", "bokeh/embed")),
    ("Bokeh models+properties", ("bokeh/core/", "bokeh/model", "bokeh/document")),
    ("Bokeh other", ("bokeh/",)),
    ("param", ("param/",)),
    ("NumPy/pandas", ("numpy/", "pandas/")),
    ("Tornado/asyncio", ("tornado/", "asyncio/")),
    ("explorer app/", (ROOT + "/app/",)),
    ("explorer core/", (ROOT + "/core/",)),
)
IDLE = {"<method 'poll' of 'select.epoll' objects>"}  # waiting for the network, not CPU


def serve_profiled(out_dir: str):
    """The explorer server in this process, profiled by phases: its IOLoop polls the file
    ``out_dir/phase`` every 20 ms; a new phase name there ends the last phase (its stats written
    to ``out_dir/<name>.prof``) and starts the next ("stop": none)."""
    from tornado.ioloop import IOLoop, PeriodicCallback

    control = Path(out_dir) / "phase"
    state = {"name": None, "profile": None}

    def poll():
        name = control.read_text().strip() if control.exists() else None
        if name == state["name"]:
            return
        if state["profile"] is not None:
            state["profile"].disable()
            state["profile"].dump_stats(str(Path(out_dir) / f"{state['name']}.prof"))
            state["profile"] = None
        state["name"] = name
        if name and name != "stop":
            state["profile"] = cProfile.Profile()
            state["profile"].enable()

    IOLoop.current()  # the loop the server will run (Bokeh's server takes the current one)
    PeriodicCallback(poll, 20).start()
    from app.main import serve

    serve(port=0, address="127.0.0.1")


def group_of(filename: str) -> str:
    for label, parts in GROUPS:
        if any(p in filename for p in parts):
            return label
    return "other"


def summary(path: Path, title: str, per: int, top: int):
    stats = pstats.Stats(str(path))
    busy = {k: v for k, v in stats.stats.items() if k[2] not in IDLE}
    total = sum(v[2] for v in busy.values())
    by_group: dict[str, float] = {}
    for (filename, _line, _name), (_cc, _nc, tt, _ct, _callers) in busy.items():
        by_group[group_of(filename)] = by_group.get(group_of(filename), 0.0) + tt
    print(f"{title}: {1000 * total:.0f} ms busy, profiled in the server's main thread ({1000 * total / max(1, per):.0f} ms "
          f"each of {per})")
    for label, t in sorted(by_group.items(), key=lambda kv: -kv[1]):
        print(f"  {label:<30} {100 * t / total:5.1f} %")
    print(f"  top {top} by cumulative time (ms each of {per}):")
    rows = sorted(busy.items(), key=lambda kv: -kv[1][3])[:top]
    for (filename, line, name), (_cc, nc, _tt, ct, _callers) in rows:
        where = filename.replace(ROOT + "/", "").split("site-packages/")[-1]
        print(f"    {1000 * ct / max(1, per):8.1f}  {name}  ({where}:{line}, {nc} calls)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sessions", type=int, default=10)
    ap.add_argument("--changes", type=int, default=6)
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--serve", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.serve:
        serve_profiled(a.serve)
        return
    with tempfile.TemporaryDirectory() as tmp:
        proc, url = start_printing_url([sys.executable, __file__, "--serve", tmp],
                                       env={"PYTHONPATH": str(Path(__file__).resolve().parents[1])})
        control = Path(tmp) / "phase"
        names = {"start": "opens", "opened": "changes", "end": "stop"}

        def phase(name):
            (Path(tmp) / "next").write_text(names[name])
            os.replace(Path(tmp) / "next", control)  # whole, never half-written

        try:
            outs = run_sessions(url.replace("http://", "ws://") + "ws", a.sessions, Plan(changes=a.changes), 300,
                                on_phase=phase)
            deadline = time.monotonic() + 30
            while not (Path(tmp) / "changes.prof").exists() and time.monotonic() < deadline:
                time.sleep(0.1)  # the server writes the last phase's stats
        finally:
            stop(proc)
        for o in outs:
            if o.error:
                print(f"session {o.index}: {o.error}")
        opened = sum(o.open_s is not None for o in outs)
        answered = sum(a is not None for o in outs for a in o.answers)
        summary(Path(tmp) / "opens.prof", "opens", opened, a.top)
        summary(Path(tmp) / "changes.prof", "changes", answered, a.top)


if __name__ == "__main__":
    main()
