"""The server's garbage collection: its start-up objects frozen, its full collections moved to
quiet moments.

:func:`freeze_startup_objects`: what the server holds before its first session (the libraries,
this app's caches) lives as long as the process; frozen (the public ``gc.freeze``), a full
collection no longer examines it.

CPython collects its oldest generation by itself when it has grown by a quarter since the last
such collection (and ten younger collections have run). That collection walks every object the
sessions hold: measured on this server, 0.1 s with two or three pages open, 0.25-0.35 s with
four (with the diagnosis' plots), about 17 ms more per Explorer page held (in process). It runs
inside whatever allocates at that moment: a page being built, a report's plots, a user's change.
In a class of 30 every page waits for it.

:class:`QuietCollector` keeps the same rule, measured on the process' heap: a quarter of growth
of its allocated blocks since the last full collection (``sys.getallocatedblocks``, 0.1 ms with
30 pages open; counting the oldest generation's objects took 55-60 ms then, once a second, and
slowed a class of 30's changes by a half), after ten younger collections. It runs the collection
from the server's event loop, between two messages, when the server process has used less than
:data:`QUIET_SHARE` of a core since it last looked; a collection due for :data:`LATEST_S` without
a quiet moment runs anyway, so memory stays bounded on a server that is never quiet. The younger
generations are collected as before (a few milliseconds each).

No Panel import: the loop is tornado's (the server's), the clock and counters can be given.
"""

from __future__ import annotations

import gc
import logging
import sys
import time
from collections.abc import Callable

log = logging.getLogger("bushing.app")

CHECK_S = 1.0  # s between two looks of the event loop
QUIET_SHARE = 0.25  # of one core, used by the server since the last look: quiet
GROWTH = 0.25  # the heap grown by this share since the last full collection: due (as CPython's rule)
FLOOR = 10_000  # and by at least this many blocks
YOUNGER = 10  # and this many collections of the middle generation since (CPython's threshold)
LATEST_S = 15.0  # a due collection waits at most this long for a quiet moment
NEVER = 1 << 30  # the oldest generation's threshold while the collector runs: CPython never reaches it


def freeze_startup_objects() -> int:
    """The objects the server holds before its first session (the libraries' modules, classes,
    option trees, this app's caches) moved out of the interpreter's cyclic collection (the public
    ``gc.freeze``): they live as long as the process, and a collection of the oldest objects
    no longer examines them all each time. Returns how many objects were frozen."""
    gc.collect()
    gc.freeze()
    return gc.get_freeze_count()


class QuietCollector:
    """Full collections when due (:data:`GROWTH`, :data:`YOUNGER`) and the server is quiet
    (:data:`QUIET_SHARE`), or due for :data:`LATEST_S`. :meth:`look` decides, once per
    :data:`CHECK_S`; :meth:`start` takes the oldest generation from CPython, :meth:`stop` gives it
    back."""

    def __init__(self, *, clock: Callable[[], float] = time.monotonic, cpu: Callable[[], float] = time.process_time,
                 heap: Callable[[], int] = sys.getallocatedblocks,
                 younger: Callable[[], int] = lambda: gc.get_count()[2],
                 collect: Callable[[], object] = gc.collect):
        self.clock, self.cpu, self.heap, self.younger, self.collect = clock, cpu, heap, younger, collect
        self.base = 0  # the heap's allocated blocks after the last full collection
        self.due_since: float | None = None
        self._threshold: tuple[int, int, int] | None = None
        self._rebase = False  # a full collection ran that this collector did not make (Panel's, Bokeh's)
        self._at, self._cpu = clock(), cpu()

    def start(self) -> None:
        """CPython's own full collections off; the heap as it is now is the base."""
        if self._threshold is None:
            self._threshold = gc.get_threshold()
            gc.set_threshold(self._threshold[0], self._threshold[1], NEVER)
            gc.callbacks.append(self._seen)
        self.base = self.heap()
        self._at, self._cpu = self.clock(), self.cpu()

    def stop(self) -> None:
        """CPython's own full collections back, as they were before :meth:`start`."""
        if self._threshold is not None:
            gc.set_threshold(*self._threshold)
            gc.callbacks.remove(self._seen)
            self._threshold = None

    def _seen(self, phase: str, info: dict) -> None:
        if phase == "stop" and info["generation"] == 2:
            self._rebase = True

    def due(self) -> bool:
        """Whether a full collection is due: the heap grown by :data:`GROWTH` (and :data:`FLOOR`
        blocks) since the last one, after :data:`YOUNGER` middle-generation collections."""
        return self.younger() >= YOUNGER and self.heap() > max(self.base * (1 + GROWTH), self.base + FLOOR)

    def look(self) -> bool:
        """One look: collect if due and quiet, or due for too long. True if it collected."""
        now, cpu = self.clock(), self.cpu()
        busy = (cpu - self._cpu) / max(now - self._at, 1e-9)
        self._at, self._cpu = now, cpu
        if self._rebase:
            self.base, self._rebase = self.heap(), False
        if not self.due():
            self.due_since = None
            return False
        if self.due_since is None:
            self.due_since = now
        if busy >= QUIET_SHARE and now - self.due_since < LATEST_S:
            return False
        start = time.perf_counter()
        self.collect()
        pause = time.perf_counter() - start
        self.base, self.due_since, self._rebase = self.heap(), None, False
        self._at, self._cpu = self.clock(), self.cpu()  # the collection's own CPU is not the pages'
        log.debug("full collection at %.0f%% of a core: %.3f s, %d blocks kept", 100 * busy, pause, self.base)
        return True


def collect_when_quiet(start_callback: Callable[[Callable[[], object], float], object]) -> QuietCollector:
    """A started :class:`QuietCollector` whose :meth:`~QuietCollector.look` ``start_callback(look,
    milliseconds)`` calls periodically (tornado's ``PeriodicCallback(look, ms).start()`` on the
    server's loop)."""
    collector = QuietCollector()
    collector.start()
    start_callback(collector.look, CHECK_S * 1000)
    return collector
