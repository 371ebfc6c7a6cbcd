"""A small class at the protocol level (issue #28, part 5): five bokeh.client sessions through
the Debian nginx in front of two `bushing serve` processes, each session opened together with
the others, then moving the drive-amplitude slider three times at a quick pace. Every session
opens, none is dropped, every change is answered by new plot data, both processes hold sessions
and /liveness answers through nginx afterwards. No time is asserted: the waits are generous
bounds, and a run that hits one fails with what had not happened.

The sessions are ``benchmarks/load_session.py``'s, the ones ``benchmarks/load_client.py``
measures with (a browser's as far as the server can tell: Panel's models, ``DocumentReady``,
``TCP_NODELAY``)."""

import signal
import tempfile
from pathlib import Path

import pytest

from benchmarks.load_session import (
    NGINX,
    Plan,
    liveness,
    port_of,
    run_sessions,
    start_explorer,
    start_nginx,
    stop,
)

SESSIONS, CHANGES = 5, 3
TIME_LIMIT_S = 240  # the whole run stops by itself after this, whatever happened


@pytest.fixture
def balanced():
    if NGINX is None:  # fail, never skip: CI installs it (.ci/run)
        pytest.fail("nginx is not installed (apt-get install -y nginx)")
    procs, front = [], None
    with tempfile.TemporaryDirectory() as tmp:
        try:
            for _ in range(2):
                procs.append(start_explorer())
            front, port = start_nginx([port_of(url) for _, url in procs], Path(tmp))
            yield f"http://127.0.0.1:{port}/", [port_of(url) for _, url in procs], Path(tmp) / "access.log", front
        finally:
            if front is not None:
                stop(front)
            for proc, _ in procs:
                stop(proc)


def test_every_change_answered_through_nginx(balanced):
    url, backs, access_log, nginx = balanced
    plan = Plan(changes=CHANGES, pause=(0.2, 0.6), open_timeout=120.0, answer_timeout=60.0, settle_max=20.0)
    outs = run_sessions(url.replace("http://", "ws://") + "ws", SESSIONS, plan, TIME_LIMIT_S, routes=True)
    assert [o.error for o in outs if o.error] == [], "sessions that did not open (or found no slider)"
    assert all(o.open_s is not None for o in outs), f"sessions still opening after {TIME_LIMIT_S} s"
    assert [o.index for o in outs if o.dropped] == [], "sessions the server closed"
    made = {o.index: len(o.answers) for o in outs}
    assert made == dict.fromkeys(range(SESSIONS), CHANGES), f"changes made per session (stopped at {TIME_LIMIT_S} s)"
    unanswered = {o.index: [i for i, a in enumerate(o.answers) if a is None] for o in outs}
    assert unanswered == {i: [] for i in range(SESSIONS)}, "changes with no new plot data within 60 s"
    assert liveness(url, timeout=30) is not None, "/liveness through nginx after the sessions"
    nginx.send_signal(signal.SIGQUIT)  # a graceful stop: each websocket's line is logged when it ends
    assert nginx.wait(30) == 0
    websockets = [line for line in access_log.read_text().splitlines() if "/ws" in line]
    assert len(websockets) == SESSIONS, websockets
    assert all(line.split()[1] == "101" for line in websockets), websockets  # every websocket upgraded
    assert {line.split()[0] for line in websockets} == {f"127.0.0.1:{p}" for p in backs}, websockets  # both used
