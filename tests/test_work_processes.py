"""Long work in worker processes (app.work): a served explorer runs the diagnosis in a pool of
worker processes, off the interpreter lock its pages' changes need. The process route gives the
same result as the thread route, passes the work's progress on in order, raises the work's own
errors, and falls back to a thread for work that is not a :class:`app.work.Task`. Work started
ahead (the diagnosis of data just loaded) is taken over by the click that asks for that same
work, and gives way to any other."""

import asyncio
import os

import numpy as np
import pytest

from app import work
from core import PAPER_B
from core.identify.diagnose import diagnose
from core.synthetic import synthetic_stiffness
from tests.helpers import run_async


@pytest.fixture
def processes():
    work.use_processes(1)
    yield
    work.stop_processes()


def data():
    hidden = PAPER_B.replace(effects={"inertia": {"mass": 0.5}})
    return synthetic_stiffness(hidden, np.linspace(1, 100, 12), [0.04e-3, 0.17e-3], noise=0.005, seed=3)


def pid_of(progress=None):
    if progress is not None:
        progress(0.5, "half way")
    return os.getpid()


def token(progress=None):
    """Eight random bytes: each run of it gives others."""
    return os.urandom(8)


def count_to(n, progress=None):
    """Says its progress ``n`` times; how many it said."""
    for i in range(n):
        progress(i / n, f"step {i}")
    return n


def refuse(progress=None):
    raise ValueError("the data hold no axial rows")


def run(task, shown=None):
    return run_async(work.in_thread(task, None if shown is None else lambda f, m: shown.append((f, m))))


def test_a_task_runs_in_another_process_and_a_plain_function_in_this_one(processes):
    assert run(work.Task(pid_of)) != os.getpid()
    assert run(pid_of) == os.getpid()


def test_the_diagnosis_in_a_worker_process_is_the_diagnosis_here(processes):
    task = work.Task(diagnose, (PAPER_B, data()), {"baseline": ["elastic", "fractional", "friction"]})
    shown, before = [], work.relayed
    there = run(task, shown)
    here = task()
    assert [s.effect for s in there.steps] == [s.effect for s in here.steps] == ["inertia"]
    np.testing.assert_allclose(there.final.gap, here.final.gap, rtol=1e-12)
    assert work.relayed > before  # its progress came back through the queue
    fractions = [f for f, _ in shown]
    assert fractions == sorted(fractions) and all(0.0 <= f < 1.0 for f in fractions)


def test_an_error_in_a_worker_is_the_works_own(processes):
    with pytest.raises(ValueError, match="no axial rows"):
        run(work.Task(refuse))


def test_without_processes_a_task_runs_in_a_thread():
    assert run(work.Task(pid_of)) == os.getpid()


def test_a_write_to_a_closed_page_that_nobody_awaited_is_not_logged(caplog):
    """The event loop of a served explorer says nothing of a failed write to a page that has gone
    (app.work.quiet_closed_writes); any other error goes to asyncio's own handler, logged."""
    from tornado.websocket import WebSocketClosedError

    loop = asyncio.new_event_loop()
    try:
        work.quiet_closed_writes(loop)
        work.quiet_closed_writes(loop)  # once per loop
        with caplog.at_level("DEBUG", logger="asyncio"):
            loop.call_exception_handler({"message": "Task exception was never retrieved",
                                         "exception": WebSocketClosedError()})
            assert [r for r in caplog.records if r.name == "asyncio"] == []
            loop.call_exception_handler({"message": "Task exception was never retrieved",
                                         "exception": ValueError("a bug")})
            loop.call_exception_handler({"message": "socket.send() raised exception.",
                                         "exception": WebSocketClosedError()})
        logged = [r for r in caplog.records if r.name == "asyncio"]
        assert [r.levelname for r in logged] == ["ERROR", "ERROR"]
    finally:
        loop.close()


def test_work_started_ahead_is_taken_over_by_the_same_work(processes):
    async def click():
        started = work.start_ahead(work.Task(token))
        assert started is not None
        assert work.claim(started, work.Task(token)) is started
        return started, await work.in_thread(work.claim(started, work.Task(token)))

    started, got = run_async(click())
    assert got == started.future.result()  # one run, not a second


def test_work_started_ahead_gives_way_to_other_work(processes):
    """It stops at its next progress report: its million reports are not made."""
    async def others():
        ahead = work.start_ahead(work.Task(count_to, (10**6,)))
        assert ahead is not None and work.start_ahead(work.Task(token)) is None  # the one worker is busy
        pid = await work.in_thread(work.Task(pid_of))  # asked for while it runs: it is cancelled
        other = work.start_ahead(work.Task(count_to, (10**6,)))
        assert work.claim(other, work.Task(count_to, (10**6 + 1,))) == work.Task(count_to, (10**6 + 1,))
        return ahead, other, pid

    ahead, other, pid = run_async(others())
    assert pid != os.getpid()
    for started in (ahead, other):
        assert started.future.cancelled() or isinstance(started.future.exception(timeout=120), work.Cancelled)


def test_a_diagnosis_click_takes_over_the_diagnosis_started_with_the_data_if_nothing_changed(processes):
    from app.main import App

    view = App().diagnosis
    assert view.state.load_csv(data().to_csv(), "inertia.csv")
    started = view._ahead
    assert started is not None
    run_async(view._run())
    assert view.state.result is started.future.result() and view.state.result.added == ["inertia"]
    # the baseline changed after the data came: the click diagnoses with the new one
    assert view.state.load_csv(data().to_csv(), "inertia.csv")
    view.state.baseline = ["elastic", "friction"]
    run_async(view._run())
    assert view.state.result.baseline.model.branches == ("elastic", "friction")


def test_work_started_ahead_that_ended_unclaimed_is_held_only_by_whoever_started_it(processes):
    """A page that loaded data and closed without a click leaves nothing behind in the server."""
    import gc
    import weakref

    async def unclaimed():
        started = work.start_ahead(work.Task(token))
        await asyncio.wrap_future(started.future)
        await work.in_thread(work.Task(pid_of))  # and other work after it
        return weakref.ref(started), started.future.result()

    ref, got = run_async(unclaimed())
    gc.collect()
    assert ref() is None and len(got) == 8
