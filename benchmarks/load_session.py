"""The protocol-level load client's machinery (``load_client.py`` prints with it; the CI test
``tests/test_load_protocol.py`` drives it): server processes, nginx in front of them, and many
bokeh.client sessions, each in its own thread, that open together and move a slider at a
person's pace.

A session is a browser's as far as the server can tell, in three points:

* ``panel.models`` is imported, so the client's document knows Panel's models;
* once its document has arrived it sends ``DocumentReady``, as a page does once rendered (Panel
  holds back every change to the page until then);
* its socket sends without Nagle's delay (``TCP_NODELAY``, as Chromium's).

A change's answer time is from setting the slider's value in the client's document (which sends
it, as the page does) to the arrival of the first message from the server that changes the data
of a plot (a ``ColumnDataSource``). The client never applies the server's changes to its
document: it reads them, times them and drops them, so that its own decoding takes as little
of the shared CPU as it can. Everything runs on loopback; every wait is bounded.
"""

from __future__ import annotations

import asyncio
import os
import random
import re
import select
import shutil
import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from app_latency import cpu_seconds  # noqa: F401 (the load client's too)

ROOT = HERE.parent
NGINX = shutil.which("nginx") or ("/usr/sbin/nginx" if Path("/usr/sbin/nginx").exists() else None)
SLIDER = "Drive amplitude"
DATA_EVENTS = {"ColumnDataChanged", "ColumnsStreamed", "ColumnsPatched"}
_local = threading.local()  # the route cookie and open timeout of the thread's session


# --- processes -------------------------------------------------------------------------------

def start_printing_url(command: list[str], env: dict | None = None, timeout: float = 120) -> tuple[subprocess.Popen, str]:
    """Start ``command`` (a server that prints its ``http://…/`` URL once listening, on port 0);
    the process and that URL. Its later output is read on and dropped, so its pipe never fills."""
    proc = subprocess.Popen(command, cwd=ROOT, env={**os.environ, **(env or {})}, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    deadline, seen = time.monotonic() + timeout, []
    while time.monotonic() < deadline and proc.poll() is None:
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        line = proc.stdout.readline() if ready else ""
        seen.append(line)
        url = re.search(r"http://[\w.:-]+/", line)
        if url:
            threading.Thread(target=lambda: [None for _ in proc.stdout], daemon=True).start()
            return proc, url.group(0)
    stop(proc)
    raise RuntimeError(f"{' '.join(command[:4])}… printed no URL:\n" + "".join(seen[-20:]))


def start_explorer(env: dict | None = None, address: str = "127.0.0.1") -> tuple[subprocess.Popen, str]:
    """``bushing serve --port 0 --address ADDRESS`` from this tree (another loopback address,
    127.0.0.2 …, stands in for another host)."""
    return start_printing_url([sys.executable, "-m", "cli.main", "serve", "--port", "0", "--address", address], env)


def start_floor(page: str) -> tuple[subprocess.Popen, str]:
    """A floor page of ``load_floors.py`` ("one" or "five") in its own process."""
    return start_printing_url([sys.executable, str(HERE / "load_floors.py"), page])


def stop(proc: subprocess.Popen):
    """End a process this module started: terminate, then kill after 10 s."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


def start_nginx(backends: list[int | str], workdir: Path) -> tuple[subprocess.Popen, int]:
    """The Debian nginx with ``deploy/nginx.conf.template`` in front of ``backends`` (ports on
    127.0.0.1, or ``host:port``): the process and its port. It inherits a socket bound at a port the OS picked
    (as tests/test_nginx.py does); sticky by the ``bushing_route`` cookie."""
    from app.deploy import nginx_config

    if NGINX is None:
        raise RuntimeError("nginx is not installed (apt-get install -y nginx)")
    front = socket.socket()
    front.bind(("127.0.0.1", 0))
    front.listen(512)
    port = front.getsockname()[1]
    (workdir / "nginx.conf").write_text(nginx_config(port, backends, workdir))
    proc = subprocess.Popen([NGINX, "-c", str(workdir / "nginx.conf"), "-p", str(workdir), "-g", "daemon off;"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, pass_fds=[front.fileno()],
                            env={**os.environ, "NGINX": f"{front.fileno()};"})
    front.close()
    return proc, port


def port_of(url: str) -> int:
    return int(re.search(r":(\d+)/", url).group(1))


def address_of(url: str) -> str:
    """``host:port`` of a server's ``http://host:port/`` URL."""
    return re.search(r"//([^/]+)/", url).group(1)


def rss_mb(pid: int) -> float:
    """Resident memory of process ``pid`` in MB (``VmRSS`` of ``/proc/PID/status``), 0 if gone."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def liveness(url: str, timeout: float = 5.0) -> float | None:
    """Seconds ``url``'s ``/liveness`` took to answer 200, or None (refused, error or timeout)."""
    return probe(url, timeout)[0]


def probe(url: str, timeout: float = 5.0) -> tuple[float | None, str | None]:
    """``url``'s ``/liveness``: (seconds to a 200, None) or (None, why not: the status, "timeout",
    "refused" or the error's name)."""
    t0 = time.perf_counter()
    try:
        with urllib.request.urlopen(url.rstrip("/") + "/liveness", timeout=timeout) as r:
            return (time.perf_counter() - t0, None) if r.status == 200 else (None, f"HTTP {r.status}")
    except urllib.error.HTTPError as exc:
        return None, f"HTTP {exc.code}"
    except TimeoutError:
        return None, f"no answer within {timeout:g} s"
    except urllib.error.URLError as exc:
        reason = exc.reason
        if isinstance(reason, (TimeoutError, socket.timeout)):
            return None, f"no answer within {timeout:g} s"
        return None, "refused" if isinstance(reason, ConnectionRefusedError) else type(reason).__name__
    except OSError as exc:
        return None, type(exc).__name__


# --- one session -----------------------------------------------------------------------------

def _install_request():
    """bokeh.client opens its websocket with a bare ``HTTPRequest``; this one carries the
    thread's route cookie (nginx's sticky key) and open timeout."""
    from bokeh.client import connection
    from tornado.httpclient import HTTPRequest

    if getattr(connection.HTTPRequest, "load_client", False):
        return

    class Request(HTTPRequest):
        load_client = True

        def __init__(self, url, **kwargs):
            route, timeout = getattr(_local, "route", None), getattr(_local, "timeout", 20.0)
            headers = {"Cookie": f"bushing_route={route}"} if route else None
            super().__init__(url, headers=headers, connect_timeout=timeout, request_timeout=timeout, **kwargs)

    connection.HTTPRequest = Request


# the modules of panel.models the explorer's and the floors' documents need beyond the package
# itself: not every module, whose models would bring external scripts (KaTeX, deck.gl …) into
# every page the same process serves afterwards (the test suite's own explorer)
PANEL_MODULES = ("panel.models.file_dropper",)


def _import_panel_models():
    """``panel.models`` and :data:`PANEL_MODULES` (imported only by the widget that uses them), so
    the client's document can hold every Panel model of these pages."""
    import importlib

    import panel.models  # noqa: F401

    for name in PANEL_MODULES:
        importlib.import_module(name)


def plot_data(message, sources: set[str]) -> bool:
    """Whether a PATCH-DOC ``message`` changes the data of a plot: a column event, or a new
    ``data`` of a ColumnDataSource (ids in ``sources``; new sources the message defines are added)."""
    found = False
    for event in message.content.get("events", []):
        kind = event.get("kind")
        if kind in DATA_EVENTS:
            found = True
        elif kind == "ModelChanged":
            if event.get("attr") == "data" and (event.get("model") or {}).get("id") in sources:
                found = True
            else:
                _collect_sources(event.get("new"), sources)
        elif kind == "RootAdded":
            _collect_sources(event.get("model"), sources)
    return found


def _collect_sources(value, sources: set[str], depth: int = 0):
    if depth > 40:
        return
    if isinstance(value, dict):
        if value.get("name") == "ColumnDataSource" and "id" in value:
            sources.add(value["id"])
        for v in value.values():
            _collect_sources(v, sources, depth + 1)
    elif isinstance(value, list):
        for v in value:
            _collect_sources(v, sources, depth + 1)


@dataclass
class Plan:
    """What every session does: ``changes`` moves of the slider, a pause drawn from ``pause``
    (s) before each; a change unanswered after ``answer_timeout`` s counts as unanswered."""
    changes: int = 6
    pause: tuple[float, float] = (1.0, 3.0)
    open_timeout: float = 20.0  # the websocket's handshake (bokeh.client's default)
    page_timeout: float = 120.0  # the page's answer (a browser waits minutes)
    answer_timeout: float = 30.0
    settle: float = 1.0  # after every session has opened: quiet this long before the changes
    settle_max: float = 30.0


@dataclass
class Outcome:
    """What one session saw: open time (s) or the error, each change's answer time (ms) or
    None, whether the server closed it (dropped), and messages read."""
    index: int
    open_s: float | None = None
    error: str | None = None
    answers: list = field(default_factory=list)
    dropped: bool = False
    messages: int = 0
    page_s: float | None = None  # from the start to the page served (its session built)
    busy: int = 0  # "server busy" refusals (HTTP 503) before the page was served
    busy_reason: str | None = None


class Run:
    """Shared clock of one load run: every session opens at ``go``; changes start once every
    session has opened (or failed) and the servers have been quiet ``plan.settle`` s."""

    def __init__(self, n: int, plan: Plan, deadline: float):
        self.plan, self.deadline = plan, deadline
        self.go = threading.Event()
        self.changes_go = threading.Event()
        self.opened = threading.Semaphore(0)
        self.last_message = time.monotonic()
        self.n = n

    def past(self) -> bool:
        return time.monotonic() > self.deadline


class Session(threading.Thread):
    """One bokeh.client session on ``ws_url`` in its own thread and IOLoop."""

    def __init__(self, index: int, ws_url: str, route: str | None, run: Run, seed: int):
        super().__init__(daemon=True, name=f"load-session-{index}")
        self.ws_url, self.route, self.run_ = ws_url, route, run
        self.rng = random.Random(seed)
        self.out = Outcome(index)
        self.sources: set[str] = set()
        self._pending: float | None = None  # perf_counter when the change in flight was set
        self._answer: float | None = None
        self._closing = False
        self._counted = False  # the run's count of sessions opened or refused has this one

    def _count(self):
        """Once: this session has opened, failed or been refused as busy (the changes start when
        every session has; a refused one keeps asking, as its page does, and drives if let in)."""
        if not self._counted:
            self._counted = True
            self.run_.opened.release()

    def run(self):
        try:
            self._open_and_drive()
        except Exception as exc:  # noqa: BLE001 - any failure is this session's outcome, reported
            if self.out.open_s is None and self.out.error is None:
                self.out.error = f"{type(exc).__name__}: {exc}"[:160]
        finally:
            self._count()

    def _open_and_drive(self):
        from bokeh.client import ClientSession

        _import_panel_models()
        _install_request()
        _local.route, _local.timeout = self.route, self.run_.plan.open_timeout
        self.run_.go.wait()
        t0 = time.perf_counter()
        try:
            session_id = self._page()
            self.out.page_s = time.perf_counter() - t0
        except Exception as exc:  # noqa: BLE001 - refused, timed out: the reason is reported
            self.out.error = f"page: {type(exc).__name__}: {exc}"[:160]
            return
        session = ClientSession(session_id=session_id, websocket_url=self.ws_url)
        try:
            session.pull()
        except Exception as exc:  # noqa: BLE001 - refused, timed out, closed: the reason is reported
            detail = session._connection.error_detail if session._connection else ""
            code = session._connection.error_code if session._connection else None
            self.out.error = f"{type(exc).__name__}: {code or ''} {detail or exc}".strip()[:160]
            return
        self.out.open_s = time.perf_counter() - t0
        self._count()
        doc, conn = session.document, session._connection
        conn._socket._socket.protocol.set_nodelay(True)  # as a browser: every frame sent at once
        for m in doc.models:
            if type(m).__name__ == "ColumnDataSource":
                self.sources.add(m.id)
        slider = next((m for m in doc.models if isinstance(getattr(m, "title", None), str)
                       and m.title.startswith(SLIDER) and "start" in m.properties()), None)
        try:
            conn.io_loop.run_sync(lambda: self._life(session, slider))
        finally:
            conn.io_loop.close(all_fds=True)

    def _page(self) -> str:
        """The page, asked for as a browser does (the server builds the session for it): its
        session id. A "busy" refusal (HTTP 503) is asked again after its ``Retry-After``, as the
        refusal's page does by itself, until the run's time limit."""
        from bokeh.util.token import get_session_id

        url = "http" + self.ws_url[len("ws"):-len("ws")]
        headers = {"Cookie": f"bushing_route={self.route}"} if self.route else {}
        while True:
            try:
                request = urllib.request.Request(url, headers=headers)
                with urllib.request.urlopen(request, timeout=self.run_.plan.page_timeout) as r:
                    page = r.read().decode("utf-8", "replace")
                break
            except urllib.error.HTTPError as exc:
                body = exc.read().decode("utf-8", "replace")
                if exc.code != 503:
                    raise
                if self.run_.past():
                    raise TimeoutError("refused as busy until the time limit") from None
                self.out.busy += 1
                self._count()
                self.out.busy_reason = re.search(r"<h1>(.*?)</h1>", body).group(1) if "<h1>" in body else body[:80]
                wait = min(30.0, float(exc.headers.get("Retry-After") or 5))
                time.sleep(max(0.0, min(wait, self.run_.deadline - time.monotonic())))
        token = re.search(r'"token":\s*"([^"]+)"', page)
        if token is None:
            raise RuntimeError("no session token in the page")
        return get_session_id(token.group(1))

    async def _life(self, session, slider):
        from bokeh.events import DocumentReady

        conn, plan = session._connection, self.run_.plan
        reader = asyncio.ensure_future(self._read(conn))
        session.document.callbacks.send_event(DocumentReady())  # what a page sends once rendered
        while not self.run_.changes_go.is_set() and not self.run_.past() and not reader.done():
            await asyncio.sleep(0.02)
        if slider is None:
            self.out.error = f"no slider titled {SLIDER!r} in the document"
        else:
            last = slider.value
            for _ in range(plan.changes):
                await self._wait(lambda: False, self.rng.uniform(*plan.pause), reader)
                if reader.done() or self.run_.past():
                    break
                value = last
                while abs(value - last) < 0.02:
                    value = round(slider.start + (0.25 + 0.5 * self.rng.random()) * (slider.end - slider.start), 3)
                last = value
                self._answer, self._pending = None, time.perf_counter()
                slider.value = value  # sent to the server as the page's slider sends it
                await self._wait(lambda: self._answer is not None, plan.answer_timeout, reader)
                self.out.answers.append(None if self._answer is None else 1000 * (self._answer - self._pending))
                self._pending = None
        self._closing = True
        if conn._socket is not None:
            conn._socket.close(1000, "done")
        reader.cancel()

    async def _wait(self, condition, seconds: float, reader):
        end = time.monotonic() + seconds
        while not condition() and time.monotonic() < end and not reader.done() and not self.run_.past():
            await asyncio.sleep(0.005)

    async def _read(self, conn):
        while (message := await conn._pop_message()) is not None:
            now = time.perf_counter()
            self.out.messages += 1
            self.run_.last_message = time.monotonic()
            data = message.msgtype == "PATCH-DOC" and plot_data(message, self.sources)  # new sources learnt
            if data and self._pending is not None and self._answer is None:
                self._answer = now
        if not self._closing:
            self.out.dropped = True


def run_sessions(ws_url: str, n: int, plan: Plan, time_limit: float, routes: bool = False,
                 on_phase=None) -> list[Outcome]:
    """``n`` sessions on ``ws_url`` opened together, then each making ``plan.changes`` changes;
    ``routes`` gives each its own route cookie (sticky sessions through nginx). ``on_phase(name)``
    is called at "start", "opened" (every session opened or failed, then quiet) and "end".
    Stops by itself after ``time_limit`` s: what has not happened by then is reported unanswered."""
    run = Run(n, plan, time.monotonic() + time_limit)
    sessions = [Session(i, ws_url, f"route-{i}" if routes else None, run, seed=i) for i in range(n)]
    for s in sessions:
        s.start()
    if on_phase:
        on_phase("start")
    run.go.set()
    for _ in range(n):
        run.opened.acquire(timeout=max(0.0, run.deadline - time.monotonic()))
    quiet_until = time.monotonic() + plan.settle_max
    while time.monotonic() < min(quiet_until, run.deadline) and time.monotonic() - run.last_message < plan.settle:
        time.sleep(0.05)
    if on_phase:
        on_phase("opened")
    run.changes_go.set()
    for s in sessions:  # each has stopped by the deadline; 5 s more to close
        s.join(max(0.0, run.deadline + 5 - time.monotonic()))
    if on_phase:
        on_phase("end")
    return [s.out for s in sessions]
