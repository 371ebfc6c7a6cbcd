"""Browser tests: the explorer served on a port the OS picks, driven by pytest-playwright in the
system Chromium (Playwright's own browser download does not work here, so it is never used).

Each test has its own server, page (pytest-playwright's context per test) and log window: no
session, cache or log line of one test reaches another, whatever their order."""

import logging
import shutil

import pytest
from playwright.sync_api import expect

from tests.helpers import served

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
# expect(...) waits for its condition as long as page.wait_for_* does (its own default, 5 s, is
# shorter than an update takes on a loaded machine)
expect.set_options(timeout=30_000)


@pytest.fixture(scope="session")
def browser_type_launch_args(browser_type_launch_args):
    if CHROMIUM is None:  # fail, never skip: CI must run these
        pytest.fail("Chromium is not installed (apt-get install -y chromium)")
    return {
        **browser_type_launch_args,
        "executable_path": CHROMIUM,
        "args": [
            "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
        ],
    }


@pytest.fixture(scope="session")
def browser_context_args(browser_context_args):
    return {**browser_context_args, "viewport": {"width": 1500, "height": 1300}, "accept_downloads": True}


class ServerLog(logging.Handler):
    """Everything the server logs at warning or above, and any record with a traceback."""

    def __init__(self):
        super().__init__(level=logging.WARNING)
        self.records = []

    def emit(self, record):
        self.records.append(record)

    def tracebacks(self, since: int = 0):
        return [r for r in self.records[since:] if r.exc_info or "Traceback" in r.getMessage()]


@pytest.fixture
def server_log():
    handler = ServerLog()
    logging.getLogger().addHandler(handler)
    yield handler
    logging.getLogger().removeHandler(handler)


@pytest.fixture
def explorer_url(page, server_log):
    """The explorer on its own server for this test; the test's page is closed before the
    server stops (a server stopping under an open page is not what a test looks at)."""
    from app.main import create_app

    with served(create_app, verbose=False) as server:
        yield f"http://localhost:{server.port}/"  # the origin Bokeh accepts by default
        page.close()


@pytest.fixture
def console_errors(page):
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    yield errors
    assert errors == [], f"browser console errors: {errors}"


@pytest.fixture
def no_server_tracebacks(explorer_url, server_log):
    """No traceback logged by the server while the test ran (checked before its page closes)."""
    before = len(server_log.records)
    yield
    tracebacks = server_log.tracebacks(since=before)
    assert tracebacks == [], [r.getMessage() for r in tracebacks]
