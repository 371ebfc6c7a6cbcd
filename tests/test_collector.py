"""The server's full garbage collections at quiet moments (app.collector)."""

from __future__ import annotations

import gc
import sys
import weakref

import pytest

from app import collector
from app.collector import FLOOR, GROWTH, LATEST_S, NEVER, QUIET_SHARE, YOUNGER, QuietCollector


class Machine:
    """A clock, the server's CPU, the heap's allocated blocks and the collections since the last
    full one, set by the test; the collections asked for, counted."""

    def __init__(self, blocks=100_000):
        self.now, self.used, self.size, self.younger, self.collected = 0.0, 0.0, blocks, 0, 0

    def collect(self):
        self.collected += 1
        self.size, self.younger = int(self.size * 0.9), 0  # some garbage freed

    def collector(self) -> QuietCollector:
        return QuietCollector(clock=lambda: self.now, cpu=lambda: self.used, heap=lambda: self.size,
                              younger=lambda: self.younger, collect=self.collect)

    def wait(self, seconds: float, share: float):
        """``seconds`` pass, the server using ``share`` of a core meanwhile."""
        self.now += seconds
        self.used += share * seconds


@pytest.fixture
def machine():
    return Machine()


@pytest.fixture
def started(machine):
    quiet = machine.collector()
    quiet.start()
    yield quiet
    quiet.stop()


def grow(machine):
    """The heap past the rule: a quarter more, after enough younger collections."""
    machine.size = int(machine.size * (1 + GROWTH)) + FLOOR + 1
    machine.younger = YOUNGER


def test_nothing_is_collected_before_cpythons_own_rule_would(machine, started):
    machine.wait(1, 0.0)
    assert not started.look()
    machine.size = int(100_000 * (1 + GROWTH)) - 1  # not a quarter more
    machine.younger = YOUNGER
    machine.wait(1, 0.0)
    assert not started.look()
    machine.size, machine.younger = 200_000, YOUNGER - 1  # grown, but too few younger collections
    machine.wait(1, 0.0)
    assert not started.look() and machine.collected == 0


def test_a_due_collection_waits_while_the_server_works_and_runs_when_it_is_quiet(machine, started):
    grow(machine)
    for _ in range(5):
        machine.wait(1, QUIET_SHARE + 0.1)  # pages being built, plots made
        assert not started.look()
    assert machine.collected == 0 and started.due_since is not None
    machine.wait(1, QUIET_SHARE - 0.1)
    assert started.look() and machine.collected == 1
    assert started.base == machine.size and started.due_since is None


def test_a_server_never_quiet_still_collects_within_the_latest_delay(machine, started):
    grow(machine)
    waited = 0
    while True:
        machine.wait(1, 1.0)
        waited += 1
        if started.look():
            break
        assert waited <= LATEST_S + 1
    assert machine.collected == 1 and LATEST_S - 1 <= waited <= LATEST_S + 1


def test_the_collectors_own_work_is_not_counted_as_the_servers(machine, started):
    """After a collection the next look measures the pages' work since, not the collection's."""
    grow(machine)
    machine.wait(1, 0.0)
    original = machine.collect

    def slow_collect():
        original()
        machine.wait(0.5, 1.0)  # the collection itself keeps a core busy

    started.collect = slow_collect
    assert started.look()
    grow(machine)
    machine.wait(1, 0.0)
    assert started.look()


def test_start_takes_the_oldest_generation_from_cpython_and_stop_gives_it_back():
    before = gc.get_threshold()
    quiet = QuietCollector()
    quiet.start()
    try:
        assert gc.get_threshold() == (before[0], before[1], NEVER)
        assert quiet._seen in gc.callbacks
    finally:
        quiet.stop()
    assert gc.get_threshold() == before and quiet._seen not in gc.callbacks


def test_another_full_collection_resets_the_base():
    """Panel and Bokeh call gc.collect() after a page is discarded: the growth is counted from it."""
    blocks = [500_000]
    quiet = QuietCollector(heap=lambda: blocks[0])
    quiet.start()
    try:
        assert quiet.base == 500_000
        blocks[0] = 400_000  # a page discarded, its memory freed by someone else's collection
        gc.collect()
        quiet.look()
        assert quiet.base == 400_000
    finally:
        quiet.stop()


class Node:
    def __init__(self):
        self.other = self  # a cycle: only the cyclic collector frees it


def test_a_quiet_look_frees_cyclic_garbage_of_the_oldest_generation():
    collected = []
    quiet = QuietCollector(cpu=lambda: 0.0, collect=lambda: collected.append(gc.collect()))  # a server that does nothing
    quiet.start()
    try:
        kept = []
        while sys.getallocatedblocks() <= quiet.base * (1 + GROWTH) + FLOOR:  # a session's worth of models
            kept += [Node() for _ in range(10_000)]
        watched = weakref.ref(kept[0])
        for _ in range(YOUNGER + 1):
            gc.collect(1)  # the nodes survive into the oldest generation, as a session's models do
        assert quiet.due()
        del kept  # the session discarded: cyclic garbage that only a full collection frees
        assert watched() is not None
        assert quiet.look()
        assert watched() is None and len(collected) == 1
        assert not quiet.due()
    finally:
        quiet.stop()


def test_collect_when_quiet_starts_a_collector_and_its_periodic_look():
    asked = []
    quiet = collector.collect_when_quiet(lambda look, ms: asked.append((look, ms)))
    try:
        assert asked == [(quiet.look, collector.CHECK_S * 1000)] and gc.get_threshold()[2] == NEVER
    finally:
        quiet.stop()
