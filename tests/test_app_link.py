"""The session's link without a browser: a session's document and its Location, as a server
gives each session. A link opened applies its good values and says which were not usable; the
state's changes reach the address bar after a pause, one write for several quick changes; a
value the URL already holds causes nothing."""

from pathlib import Path
from urllib.parse import parse_qsl

import panel as pn
import pytest
from bokeh.document import Document
from bokeh.server.callbacks import NextTickCallback

from app.link import URL_NAMES, design_query
from app.main import URL_DELAY_MS, App
from core import PAPER_B

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"



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


def turn(doc: Document) -> None:
    """The event loop's next turn: the document's next-tick callbacks run (a change handled, the
    link's pause starts)."""
    for callback in [c for c in doc.session_callbacks if isinstance(c, NextTickCallback)]:
        doc.remove_next_tick_callback(callback)
        callback.callback()


def flush(doc: Document) -> int:
    """The loop's next turn, then the document's waiting timeouts run (the pause ends); how
    many timeouts there were."""
    turn(doc)
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
    # each refused value's message names the key, the value, the rule and what is kept
    assert s.errors["amplitude"].startswith("The link's amp=-5.0 is outside this bushing's amplitude axis (")
    assert s.errors["shear_modulus_mpa"] == "The link's mu_MPa='abc' is not a number; kept 2.42."
    flush(session)
    # the whole session is in the address bar (an optional field left empty: its key left out)
    assert set(url()) == set(URL_NAMES.values()) - {"K_GPa"}
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
    # the pause starts once the changes are handled (the loop's next turn), however long that took
    assert [type(c) for c in session.session_callbacks] == [NextTickCallback]
    turn(session)
    assert writes == [] and [c.timeout for c in session.session_callbacks] == [URL_DELAY_MS]
    assert flush(session) == 1 and len(writes) == 1 and len(changes) == 5  # one write; no echo into the state
    assert (url()["mu_MPa"], url()["amp"]) == ("2.8", "0.2")
    assert flush(session) == 0
    pn.state.location.search = before  # the back button
    assert (app.state.shear_modulus_mpa, app.state.amplitude) == (2.42, 0.1)
    flush(session)
    assert len(writes) == 2 and pn.state.location.search == before  # the back button's own; none after it


def test_a_field_the_rules_refuse_is_never_written_to_the_link(session):
    """The address bar shows what the plots draw: a blank or invalid field keeps its message
    beside it, the link the value drawn (the field is not reset by the link's own write)."""
    app = opened("")
    app.state.outer_radius_mm = None  # the field emptied
    app.state.shear_modulus_mpa = -1.0
    flush(session)
    assert (url()["b_mm"], url()["mu_MPa"]) == ("35", "2.42")  # the drawn design's
    assert app.state.outer_radius_mm is None and set(app.state.errors) == {"outer_radius_mm", "shear_modulus_mpa"}
    pn.state.curdoc = Document()  # a link with a blank value still opens blank, said so
    again = opened("?b_mm=null")
    assert again.state.outer_radius_mm is None and again.state.errors == {"outer_radius_mm": "Enter a number."}


def test_a_link_holds_the_effects_the_name_and_the_reference(session):
    app = opened("")
    s = app.state
    s.pin_reference()
    diagnosed = s.design.replace(name="Paper B (diagnosed)", effects={"viscous": {"viscosity": 1234.5},
                                                                      "inertia": {"mass": 0.25}})
    s.adopt(diagnosed)
    s.length_mm = 80.0  # the reference stays Paper B
    s.pin_reference()
    s.length_mm = 90.0  # back to the diagnosed design, named again
    assert s.design == diagnosed
    flush(session)
    assert url()["effects"] == "inertia@axial.mass:0.25,viscous.viscosity:1234.5"
    assert (url()["name"], url()["ref.L_mm"], url()["ref.effects"]) == ("Paper B (diagnosed)", "80", url()["effects"])
    link = pn.state.location.search
    pn.state.curdoc = Document()
    again = opened(link).state
    assert again.design == diagnosed and again.errors == {}
    ref, want = again.reference.to_dict(), s.reference.to_dict()
    assert ref["effects"] == want["effects"] and ref["geometry"] == pytest.approx(want["geometry"], rel=1e-12)


def test_a_link_holds_the_bulk_modulus_and_an_empty_field_is_the_incompressible_rubber(session):
    """The optional bulk modulus: set, it is in the link (K_GPa) and the link opens it again;
    emptied, the design has none and the link no key; K/µ outside 50–1e6 is refused beside it."""
    app = opened("?mode=radial")
    s = app.state
    s.bulk_modulus_gpa = 2.0
    assert s.errors == {} and s.design.material.bulk_modulus == pytest.approx(2.0e9, rel=1e-12)
    flush(session)
    assert url()["K_GPa"] == "2"
    link = pn.state.location.search
    pn.state.curdoc = Document()
    again = opened(link).state
    assert again.design == s.design
    again.bulk_modulus_gpa = None
    assert again.errors == {} and again.design.material.bulk_modulus is None
    again.bulk_modulus_gpa = 0.01  # K/µ = 4: far too compressible for rubber
    assert "between 50 and 1000000 times the shear modulus" in again.errors["bulk_modulus_gpa"]
    assert again.design.material.bulk_modulus is None  # the plots keep the last valid design


def test_a_links_bad_effect_or_amplitude_is_refused_with_its_rule(session):
    reference = "&".join(f"ref.{k}={v}" for k, v in design_query(PAPER_B).items() if k != "name")
    app = opened("?amp=1e6&effects=viscous.viscosity:-3&" + reference.replace("ref.a_mm=20", "ref.a_mm=50"))
    s = app.state
    assert s.amplitude == 0.1 and s.effects == {} and s.reference is None
    assert s.errors["amplitude"].startswith("The link's amp=1000000.0 is outside this bushing's amplitude axis")
    assert s.errors["effects"] == ("The link's effects='viscous.viscosity:-3' must be ≥ 0, got -3.0; kept none.")
    assert s.errors["reference"] == "The link's ref.b_mm='35' must be larger than the inner radius a; kept none."
    flush(session)
    assert url()["amp"] == "0.1" and "effects" not in url() and "ref.a_mm" not in url()


def test_a_design_file_downloaded_opens_again_exactly(session):
    """The export's design file, opened in the sidebar, is the design again (name, effects,
    exact SI values) at the operating point the user had; a broken one is named and refused."""
    from app.inputs import DesignFile
    from core.io.design_file import dumps_design, loads_design

    app = opened("?f_Hz=40&amp=0.3")
    s = app.state
    s.adopt(s.design.replace(name="Mine", effects={"viscous": {"viscosity": 777.0}, "inertia": {"mass": 0.3}}))
    saved = app.export._design_json().getvalue()
    assert loads_design(saved) == s.design
    shown = s.design
    s.shear_modulus_mpa = 1.5
    opener = DesignFile(s)
    assert opener.load(saved.encode(), "bushing-design.json")
    assert s.design == shown and (s.amplitude, s.frequency_hz) == (0.3, 40)
    assert opener.load(b'{"mode": "axial"}', "broken.json") is False
    assert opener.message.object.startswith('<div class="field-error" style="color:#b03a2e">⚠ broken.json not loaded: ')
    assert "geometry: missing (required)" in opener.message.object and s.design == shown
    assert opener.load(dumps_design(PAPER_B.in_mode("torsion")), "t.json")  # another mode: mid-range amplitude
    assert s.design.mode == "torsion" and s.errors == {}


def test_a_link_number_is_the_shortest_within_nine_digits():
    """A link's number reads back as near its value as nine significant digits do (half a unit
    of the ninth), in the fewest digits that do: float noise goes."""
    import math

    import numpy as np

    from core.numbers import LINK_DIGITS, link_number

    rng = np.random.default_rng(7)
    for v in [*(10.0 ** rng.uniform(-9, 9, 300) * rng.choice([-1, 1], 300)), 0.30000000000000004, 40.0]:
        text = link_number(v)
        half = 0.5 * 10.0 ** (math.floor(math.log10(abs(v))) - LINK_DIGITS + 1)
        assert abs(float(text) - v) <= half * (1 + 1e-9), (v, text)
        assert "e" not in text.lower()
        digits = len(text.lstrip("-").replace(".", "").strip("0"))
        assert digits <= LINK_DIGITS
    assert link_number(0.30000000000000004) == "0.3" and link_number(40.0) == "40"


def test_a_loop_upload_moves_the_operating_point_to_round_numbers():
    """The loop's frequency is estimated from its samples (0.09999999973 Hz for the example's
    0.1 Hz): the operating point and its link take the quantity's four digits."""
    from app.link import url_query
    from app.state import ExplorerState

    s = ExplorerState()
    assert s.load_measured_loop((EXAMPLES / "paper_b_loop.csv").read_text(), "paper_b_loop.csv")
    query = url_query(s)
    assert query["f_Hz"] == "0.1", query
