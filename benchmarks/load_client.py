"""A classroom on one machine, at the protocol level (issue #28): prints figures, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/load_client.py [--sessions 30] [--changes 6] [--processes 1 2]
                                                      [--floors | --no-floors] [--time-limit 300]

For each configuration it starts the servers on loopback (ports picked by the OS), opens
``--sessions`` bokeh.client sessions together (no browser: ``load_session.py``; each imports
Panel's models, sends ``DocumentReady`` as a page does and sets ``TCP_NODELAY``), waits until
every session has opened (or failed) and the servers are quiet, then each session moves the
"Drive amplitude" slider ``--changes`` times, a seeded pause of 1–3 s before each, and times each
change from setting the value to the first message that changes a plot's data. The
configurations, in this order:

* with ``--floors`` (the default): the two floor pages of ``load_floors.py``, one process each:
  the bare Panel page (one slider → one ``DynamicMap`` curve of 400 points) and the plain
  HoloViews idiom (one slider → five ``DynamicMap`` s of five curves of 200 points);
* the explorer (``bushing serve``) with each count of ``--processes``: one process directly,
  more behind the Debian nginx (``deploy/nginx.conf.template``, each session its own route
  cookie, so sessions spread over the processes).

Per configuration it prints the opens (p50, max; errors by reason), the changes (p50, p95, max;
unanswered within ``--answer-timeout``), sessions the server closed (dropped), the server's CPU
(utime+stime of ``/proc/PID/stat``, every server process) per session opened (from the start
to every session opened and quiet) and per change answered (from then to the end), the RSS of
each server process (idle, after the opens, at the end), ``/liveness`` polled once a second
throughout, and the load average. Then the explorer's figures as ratios to each floor's.

Everything shares this machine: the servers, nginx and the client (one thread per session).
Each configuration stops by itself after ``--time-limit`` s; what has not happened by then is
reported as unanswered.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from load_session import (
    Plan,
    cpu_seconds,
    port_of,
    probe,
    rss_mb,
    run_sessions,
    start_explorer,
    start_floor,
    start_nginx,
    stop,
)


def pct(values: list[float], q: float) -> float:
    """The ``q``-th percentile (nearest rank) of ``values``."""
    values = sorted(values)
    return values[min(len(values) - 1, round(q / 100 * (len(values) - 1)))]


class Poller(threading.Thread):
    """``/liveness`` of ``url`` once a second until stopped: the answer times (s) and failures."""

    def __init__(self, url: str):
        super().__init__(daemon=True)
        self.url, self.times, self.failures = url, [], Counter()
        self.done = threading.Event()

    def run(self):
        while not self.done.wait(1.0):
            t, why = probe(self.url)
            if t is None:
                self.failures[why] += 1
            else:
                self.times.append(t)


def measure(name: str, pids: list[int], url: str, routes: bool, n: int, plan: Plan, time_limit: float) -> dict:
    """One configuration: ``n`` sessions on ``url`` served by the processes ``pids``."""
    marks = {}

    def phase(label):
        marks[label] = (sum(cpu_seconds(p) for p in pids), [rss_mb(p) for p in pids], os.getloadavg()[0])

    poller = Poller(url)
    poller.start()
    t0 = time.monotonic()
    outs = run_sessions(url.replace("http://", "ws://") + "ws", n, plan, time_limit, routes=routes, on_phase=phase)
    poller.done.set()
    poller.join(10)
    opens = [o.open_s for o in outs if o.open_s is not None]
    answers = [a for o in outs for a in o.answers]
    answered = [a for a in answers if a is not None]
    r = {"name": name, "n": n, "opens": opens, "errors": Counter(o.error for o in outs if o.error),
         "answered": answered, "unanswered": len(answers) - len(answered),
         "not_made": len([o for o in outs if o.open_s is not None]) * plan.changes - len(answers),
         "dropped": sum(o.dropped for o in outs), "rss": marks["start"][1], "rss_open": marks["opened"][1],
         "rss_end": marks["end"][1], "live": poller.times, "live_failed": poller.failures,
         "load": (marks["start"][2], marks["end"][2]), "seconds": time.monotonic() - t0,
         "pages": [o.page_s for o in outs if o.page_s is not None], "busy": sum(o.busy for o in outs), "busy_sessions": sum(o.busy > 0 for o in outs),
         "busy_reasons": Counter(o.busy_reason for o in outs if o.busy_reason)}
    r["cpu_open_ms"] = 1000 * (marks["opened"][0] - marks["start"][0]) / max(1, len(opens))
    r["cpu_change_ms"] = 1000 * (marks["end"][0] - marks["opened"][0]) / max(1, len(answered))
    return r


def report(r: dict):
    print(f"{r['name']}: {r['n']} sessions, {r['seconds']:.0f} s, load average {r['load'][0]:.2f} → {r['load'][1]:.2f}")
    o = r["opens"]
    if o:
        print(f"  opens        {len(o)}/{r['n']}   p50 {statistics.median(o):6.2f} s   max {max(o):6.2f} s")
    else:
        print(f"  opens        0/{r['n']}")
    if r["pages"]:
        p = r["pages"]
        print(f"  pages served {len(p)}/{r['n']}   p50 {statistics.median(p):6.2f} s   max {max(p):6.2f} s   "
              f"(the session built; opened = its document then pulled by websocket)")
    for reason, count in r["errors"].most_common():
        print(f"  open errors  {count} × {reason}")
    if r["busy"]:
        reason = r["busy_reasons"].most_common(1)[0][0]
        print(f"  busy         {r['busy']} refusals (HTTP 503, {reason!r}) to {r['busy_sessions']} sessions, "
              f"each asked again after its Retry-After, as the refusal's page does")
    waiting = r["n"] - len(o) - sum(r["errors"].values())
    if waiting:
        print(f"  still opening at the time limit (no answer, no refusal): {waiting}")
    a = r["answered"]
    if a:
        print(f"  changes      {len(a)} answered   p50 {statistics.median(a):6.0f} ms   p95 {pct(a, 95):6.0f} ms   "
              f"max {max(a):6.0f} ms")
    print(f"  unanswered   {r['unanswered']}   not made (deadline) {r['not_made']}   dropped sessions {r['dropped']}")
    print(f"  server CPU   per open {r['cpu_open_ms']:6.0f} ms   per change {r['cpu_change_ms']:6.1f} ms")
    rss = "   ".join(f"{a:.0f} → {b:.0f} → {c:.0f}" for a, b, c in zip(r["rss"], r["rss_open"], r["rss_end"],
                                                                       strict=True))
    grown = (sum(r["rss_open"]) - sum(r["rss"])) / max(1, len(o))
    print(f"  RSS MB       idle → opened → end, per process: {rss}   (+{grown:.1f} MB per session opened)")
    live = r["live"]
    failed = ", ".join(f"{n} × {why}" for why, n in r["live_failed"].most_common()) or "none failed"
    print(f"  /liveness    {len(live)} answered (max {max(live, default=0):.2f} s); {failed}")


def ratios(a: dict, b: dict):
    med = statistics.median
    cells = []
    if a["opens"] and b["opens"]:
        cells.append(f"open p50 {med(a['opens']) / med(b['opens']):5.2f}")
    if a["answered"] and b["answered"]:
        cells += [f"change p50 {med(a['answered']) / med(b['answered']):5.2f}",
                  f"p95 {pct(a['answered'], 95) / pct(b['answered'], 95):5.2f}"]
    if b["cpu_open_ms"] > 0 and b["cpu_change_ms"] > 0:
        cells += [f"CPU per open {a['cpu_open_ms'] / b['cpu_open_ms']:5.2f}",
                  f"per change {a['cpu_change_ms'] / b['cpu_change_ms']:5.2f}"]
    print(f"  {a['name']} / {b['name']}: " + "   ".join(cells))


def floor(page: str, name: str, n: int, plan: Plan, time_limit: float) -> dict:
    proc, url = start_floor(page)
    try:
        return measure(name, [proc.pid], url, False, n, plan, time_limit)
    finally:
        stop(proc)


def explorer(k: int, nginx: bool, n: int, plan: Plan, time_limit: float) -> dict:
    procs, front = [], None
    with tempfile.TemporaryDirectory() as tmp:
        try:
            for _ in range(k):
                procs.append(start_explorer())
            name = f"explorer, {k} process{'es' if k > 1 else ''}"
            if nginx or k > 1:
                front, port = start_nginx([port_of(url) for _, url in procs], Path(tmp))
                url, name = f"http://127.0.0.1:{port}/", name + " behind nginx"
            else:
                url = procs[0][1]
            return measure(name, [p.pid for p, _ in procs], url, front is not None, n, plan, time_limit)
        finally:
            if front is not None:
                stop(front)
            for p, _ in procs:
                stop(p)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sessions", type=int, default=30)
    ap.add_argument("--changes", type=int, default=6, help="per session")
    ap.add_argument("--processes", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--nginx", action="store_true", help="nginx in front of one process too")
    ap.add_argument("--floors", action=argparse.BooleanOptionalAction, default=True)
    ap.add_argument("--time-limit", type=float, default=300.0, help="s per configuration (it stops by itself)")
    ap.add_argument("--open-timeout", type=float, default=20.0, help="s for the websocket handshake (bokeh.client: 20)")
    ap.add_argument("--answer-timeout", type=float, default=30.0)
    a = ap.parse_args(argv)
    if not 1 <= a.sessions <= 200 or not 0 <= a.changes <= 100 or not all(1 <= k <= 8 for k in a.processes):
        sys.exit("load_client: --sessions 1..200, --changes 0..100, --processes 1..8")
    plan = Plan(changes=a.changes, open_timeout=a.open_timeout, answer_timeout=a.answer_timeout)
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}; {a.sessions} sessions × {a.changes} changes")
    results = []
    if a.floors:
        for page, name in (("one", "one-plot floor"), ("five", "five-plot idiom")):
            results.append(floor(page, name, a.sessions, plan, a.time_limit))
            report(results[-1])
    for k in a.processes:
        r = explorer(k, a.nginx, a.sessions, plan, a.time_limit)
        report(r)
        if a.floors:
            for f in results[:2]:
                ratios(r, f)
        results.append(r)


if __name__ == "__main__":
    main()
