"""Long work off the event loop, with its progress on the page (issue #27, item 12).

A button that starts work taking over half a second (the diagnosis, *Find designs*) runs it with
:func:`in_thread`: the work runs in a worker thread (the page stays responsive), reports its
progress through a ``say(fraction, message)`` callback, and the event loop shows the latest
report every :data:`PROGRESS_POLL_S` seconds. The caller then shows the result in one push
(``pn.io.hold()``) with the progress hidden, so that the page never shows a finished progress
without its result.

A page closed during the work: its session's connection is gone, or the session discarded. Then
nothing more is written to its document (:func:`page_open`): no progress, no result. A write to
a socket that has closed is what logged ``WebSocketClosedError`` (issue #27, item 15). A page can
still close while a message is being written to it (a group of the report's plots made while the
work runs, half a second of the event loop during which the page's close is not read): the
failed writes then go nowhere, quietly (:func:`quiet_closed_writes`).

No Panel import: the states (:mod:`app.targets_form`) use it too; the views pass the document.

**Work in another process.** A worker thread shares the server's interpreter lock: while one
page's diagnosis computes, every other page's changes wait for their turn at it. A served
explorer therefore runs a :class:`Task` (a module-level function and its arguments, which can be
sent to another process) in a pool of worker processes (:func:`use_processes`, called by
:func:`app.main.serve`; ``BUSHING_WORKERS`` processes, 1 by default): the event loop keeps its core,
and the work gets its own. The workers are forked from a server process that has imported the
core (``forkserver``, preloaded), started when the explorer starts, so that the first task pays
no import. A task's progress comes back through one queue, and is shown as a thread's is. An
in-process server (the tests', a notebook's) runs tasks in a thread, as before.

**Work started ahead.** Work a page will most likely ask for next (the diagnosis of data just
loaded) can start before the click (:func:`start_ahead`), in a worker that nothing else uses; the
click then takes it over if it is the same work (:func:`claim`), or cancels it. Work started ahead
gives way to work asked for: it starts only on an idle worker, and work asked for while every
worker is busy cancels it, which then waits until the worker stops it at its next progress report
(:class:`Cancelled`; ``benchmarks/ahead_cancel.py``: 0.06-0.08 s median, 0.36 s at most).
"""

from __future__ import annotations

import asyncio
import atexit
import itertools
import logging
import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from typing import Any

import numpy as np

log = logging.getLogger("bushing.app")

WATCH_S = 1.0  # s between a worker's two looks at its server (ended when it is gone)
PROGRESS_POLL_S = 0.15  # s between two progress updates on the page
# s before each step done on the event loop while the work runs (in_thread's ``meanwhile``): the
# loop writes the page's messages meanwhile (the progress set at a click can wait for the server's
# answer to the click to be written first: a few turns of the loop, measured 10-25 ms)
STEP_GAP_S = 0.03

Say = Callable[[float, str], None]


@dataclass(frozen=True)
class Task:
    """Work that can run in another process: ``function(*args, progress=say, **kwargs)``, the
    function defined at a module's top level, the arguments plain data (designs, measured data)."""

    function: Callable
    args: tuple = ()
    kwargs: dict = field(default_factory=dict)

    def __call__(self, say: Say | None = None) -> Any:
        return self.function(*self.args, progress=say, **self.kwargs)


# --- the worker processes ---------------------------------------------------------------------

PRELOAD = ["core.identify.diagnose", "core.identify.fit"]  # imported once, in the fork server
_pool: ProcessPoolExecutor | None = None
_pool_lock = threading.Lock()
_progress: dict[int, list] = {}  # task id → the latest [fraction, message] of a running task
_ids = itertools.count(1)
relayed = 0  # progress reports received from the worker processes (tests count them)
_queue = None  # the workers' progress queue (the parent's end)
_worker_queue = None  # in a worker: the same queue
_size = 0  # the pool's worker processes
_running: set = set()  # the pool's futures not yet done (work running or waiting)
_ahead: list = []  # the work started ahead (Started) and running, not yet claimed nor cancelled, oldest first
CANCEL_SLOTS = 64  # work started ahead and cancelled: its id at [id % CANCEL_SLOTS] of the shared array
_cancelled = None  # shared with the workers: the ids of work started ahead no longer wanted
_worker_cancelled = None  # in a worker: the same value


def workers() -> int:
    """How many worker processes: ``BUSHING_WORKERS`` (1–64), 1 if unset or not a whole number."""
    text = os.environ.get("BUSHING_WORKERS", "1").strip()
    return min(64, max(1, int(text))) if text.isdigit() else 1


def use_processes(count: int | None = None) -> None:
    """Run :class:`Task` work in ``count`` worker processes (:func:`workers` if None) from now on,
    and start them (a no-op task each), so that the first page's work does not wait for them."""
    global _pool, _queue, _size, _cancelled
    with _pool_lock:
        if _pool is not None:
            return
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(PRELOAD)
        _queue, _size, _cancelled = context.Queue(), count or workers(), context.RawArray("q", CANCEL_SLOTS)
        _pool = ProcessPoolExecutor(max_workers=_size, mp_context=context,
                                    initializer=_start_worker, initargs=(_queue, _cancelled, os.getpid()))
        threading.Thread(target=_relay, args=(_queue,), name="work-progress", daemon=True).start()
        for _ in range(_size):
            _pool.submit(int)
    atexit.register(stop_processes)


def stop_processes() -> None:
    """Stop the worker processes (work not started is cancelled); tasks run in threads again."""
    global _pool
    with _pool_lock:
        pool, _pool = _pool, None
        _ahead.clear()
    if pool is not None:
        pool.shutdown(wait=True, cancel_futures=True)


def _start_worker(queue, cancelled, server: int) -> None:
    global _worker_queue, _worker_cancelled
    _worker_queue, _worker_cancelled = queue, cancelled
    threading.Thread(target=_watch_server, args=(server,), name="watch-server", daemon=True).start()


def _watch_server(server: int) -> None:
    """In a worker: end the process once the server that started it is gone. A server killed
    outright (SIGKILL, the kernel's out-of-memory killer) stops nothing: its worker held the
    pipes by which the forkserver and the resource tracker would see their parent gone, so all
    three ran on, orphaned; the worker gone, they see it and end too."""
    while True:
        time.sleep(WATCH_S)
        if _gone(server):
            os._exit(0)


def _gone(pid: int) -> bool:
    """Whether process ``pid`` has ended (or is a zombie that nothing has reaped yet)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OSError:
        return False  # it exists (owned by another user: not ours to signal, but alive)
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] == "Z"
    except (OSError, IndexError):
        return False  # no /proc: the signal's answer stands


def _relay(queue) -> None:
    """In the server: every progress report of the workers into its task's slot."""
    while True:
        try:
            task_id, fraction, message = queue.get()
        except (EOFError, OSError, ValueError):
            return
        global relayed
        relayed += 1
        slot = _progress.get(task_id)
        if slot is not None:
            slot[:] = [fraction, message]


def _run_task(task_id: int, task: Task) -> Any:
    """In a worker: ``task``, its progress sent to the server with ``task_id``."""
    def say(fraction: float, message: str):
        if _worker_cancelled is not None and _worker_cancelled[task_id % CANCEL_SLOTS] == task_id:
            raise Cancelled
        _worker_queue.put((task_id, float(fraction), str(message)))

    return task(say)


class Cancelled(BaseException):
    """In a worker: the work started ahead is no longer wanted (:func:`cancel`). Not an
    :class:`Exception`: no ``except Exception`` of the work catches it."""


@dataclass(eq=False)
class Started:
    """Work started ahead (:func:`start_ahead`): its task, the pool's future, its id, the latest
    progress the worker reported ([fraction, message], empty before the first) and whether it
    was cancelled. Its result is held by whoever holds it (the page that loaded the data), not
    here: work that ended unclaimed is forgotten with its page."""

    task: Task
    future: Any
    task_id: int
    latest: list
    cancelled: bool = False


def _ended(started: Started) -> None:
    """``started`` has ended: nothing left to cancel, no progress to relay (a click that takes it
    over later reads its last progress from it)."""
    _forget(started)
    _progress.pop(started.task_id, None)


def _forget(started: Started) -> None:
    """``started`` no longer among the work that other work may cancel."""
    try:
        _ahead.remove(started)
    except ValueError:
        pass  # claimed, cancelled or ended already


def _pooled(pool, task: Task, latest: list):
    """``task`` submitted to the pool, its progress into ``latest``: the pool's future and its id."""
    task_id = next(_ids)
    _progress[task_id] = latest
    try:
        future = pool.submit(_run_task, task_id, task)
    except BrokenProcessPool:
        _progress.pop(task_id, None)
        raise
    _running.add(future)
    future.add_done_callback(_running.discard)
    return future, task_id


def start_ahead(task: Task) -> Started | None:
    """``task`` started now in a worker process, before it is asked for, if the processes are on
    and a worker is idle (None otherwise, or if the pool is broken): :func:`claim` takes it over,
    or :func:`cancel` stops it."""
    pool = _pool
    if pool is None or len(_running) >= _size:
        return None
    latest: list = []
    try:
        future, task_id = _pooled(pool, task, latest)
    except BrokenProcessPool:
        return None
    started = Started(task, future, task_id, latest)
    _ahead.append(started)
    future.add_done_callback(lambda _future: _ended(started))
    return started


def cancel(started: Started | None) -> None:
    """The work ``started`` ahead no longer wanted: not started if it waits, stopped by its worker
    at its next progress report if it runs (its progress is no longer relayed)."""
    if started is None:
        return
    started.cancelled = True
    _forget(started)
    if not started.future.cancel() and _cancelled is not None:
        _cancelled[started.task_id % CANCEL_SLOTS] = started.task_id
    _progress.pop(started.task_id, None)


def same_work(a: Task, b: Task) -> bool:
    """Whether two tasks are the same work: the same function, each argument the same object or
    an equal one, the same keyword arguments."""
    def same(x, y) -> bool:
        try:
            return x is y or bool(x == y)
        except (TypeError, ValueError):  # arrays and the like: only the same object is the same
            return False

    return (a.function is b.function and len(a.args) == len(b.args) and all(map(same, a.args, b.args))
            and a.kwargs.keys() == b.kwargs.keys() and all(same(a.kwargs[k], b.kwargs[k]) for k in a.kwargs))


def claim(started: Started | None, task: Task) -> Started | Task:
    """What to run for ``task``: the work ``started`` ahead if it is that same task and was not
    cancelled (it is then no longer cancelled by other work), else ``task`` (``started`` cancelled)."""
    if (started is not None and not started.cancelled and not started.future.cancelled()
            and same_work(started.task, task)):
        _forget(started)
        return started
    cancel(started)
    return task


def _submit(work, latest: list):
    """``work`` started: in a worker process if it is a :class:`Task` and the processes are on,
    else in a thread (a :class:`Started` goes on where it is); a future, and the id whose
    progress ``latest`` receives (or None). Work started ahead that holds the last idle worker is
    cancelled for it."""
    if isinstance(work, Started):
        latest[:] = work.latest
        _progress[work.task_id] = latest
        return asyncio.wrap_future(work.future), work.task_id
    pool = _pool
    if isinstance(work, Task) and pool is not None:
        if _ahead and len(_running) >= _size:
            cancel(_ahead[0])
        try:
            future, task_id = _pooled(pool, work, latest)
            return asyncio.wrap_future(future), task_id
        except BrokenProcessPool:
            _reset_broken(pool)

    def say(fraction: float, message: str):
        latest[:] = [fraction, message]

    return asyncio.ensure_future(asyncio.to_thread(work, say)), None


def _reset_broken(pool) -> None:
    """A worker died (killed, out of memory): the pool is replaced by a new one."""
    global _pool
    log.warning("a worker process stopped; starting new ones")
    with _pool_lock:
        if _pool is pool:
            _pool = None
    pool.shutdown(wait=False, cancel_futures=True)
    use_processes()


class PageClosed(Exception):
    """The page that asked for the work closed before it ended."""


def _unretrieved_closed_write(context: dict) -> bool:
    """Whether an event loop's error ``context`` is a failed write to a websocket that closed,
    which nobody awaited (Panel writes a message's parts as separate futures, and drops them
    when one fails)."""
    from tornado.websocket import WebSocketClosedError

    return isinstance(context.get("exception"), WebSocketClosedError) and "never retrieved" in context.get("message", "")


def quiet_closed_writes(loop: asyncio.AbstractEventLoop | None = None) -> None:
    """The event loop (the running one if None) says nothing of a write to a page that has gone
    and that nobody awaited (:func:`_unretrieved_closed_write`): the message was for nobody.
    Every other error goes to the handler it had (asyncio's own by default). Once per loop."""
    if loop is None:
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:
            return  # no event loop runs (a script, a test building a page): nothing is served
    previous = loop.get_exception_handler()
    if getattr(previous, "quiet_closed_writes", False):
        return

    def handler(loop, context):
        if _unretrieved_closed_write(context):
            log.debug("a message to a closed page went nowhere: %s", context.get("message"))
        elif previous is not None:
            previous(loop, context)
        else:
            loop.default_exception_handler(context)

    handler.quiet_closed_writes = True
    loop.set_exception_handler(handler)


def page_open(doc) -> bool:
    """Whether the Bokeh document ``doc`` still has a page to write to: no document or no server
    session (a script, a test without a server) counts as open."""
    context = getattr(doc, "session_context", None)
    if context is None:
        return True
    session = context.session
    return not context.destroyed and (session is None or session.connection_count > 0)


async def in_thread(work: Callable[[Say], Any], show: Callable[[float, str], None] | None = None,
                    doc=None, meanwhile: Iterable[Callable[[], None]] = ()) -> Any:
    """``work(say)`` in a worker thread (a :class:`Task` in a worker process when they are on:
    :func:`use_processes`; work :class:`Started` ahead followed where it runs); while it runs, ``show(fraction, message)`` on the event
    loop with the latest ``say`` (fraction clipped to 0–1), only while the page is open and the
    work is not finishing (a fraction of 1: its result comes next, in the caller's push).
    Returns what ``work`` returns, raises what it raises; :class:`PageClosed` if the page closed
    meanwhile (the result would go nowhere). ``doc``: the page's Bokeh document (``pn.state.curdoc``
    in the view that asks).

    ``meanwhile``: steps for the event loop while the work runs in its worker process (the server's
    other core), each called once the work has started, :data:`STEP_GAP_S` after the previous one
    (the loop writes and reads the page's messages between two steps: what the caller set before
    this call reaches the page before the first step), only while the work runs and the page is
    open. Those left when the work ends or the page closes are not called."""
    latest: list = []  # written by the worker, read here on the event loop
    task, task_id = _submit(work, latest)
    steps = list(meanwhile)
    try:
        shown = None
        while not task.done():
            await asyncio.wait({task}, timeout=STEP_GAP_S if steps else PROGRESS_POLL_S)
            if (show is not None and latest and latest != shown and latest[0] < 1.0 and not task.done()
                    and page_open(doc)):
                shown = list(latest)
                show(float(np.clip(shown[0], 0.0, 1.0)), str(shown[1]))
            if steps and not task.done():
                if page_open(doc):
                    steps.pop(0)()
                else:
                    steps.clear()
    finally:
        _progress.pop(task_id, None)
    if not page_open(doc):
        task.exception()  # retrieved: an error of work whose page has gone is nobody's
        raise PageClosed
    try:
        return task.result()
    except BrokenProcessPool:
        pool = _pool
        if pool is not None:
            _reset_broken(pool)
        raise RuntimeError("its worker process stopped (out of memory?); try again") from None
