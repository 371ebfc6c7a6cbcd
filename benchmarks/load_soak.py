"""A class that comes and goes, at the protocol level (issue #28, part 4): the server's memory
per idle session and over repeated cycles of sessions. Prints figures, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/load_soak.py [--cycles 3] [--sessions 30] [--changes 2]

Starts one `bushing serve` process (loopback, a port the OS picks). Each cycle opens
``--sessions`` bokeh.client sessions together (``load_session.py``'s: a browser's as far as the
server can tell), reads the server's resident memory (VmRSS) once every session has opened and
the server is quiet (the sessions idle: the memory of an idle session is the growth over the
cycle's start, divided by the sessions), lets each move the amplitude ``--changes`` times, closes
them all, then waits the unused-session lifetime and one check interval (app.main) plus a margin
and reads the memory again. Memory that comes back to a plateau after the first cycle (libraries
and caches warmed up) means the sessions' memory is given back.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from load_session import Plan, rss_mb, run_sessions, start_explorer, stop

from app.main import SESSION_CHECK_S, SESSION_LIFETIME_S

MARGIN_S = 5


def main(cycles: int, sessions: int, changes: int, time_limit: float):
    proc, url = start_explorer()
    ws = url.replace("http://", "ws://") + "ws"
    plan = Plan(changes=changes, pause=(1.0, 3.0), open_timeout=60.0, answer_timeout=30.0)
    try:
        start = rss_mb(proc.pid)
        print(f"one process, {sessions} sessions a cycle, {changes} changes each; RSS at start {start:.0f} MB")
        for cycle in range(1, cycles + 1):
            seen = {}
            outs = run_sessions(ws, sessions, plan, time_limit, routes=False,
                                on_phase=lambda phase, seen=seen: seen.__setitem__(phase, rss_mb(proc.pid)))
            opened = sum(o.open_s is not None for o in outs)
            time.sleep(SESSION_LIFETIME_S + SESSION_CHECK_S + MARGIN_S)
            after = rss_mb(proc.pid)
            idle = (seen["opened"] - seen["start"]) / max(opened, 1)
            failed = sessions - opened
            print(f"  cycle {cycle}: {opened} opened{f' ({failed} failed)' if failed else ''}; RSS "
                  f"{seen['start']:.0f} MB before, {seen['opened']:.0f} MB with every session open and idle "
                  f"({idle:.1f} MB a session), {seen['end']:.0f} MB at the end, {after:.0f} MB after the "
                  f"lifetime ({SESSION_LIFETIME_S} s + {SESSION_CHECK_S} s check + {MARGIN_S} s)")
    finally:
        stop(proc)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cycles", type=int, default=3)
    ap.add_argument("--sessions", type=int, default=30)
    ap.add_argument("--changes", type=int, default=2, help="per session")
    ap.add_argument("--time-limit", type=float, default=300.0, help="s per cycle (it stops by itself)")
    a = ap.parse_args()
    if not (1 <= a.cycles <= 20 and 1 <= a.sessions <= 200 and 0 <= a.changes <= 50 and 10 <= a.time_limit <= 3600):
        ap.error("--cycles 1–20, --sessions 1–200, --changes 0–50, --time-limit 10–3600 s")
    main(a.cycles, a.sessions, a.changes, a.time_limit)
