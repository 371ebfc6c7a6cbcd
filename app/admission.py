"""How many sessions one server process takes, how it builds their pages, and what a browser is
told beyond that.

A server process builds each new session's page on its one thread, about a second of CPU each
(docs/serving.md). Thirty people opening the explorer together used to be thirty builds run
back to back in one turn of the server's event loop: half a minute in which nothing else was
answered, not the pages already open, not even ``/liveness``. So a process

* builds one page at a time (:data:`BUILDING_AT_ONCE`): the other new pages wait for their
  turn without holding the thread. The next build starts once the page just built has joined
  its session by websocket (or after :data:`JOIN_WAIT_S`), so that pages are built, sent and
  shown in turn, not all at the end of a burst; between two builds the server answers
  everything else that came in (a change in an open page, ``/liveness``);
* takes at most :attr:`Admission.max_sessions` sessions, those open and those waiting to be
  built (their memory and their changes' CPU). A page beyond is refused at once: an HTTP 503
  ("Service Unavailable") with ``Retry-After`` and a page that says the server is busy and
  reloads itself after that delay (drawn from :data:`RETRY_S`, so that refused pages do not all
  come back together). A websocket that would open a new session by itself (``bokeh.client``
  without a page) is refused the same way, before its handshake.

The handlers are Panel's own with that check in front (:class:`AdmittingDocHandler`,
:class:`AdmittingWSHandler`), routed by :func:`app.patches.route_sessions`.
"""

from __future__ import annotations

import asyncio
import html
import random
import weakref
from dataclasses import dataclass

from panel.io.server import DocHandler, WSHandler

MAX_SESSIONS = 40  # per process: docs/serving.md, measured (change p95 and RSS at 30 and 50)
BUILDING_AT_ONCE = 1  # pages built at once; the others wait for their turn
JOIN_WAIT_S = 2.0  # after a build, the next waits (at most this long) for the page's websocket
POLL_S = 0.02
RETRY_S = (5, 15)  # a refused page reloads itself after a delay drawn from this range (s)
BUSY_TITLE = "Bushing Explorer: the server is busy"


@dataclass
class Admission:
    """One process's limit and the pages it is building or about to build.

    Attributes
    ----------
    max_sessions : int
        Sessions the process takes: those open and those waiting to be built; a new one beyond
        is refused.
    opening : int
        Pages being built or waiting for their turn now.
    refused : int
        Pages and websockets refused since the start.
    """

    max_sessions: int = MAX_SESSIONS
    opening: int = 0
    refused: int = 0

    def __post_init__(self):
        value = self.max_sessions
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"max_sessions: a whole number of at least 1, got {value!r}")

    def refusal(self, live: int) -> str | None:
        """Why a new session is refused with ``live`` sessions held (and :attr:`opening` pages
        on their way), or None if it is taken."""
        held = live + self.opening
        if held >= self.max_sessions:
            waiting = f", {self.opening} of them opening now" if self.opening else ""
            return (f"This server holds {held} sessions{waiting}, the most it takes "
                    f"({self.max_sessions}), so that each one keeps answering at once.")
        return None


def busy_page(reason: str, retry_s: int) -> str:
    """The HTML of a refusal: the server is busy, why, and a reload after ``retry_s`` seconds."""
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta http-equiv="refresh" content="{retry_s}">
<title>{BUSY_TITLE}</title></head>
<body style="font-family: sans-serif; max-width: 40em; margin: 4em auto">
<h1>The server is busy</h1>
<p>{html.escape(reason)}</p>
<p>This page tries again by itself in {retry_s} s. If it keeps coming back, the class or team
needs more server processes (docs/serving.md in the explorer's repository).</p>
</body></html>"""


ADMISSION = Admission()  # the process's; app.main.serve sets its limit
_turns: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # event loop → its builds' semaphore


def _turn() -> asyncio.Semaphore:
    """The running event loop's semaphore of page builds (a semaphore belongs to one loop)."""
    loop = asyncio.get_running_loop()
    if loop not in _turns:
        _turns[loop] = asyncio.Semaphore(BUILDING_AT_ONCE)
    return _turns[loop]


def _refuse(handler, reason: str) -> None:
    ADMISSION.refused += 1
    retry = random.randint(*RETRY_S)
    handler.set_status(503)
    handler.set_header("Retry-After", str(retry))
    handler.set_header("Cache-Control", "no-store")
    handler.set_header("Content-Type", "text/html; charset=utf-8")
    handler.finish(busy_page(reason, retry))


class AdmittingDocHandler(DocHandler):
    """Panel's page handler, behind :data:`ADMISSION`: one page built at a time, a page beyond
    the sessions taken refused."""

    async def get(self, *args, **kwargs):
        reason = ADMISSION.refusal(len(self.application_context.sessions))
        if reason is not None:
            _refuse(self, reason)
            return
        ADMISSION.opening += 1
        counted, self._session = True, None
        try:
            async with _turn():
                try:
                    await super().get(*args, **kwargs)
                finally:  # built (or failed): a session held now, no longer one opening
                    ADMISSION.opening -= 1
                    counted = False
                _finish(self)  # the page is sent now, not after the wait below
                await _joined(self._session)
        finally:
            if counted:  # given up while waiting for its turn
                ADMISSION.opening -= 1

    async def get_session(self):
        self._session = await super().get_session()
        return self._session


def _finish(handler) -> None:
    """Send ``handler``'s answer now (tornado sends it when the handler returns otherwise)."""
    try:
        handler.finish()
    except RuntimeError:  # already finished (a redirect, a refusal)
        pass


async def _joined(session) -> None:
    """Until ``session``'s page has connected its websocket, at most :data:`JOIN_WAIT_S`."""
    waited = 0.0
    while session is not None and session.connection_count == 0 and waited < JOIN_WAIT_S:
        await asyncio.sleep(POLL_S)
        waited += POLL_S


class AdmittingWSHandler(WSHandler):
    """Panel's websocket handler, behind :data:`ADMISSION`: a websocket that would open a new
    session beyond its limits is refused before its handshake (a page's own websocket joins
    the session its page opened, and is always taken)."""

    async def prepare(self):
        await super().prepare()
        if self.current_user is None:
            return  # Panel's own refusal (403) has answered
        session_id = _session_id(self.request.headers.get("Sec-WebSocket-Protocol", ""))
        known = {s.id for s in self.application_context.sessions}
        if session_id not in known:
            reason = ADMISSION.refusal(len(known))
            if reason is not None:
                _refuse(self, reason)


def _session_id(protocols: str) -> str | None:
    """The session id in a Bokeh websocket's subprotocols (``bokeh, TOKEN``), or None."""
    from bokeh.util.token import get_session_id

    parts = [p.strip() for p in protocols.split(",")]
    if len(parts) != 2 or parts[0] != "bokeh":
        return None
    try:
        return get_session_id(parts[1])
    except Exception:  # noqa: BLE001 - a malformed token: Bokeh's own handshake refuses it
        return None
