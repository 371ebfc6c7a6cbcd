"""Long work off the event loop, with its progress on the page (issue #27, item 12).

A button that starts work taking over half a second (the diagnosis, *Find designs*) runs it with
:func:`in_thread`: the work runs in a worker thread (the page stays responsive), reports its
progress through a ``say(fraction, message)`` callback, and the event loop shows the latest
report every :data:`PROGRESS_POLL_S` seconds. The caller then shows the result in one push
(``pn.io.hold()``) with the progress hidden, so that the page never shows a finished progress
without its result.

A page closed during the work: its session's connection is gone, or the session discarded. Then
nothing more is written to its document (:func:`page_open`): no progress, no result. A write to
a socket that has closed is what logged ``WebSocketClosedError`` (issue #27, item 15).

No Panel import: the states (:mod:`app.targets_form`) use it too; the views pass the document.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

import numpy as np

PROGRESS_POLL_S = 0.15  # s between two progress updates on the page

Say = Callable[[float, str], None]


class PageClosed(Exception):
    """The page that asked for the work closed before it ended."""


def page_open(doc) -> bool:
    """Whether the Bokeh document ``doc`` still has a page to write to: no document or no server
    session (a script, a test without a server) counts as open."""
    context = getattr(doc, "session_context", None)
    if context is None:
        return True
    session = context.session
    return not context.destroyed and (session is None or session.connection_count > 0)


async def in_thread(work: Callable[[Say], Any], show: Callable[[float, str], None] | None = None,
                    doc=None) -> Any:
    """``work(say)`` in a worker thread; while it runs, ``show(fraction, message)`` on the event
    loop with the latest ``say`` (fraction clipped to 0–1), only while the page is open and the
    work is not finishing (a fraction of 1: its result comes next, in the caller's push).
    Returns what ``work`` returns, raises what it raises; :class:`PageClosed` if the page closed
    meanwhile (the result would go nowhere). ``doc``: the page's Bokeh document (``pn.state.curdoc``
    in the view that asks)."""
    latest: list = []  # written by the worker, read here on the event loop

    def say(fraction: float, message: str):
        latest[:] = [fraction, message]

    task = asyncio.ensure_future(asyncio.to_thread(work, say))
    shown = None
    while not task.done():
        await asyncio.wait({task}, timeout=PROGRESS_POLL_S)
        if show is not None and latest and latest != shown and latest[0] < 1.0 and not task.done() and page_open(doc):
            shown = list(latest)
            show(float(np.clip(shown[0], 0.0, 1.0)), str(shown[1]))
    if not page_open(doc):
        task.exception()  # retrieved: an error of work whose page has gone is nobody's
        raise PageClosed
    return task.result()
