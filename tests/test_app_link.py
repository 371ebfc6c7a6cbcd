"""The session's link without a browser: a session's document and its Location, as a server
gives each session. A link opened applies its good values and says which were not usable; the
state's changes reach the address bar after a pause, one write for several quick changes; a
value the URL already holds causes nothing."""

from urllib.parse import parse_qsl

import panel as pn
import pytest
from bokeh.document import Document

from app.link import URL_NAMES
from app.main import URL_DELAY_MS, App


@pytest.fixture
def session():
    """A session's document, current while the test runs (pn.state.location is its Location)."""
    doc = Document()
    pn.state.curdoc = doc
    yield doc
    pn.state.curdoc = None


def opened(search: str) -> App:
    """A session opened at the link ``search`` (as create_app builds one)."""
    pn.state.location.search = search
    app = App()
    app.sync_url()
    return app


def flush(doc: Document) -> int:
    """Run the document's waiting timeouts (the pause ends); how many there were."""
    waiting = list(doc.session_callbacks)
    for callback in waiting:
        doc.remove_timeout_callback(callback)
        callback.callback()
    return len(waiting)


def url() -> dict[str, str]:
    return dict(parse_qsl(pn.state.location.search[1:], keep_blank_values=True))


def test_a_link_with_bad_values_applies_the_good_ones_and_says_which(session):
    app = opened("?b_mm=40&amp=-5&f_Hz=20&mu_MPa=abc&mode=radial&tol=mu:10&bands=true")
    s = app.state
    assert (s.mode, s.outer_radius_mm, s.frequency_hz, s.tolerance_text, s.band_on) == ("radial", 40, 20, "mu:10", True)
    assert s.amplitude > 0 and s.shear_modulus_mpa == 2.42  # kept: the link's values are no values
    assert "-5.0 was not usable" in s.errors["amplitude"] and "'abc' was not usable" in s.errors["shear_modulus_mpa"]
    flush(session)
    assert set(url()) == set(URL_NAMES.values())  # the whole session is in the address bar
    assert (url()["b_mm"], url()["f_Hz"], url()["tol"], url()["bands"]) == ("40", "20", "mu:10", "true")


def test_quick_changes_write_the_url_once_and_nothing_echoes(session):
    app = opened("")
    flush(session)
    writes, changes = [], []
    pn.state.location.param.watch(writes.append, "search")
    app.state.param.watch(changes.append, list(URL_NAMES))
    before = pn.state.location.search
    for value in (2.5, 2.6, 2.7, 2.8):  # a slider drag
        app.state.shear_modulus_mpa = value
    app.state.amplitude = 0.2
    assert writes == [] and len(changes) == 5  # within the pause: the URL waits
    assert [c.timeout for c in session.session_callbacks] == [URL_DELAY_MS]
    assert flush(session) == 1 and len(writes) == 1 and len(changes) == 5  # one write; no echo into the state
    assert (url()["mu_MPa"], url()["amp"]) == ("2.8", "0.2")
    assert flush(session) == 0
    pn.state.location.search = before  # the back button
    assert (app.state.shear_modulus_mpa, app.state.amplitude) == (2.42, 0.1)
    flush(session)
    assert len(writes) == 2 and pn.state.location.search == before  # the back button's own; none after it


def test_a_blank_field_travels_in_the_link_as_blank(session):
    app = opened("")
    app.state.outer_radius_mm = None  # the field emptied
    flush(session)
    link = pn.state.location.search
    assert url()["b_mm"] == "null"  # the link's format, as before
    pn.state.curdoc = Document()  # a new session at that link: the field is blank again, said so
    again = opened(link)
    assert again.state.outer_radius_mm is None and again.state.errors == {"outer_radius_mm": "Enter a number."}
