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

from app.deploy import nginx_config
from benchmarks.load_session import (
    NGINX,
    Plan,
    address_of,
    liveness,
    run_sessions,
    start_explorer,
    start_nginx,
    stop,
)

SESSIONS, CHANGES = 5, 3
TIME_LIMIT_S = 240  # the whole run stops by itself after this, whatever happened


def behind_nginx(addresses: list[str]):
    """``bushing serve`` processes on ``addresses`` (one each; other loopback addresses stand in
    for other hosts) and the Debian nginx in front of them on 127.0.0.1: yields nginx's URL, the
    processes' ``host:port``, nginx's access log and its process."""
    if NGINX is None:  # fail, never skip: CI installs it (.ci/run)
        pytest.fail("nginx is not installed (apt-get install -y nginx)")
    procs, front = [], None
    with tempfile.TemporaryDirectory() as tmp:
        try:
            for address in addresses:
                procs.append(start_explorer(address=address))
            backs = [address_of(url) for _, url in procs]
            front, port = start_nginx(backs, Path(tmp))
            yield f"http://127.0.0.1:{port}/", backs, Path(tmp) / "access.log", front
        finally:
            if front is not None:
                stop(front)
            for proc, _ in procs:
                stop(proc)


@pytest.fixture
def balanced():
    """Two processes on this host (the configuration of deploy/nginx.conf.template)."""
    yield from behind_nginx(["127.0.0.1", "127.0.0.1"])


@pytest.fixture
def hosts():
    """Two processes on two "hosts": 127.0.0.2 and 127.0.0.3 (loopback addresses standing in for
    machines; nginx reaches them as it would reach other machines' addresses)."""
    yield from behind_nginx(["127.0.0.2", "127.0.0.3"])


def websocket_lines(nginx, access_log: Path) -> list[str]:
    """The access log's websocket lines, after a graceful stop of nginx (each websocket's line
    is logged when it ends)."""
    nginx.send_signal(signal.SIGQUIT)
    assert nginx.wait(30) == 0
    return [line for line in access_log.read_text().splitlines() if "/ws" in line]


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
    websockets = websocket_lines(nginx, access_log)
    assert len(websockets) == SESSIONS, websockets
    assert all(line.split()[1] == "101" for line in websockets), websockets  # every websocket upgraded
    assert {line.split()[0] for line in websockets} == set(backs), websockets  # both used


def test_sessions_spread_over_hosts(hosts):
    """The multi-host configuration (docs/serving.md, ``python -m app.deploy``): nginx in front of
    processes on other hosts' addresses. Four sessions each open on one of the hosts, change the
    amplitude once and are answered; both hosts hold sessions."""
    url, backs, access_log, nginx = hosts
    assert {b.rsplit(":", 1)[0] for b in backs} == {"127.0.0.2", "127.0.0.3"}
    plan = Plan(changes=1, pause=(0.2, 0.4), open_timeout=120.0, answer_timeout=60.0, settle_max=20.0)
    outs = run_sessions(url.replace("http://", "ws://") + "ws", 4, plan, TIME_LIMIT_S, routes=True)
    assert [o.error for o in outs if o.error] == [] and all(o.open_s is not None for o in outs)
    assert [o.index for o in outs if o.dropped] == []
    assert [a for o in outs for a in o.answers] != [] and None not in [a for o in outs for a in o.answers]
    websockets = websocket_lines(nginx, access_log)
    assert {line.split()[0] for line in websockets} == set(backs), websockets  # both hosts used


def test_the_multi_host_configuration_names_every_host(tmp_path):
    """``python -m app.deploy`` writes the configuration the test above runs for any hosts: every
    backend a ``server`` line of the sticky upstream, the listen address as asked; a malformed
    backend is refused in one line."""
    from app.deploy import main

    text = nginx_config(80, ["10.0.0.11:5006", "10.0.0.12:5006", 5007], tmp_path, host="0.0.0.0")
    upstream = text[text.index("upstream bushing {"):text.index("}", text.index("upstream bushing {"))]
    assert "hash $route;" in upstream
    assert [line.strip() for line in upstream.splitlines() if line.strip().startswith("server ")] == [
        "server 10.0.0.11:5006;", "server 10.0.0.12:5006;", "server 127.0.0.1:5007;"]
    assert "listen 0.0.0.0:80;" in text
    for bad in ("10.0.0.11", "10.0.0.11:0", "host;evil:80", ":5006"):
        with pytest.raises(ValueError, match="backend"):
            nginx_config(80, [bad], tmp_path)
    assert main(["--backend", "nohost"]) == 2
