"""Sessions admitted (issue #28, "50 sessions degrade gracefully"): a server process builds one
page at a time and takes at most ``max_sessions`` sessions (open or waiting to be built); beyond,
a page or a websocket that would open a new session is refused at once with HTTP 503,
``Retry-After`` and a page that says the server is busy (app/admission.py), while ``/liveness``
and the sessions already open keep answering."""

import threading
import urllib.error
import urllib.request

import pytest

from app import admission, patches
from app.main import create_app
from tests.helpers import off_the_loop, served


def test_the_refusal_names_the_limit_reached():
    limits = admission.Admission(max_sessions=3)
    assert limits.refusal(2) is None
    assert "holds 3 sessions" in limits.refusal(3)
    limits.opening = 2
    assert limits.refusal(0) is None
    assert "holds 3 sessions, 2 of them opening now" in limits.refusal(1)


@pytest.mark.parametrize("bad", [0, -1, 2.5, True, "4", None])
def test_limits_are_whole_numbers_of_at_least_one(bad):
    with pytest.raises(ValueError, match="max_sessions: a whole number of at least 1"):
        admission.Admission(max_sessions=bad)


def test_the_busy_page_escapes_its_reason_and_reloads_itself():
    page = admission.busy_page("<b>&</b>", 7)
    assert "&lt;b&gt;&amp;&lt;/b&gt;" in page and "<b>" not in page
    assert '<meta http-equiv="refresh" content="7">' in page and "The server is busy" in page


def test_the_routes_replaced_were_panels():
    """The one library internal behind admission (app/patches/): Bokeh's server reads its
    per-app routes from this module list, which holds Panel's handlers."""
    from bokeh.server import urls
    from panel.io.server import DocHandler, WSHandler

    previous = patches.route_sessions(admission.AdmittingDocHandler, admission.AdmittingWSHandler)
    try:
        handlers = [handler for _route, handler, *_rest in previous]  # Panel's (or already ours)
        assert any(issubclass(h, DocHandler) for h in handlers) and any(issubclass(h, WSHandler) for h in handlers)
        now = [handler for _route, handler, *_rest in urls.per_app_patterns]
        assert admission.AdmittingDocHandler in now and admission.AdmittingWSHandler in now
        assert DocHandler not in now and WSHandler not in now
    finally:
        urls.per_app_patterns[:] = previous


@pytest.fixture
def admitting(monkeypatch):
    """Admission routed for the servers this test starts, with the limits it sets; put back after.
    These pages never join by websocket: the next build does not wait long for them."""
    from bokeh.server import urls

    monkeypatch.setattr(admission, "JOIN_WAIT_S", 0.1)
    before = admission.ADMISSION
    admission.ADMISSION = admission.Admission(max_sessions=2)
    previous = patches.route_sessions(admission.AdmittingDocHandler, admission.AdmittingWSHandler)
    try:
        yield admission.ADMISSION
    finally:
        urls.per_app_patterns[:] = previous
        admission.ADMISSION = before


KEPT = {"unused_session_lifetime_milliseconds": 3_600_000}  # no session discarded during a test


def get(url: str):
    """(status, headers, body) of a GET of ``url``."""
    try:
        with urllib.request.urlopen(url, timeout=120) as r:
            return r.status, r.headers, r.read().decode()
    except urllib.error.HTTPError as exc:
        return exc.code, exc.headers, exc.read().decode()


def test_a_page_beyond_the_sessions_held_is_told_the_server_is_busy(admitting):
    from bokeh.client import pull_session

    with served(create_app, verbose=False, liveness=True, **KEPT) as server:
        url = f"http://localhost:{server.port}/"
        assert [get(url)[0] for _ in range(2)] == [200, 200]
        assert len(server.get_sessions()) == 2
        status, headers, body = get(url)
        assert status == 503
        assert admission.RETRY_S[0] <= int(headers["Retry-After"]) <= admission.RETRY_S[1]
        assert "The server is busy" in body and "holds 2 sessions" in body
        with pytest.raises(OSError, match="503"):  # a new session by websocket alone
            off_the_loop(lambda: pull_session(url=url))  # bokeh.client's own loop
        assert len(server.get_sessions()) == 2  # nothing built for the refusals
        assert get(url + "liveness")[0] == 200
        assert admitting.refused == 2


def test_a_burst_of_pages_is_built_one_at_a_time_and_beyond_the_limit_refused(admitting):
    """Eight pages asked for at once with room for five: five are served (their sessions built,
    one after the other), three refused as busy; ``/liveness`` answers during the burst."""
    admitting.max_sessions = 5
    with served(create_app, verbose=False, liveness=True, **KEPT) as server:
        url = f"http://localhost:{server.port}/"
        results = [None] * 8

        def ask(i):
            results[i] = get(url)

        threads = [threading.Thread(target=ask, args=(i,)) for i in range(8)]
        for t in threads:
            t.start()
        live = get(url + "liveness")
        for t in threads:
            t.join(300)
        assert live[0] == 200
        statuses = [r[0] for r in results]
        assert sorted(statuses) == [200] * 5 + [503] * 3, statuses
        assert all("The server is busy" in body for status, _h, body in results if status == 503)
        assert len(server.get_sessions()) == 5
        assert admitting.opening == 0
