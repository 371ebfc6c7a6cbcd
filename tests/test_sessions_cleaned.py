"""Session lifetime (issue #28, part 4): a closed page's session is discarded by the server
after the documented unused-session lifetime (docs/serving.md: 15 s, checked every 5 s), so a
class that comes and goes leaves no sessions behind. The sessions are bokeh.client's (as the load
client's, a page's as far as the server can tell); the wait is bounded by the lifetime, the
check interval and a margin, and ends as soon as the server holds no session."""

import time

from app.main import SESSION_CHECK_S, SESSION_LIFETIME_S, SESSION_OPTIONS, create_app
from tests.helpers import off_the_loop, served

MARGIN_S = 20  # a loaded machine's event loop may run the check late


def sessions(server) -> int:
    return len(server.get_sessions())  # Bokeh's Server: every application's sessions


def test_closed_sessions_are_discarded_after_the_lifetime():
    from bokeh.client import pull_session

    with served(create_app, verbose=False, **SESSION_OPTIONS) as server:
        url = f"http://localhost:{server.port}/"

        def two_pages():  # bokeh.client runs a loop of its own: off any browser test's (off_the_loop)
            pulled = [pull_session(url=url) for _ in range(2)]
            held = sessions(server)
            for session in pulled:
                session.close()
            return held

        assert off_the_loop(two_pages) == 2
        closed = time.monotonic()
        bound = SESSION_LIFETIME_S + SESSION_CHECK_S + MARGIN_S
        while sessions(server) and time.monotonic() - closed < bound:
            time.sleep(0.5)
        assert sessions(server) == 0, f"sessions still held {bound} s after their pages closed"
