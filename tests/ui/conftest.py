"""Browser tests: the explorer served on a free port, driven by pytest-playwright in the
system Chromium (Playwright's own browser download does not work here, so it is never used)."""

import logging
import shutil

import pytest

from tests.helpers import free_port, wait_for

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


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

    def tracebacks(self):
        return [r for r in self.records if r.exc_info or "Traceback" in r.getMessage()]


@pytest.fixture(scope="session")
def server_log():
    handler = ServerLog()
    logging.getLogger().addHandler(handler)
    yield handler
    logging.getLogger().removeHandler(handler)


@pytest.fixture(scope="session")
def explorer_url(server_log):
    import panel as pn

    from app.main import create_app

    port = free_port()
    server = pn.serve(
        create_app, port=port, address="127.0.0.1", show=False, threaded=True, liveness=True,
        websocket_origin=[f"127.0.0.1:{port}", f"localhost:{port}"], verbose=False,
    )
    url = f"http://127.0.0.1:{port}/"
    wait_for(url + "liveness")
    yield url
    server.stop()


@pytest.fixture
def console_errors(page):
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    yield errors
    assert errors == [], f"browser console errors: {errors}"


@pytest.fixture
def no_server_tracebacks(server_log):
    before = len(server_log.records)
    yield
    new = server_log.records[before:]
    tracebacks = [r for r in new if r.exc_info or "Traceback" in r.getMessage()]
    assert tracebacks == [], [r.getMessage() for r in tracebacks]
