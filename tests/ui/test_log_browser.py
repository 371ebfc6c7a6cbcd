"""The server's log stays clean (issue #27, item 15): the steps that once logged a warning or a
traceback, driven in a real browser, and then no warning, no traceback in the server's log and no
Bokeh warning raised while the server ran them. Each step waits for the state it then checks."""

import gc
import threading
import warnings

import pytest
from playwright.sync_api import expect

from tests.helpers import served
from tests.ui.bokeh_page import mystery_demo, open_explorer

pytestmark = pytest.mark.usefixtures("console_errors")


@pytest.fixture
def bokeh_warnings():
    """Every warning raised in the process (the server's thread included) while the test runs."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield caught


def assert_clean(server_log, caught):
    logged = [f"{r.levelname} {r.name}: {r.getMessage()}" for r in server_log.records]
    assert logged == [], logged
    raised = [f"{w.category.__name__}: {w.message}" for w in caught if "bokeh" in w.category.__module__
              or "panel" in w.category.__module__]
    assert raised == [], raised


def test_clear_the_data_after_a_fit_with_fit_on(page, explorer_url, server_log, bokeh_warnings):
    """Fit on one amplitude (the rest predicted), then *Clear the data*: the tab's plots go back
    to no data, with nothing logged (once: "kept its last plots: AttributeError: unexpected
    attribute 'design' to figure")."""
    open_explorer(page, explorer_url)
    page.get_by_text("Measured data and fit", exact=True).click()
    page.get_by_role("button", name="Fit the five material parameters").wait_for()
    page.get_by_role("button", name="Load the synthetic Paper B example").click()
    page.get_by_text("150 points").first.wait_for()
    fit_on = page.get_by_label("Fit on (the rest is predicted)")
    fit_on.fill("amplitude=0.1")
    fit_on.press("Enter")
    page.get_by_role("button", name="Fit the five material parameters").click()
    page.get_by_text("Fitted on amplitude=0.1").wait_for(timeout=60_000)
    page.get_by_role("button", name="Clear the data").click()
    expect(page.get_by_text("150 points")).to_have_count(0)
    expect(page.get_by_text("Fitted on amplitude=0.1")).to_have_count(0)
    assert_clean(server_log, bokeh_warnings)


def test_first_mystery_demo(page, explorer_url, server_log, bokeh_warnings):
    """The first click in the diagnosis tab, on a widget the server sent with the tab: the page
    refers to it by id (the server knows it), never sends it again as a new model."""
    mystery_demo(page, explorer_url)
    assert_clean(server_log, bokeh_warnings)


@pytest.fixture
def served_explorer(page, server_log):
    """The explorer on its own server: ``(url, server)``, the page closed before the server stops."""
    from app.main import create_app

    # Bokeh's own session lifetimes: a closed page's session is discarded some 15–32 s after it
    # closes (passing shorter ones to pn.serve made the page load Panel's CSS from the CDN, which
    # fails offline: console errors)
    with served(create_app, verbose=False) as server:
        yield f"http://localhost:{server.port}/", server
        if not page.is_closed():
            page.close()


def poll(server, done):
    """Set ``done`` once ``server`` holds no session (checked on its loop every 0.05 s)."""
    if not server.get_sessions():
        done.set()
    else:
        server.io_loop.call_later(0.05, poll, server, done)


def test_a_page_closed_during_find_designs(page, served_explorer, server_log, bokeh_warnings, monkeypatch):
    """The page closes while *Find designs* runs, and its session is discarded before the search
    ends: the result goes nowhere, and nothing is logged (no unretrieved exception, no traceback,
    no warning)."""
    from app.targets_form import TargetsForm

    url, server = served_explorer
    started, closed, computed, ended = (threading.Event() for _ in range(4))
    search, compute = TargetsForm.search, TargetsForm.compute

    def gated(self, progress=None):
        started.set()
        closed.wait(60)  # the search runs on after the page has gone
        try:
            return compute(self, progress)
        finally:
            computed.set()

    async def watched(self, doc=None):
        try:
            await search(self, doc)
        finally:
            ended.set()

    monkeypatch.setattr(TargetsForm, "compute", gated)
    monkeypatch.setattr(TargetsForm, "search", watched)
    open_explorer(page, url)
    page.get_by_text("What-ifs", exact=True).click()
    page.get_by_role("button", name="Find designs").wait_for()
    target = page.get_by_label("|K| target")
    target.fill("4.5")
    target.press("Enter")
    page.get_by_role("button", name="Find designs").click()
    assert started.wait(30)
    page.close()
    sessions = threading.Event()  # set once the server has discarded the closed page's session
    server.io_loop.add_callback(lambda: poll(server, sessions))
    assert sessions.wait(90)
    closed.set()
    assert computed.wait(60)
    assert ended.wait(60)
    # any exception nobody retrieved is logged by asyncio when its future is freed
    done = threading.Event()
    server.io_loop.add_callback(lambda: (gc.collect(), done.set()))
    assert done.wait(30)
    assert_clean(server_log, bokeh_warnings)


def gate(monkeypatch, cls, where: str):
    """The work of ``cls`` held (before it, or after it with its result in hand) until the test
    sets ``release``: ``(started, release, ended)`` events, ``ended`` set once it has returned.
    The work is ``cls.compute``, or the function of the :class:`app.work.Task` that ``cls.task``
    gives (the diagnosis: the view runs that task)."""
    from app.work import Task

    started, release, ended = (threading.Event() for _ in range(3))

    def held(work):
        def run(*args, **kwargs):
            try:
                started.set()
                if where == "before":
                    release.wait(60)
                result = work(*args, **kwargs)
                if where == "after":
                    release.wait(60)
                return result
            finally:
                ended.set()

        return run

    if hasattr(cls, "task"):
        task = cls.task
        monkeypatch.setattr(cls, "task", lambda self: (t := task(self)) and Task(held(t.function), t.args, t.kwargs))
    else:
        compute = cls.compute
        monkeypatch.setattr(cls, "compute", lambda self, progress=None: held(compute)(self, progress))
    return started, release, ended


def start_diagnosis(page, url):
    open_explorer(page, url)
    page.get_by_text("Find the missing effect", exact=True).click()
    page.get_by_role("button", name="Load a mystery data set (demo)").click()
    page.get_by_text("mystery data set").first.wait_for()
    page.get_by_role("button", name="Diagnose").click()


def start_find_designs(page, url):
    open_explorer(page, url)
    page.get_by_text("What-ifs", exact=True).click()
    target = page.get_by_label("|K| target")
    target.fill("4.5")
    target.press("Enter")
    page.get_by_role("button", name="Find designs").click()


# when the page closes: while the work runs, its session discarded before it ends; as it ends,
# the socket just closed; as it ends, the session discarded
MOMENTS = [("before", True), ("after", False), ("after", True)]


@pytest.mark.parametrize(("where", "discarded"), MOMENTS, ids=["during", "at-its-end", "at-its-end-discarded"])
@pytest.mark.parametrize("work", ["diagnosis", "find designs"])
def test_a_page_closed_during_long_work_logs_nothing(page, served_explorer, server_log, bokeh_warnings, monkeypatch,
                                                     work, where, discarded):
    """The page closes at several moments of the diagnosis or of *Find designs*: nothing is
    logged (no WebSocketClosedError, no unretrieved exception, no warning), whenever it closes
    (issue #27, item 15)."""
    from app.diagnosis_state import DiagnosisState
    from app.targets_form import TargetsForm

    url, server = served_explorer
    cls, start = (DiagnosisState, start_diagnosis) if work == "diagnosis" else (TargetsForm, start_find_designs)
    started, release, ended = gate(monkeypatch, cls, where)
    start(page, url)
    assert started.wait(60)
    page.close()
    if discarded:
        sessions = threading.Event()
        server.io_loop.add_callback(lambda: poll(server, sessions))
        assert sessions.wait(90)
    release.set()
    assert ended.wait(120)
    # the event loop has run what the work's end scheduled, then any exception nobody retrieved
    # is logged by asyncio when its future is freed
    for _ in range(3):
        done = threading.Event()
        server.io_loop.add_callback(lambda ev=done: (gc.collect(), ev.set()))
        assert done.wait(30)
    assert_clean(server_log, bokeh_warnings)
