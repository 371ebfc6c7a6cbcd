"""What a session costs the server, fixed by counts (issue #28, cheaper sessions): the walks over
a page's models while it is built, the HoloViews elements an amplitude change builds, and what a
second session of the same design builds again. No clock: ``benchmarks/load_client.py`` prints
the times."""

import pytest

from app.main import App
from app.plotting import style
from app.tabs.explorer import GRID
from tests.helpers import rendered

KEYS = ("loop", *GRID)


@pytest.fixture
def built(monkeypatch):
    """Every element :func:`app.plotting.style.styled` makes while the test runs (every curve,
    marker, area and overlay of the plots is made there), in order."""
    made = []
    original = style.styled

    def counted(kind, data, **options):
        element = original(kind, data, **options)
        made.append(element)
        return element

    monkeypatch.setattr(style, "styled", counted)
    return made


def elements(app, key) -> list:
    return list(app.plots.frame(key).values())


def test_a_session_s_page_is_built_with_one_walk_over_its_models(monkeypatch):
    """Bokeh recomputes a document's set of models (a walk over all of them) whenever its last
    freeze ends. The page is built under one freeze (:class:`app.main.Page`): one walk, at the
    end, instead of one per root added, for the theme and per linked axis (15 walks of some 540
    models before); every model is in the document and knows it."""
    from bokeh.document.models import DocumentModelManager

    walks = []
    original = DocumentModelManager.recompute

    def counted(self):
        walks.append(self)
        original(self)

    monkeypatch.setattr(DocumentModelManager, "recompute", counted)
    doc = rendered(App().template())
    assert len(walks) == 1
    reachable = {m.id for root in doc.roots for m in root.references()}
    assert {m.id for m in doc.models} == reachable and all(m.document is doc for m in doc.models)


def test_an_amplitude_change_builds_only_what_it_moves(built):
    """Moving the amplitude rebuilds the loop, the curves through the operating point against
    frequency and the marker on the amplitude axes; the sweeps, the operating curves against
    amplitude and the frequency markers stay the objects they were (cached by value: a live plot
    sends them no data). No element is built to be thrown away, and no Bokeh model is replaced:
    the same models, new data."""
    app = App()
    doc = rendered(app.template())
    # a session's first update of a text adds Panel's stylesheets to it (three models, once; Panel's own)
    app.state.amplitude = round(app.state.amplitude * 0.8, 6)
    before = {key: elements(app, key) for key in KEYS}
    models = {m.id for m in doc.models}
    built.clear()
    app.state.amplitude = round(app.state.amplitude * 1.7, 6)
    after = {key: elements(app, key) for key in KEYS}
    shown = {id(frame) for key in KEYS for frame in (app.plots.frame(key), *app.plots.frame(key).values())}
    assert built and all(id(element) in shown for element in built)  # nothing built for nothing
    for quantity, against in GRID:
        old, new = before[(quantity, against)], after[(quantity, against)]
        moved = [n for o, n in zip(old, new) if o is not n]
        if against == "amplitude":  # only its marker moves
            assert [type(n).__name__ for n in moved] == ["VLine"]
        else:  # only its operating curve moves
            assert [n.label for n in moved] == ["operating point"]
    assert not any(o is n for o, n in zip(before["loop"], after["loop"]))
    assert {m.id for m in doc.models} == models


def test_a_second_session_of_the_same_design_builds_only_its_loop_and_its_overlays(built):
    """The curves of a design (the sweeps, the operating curves) and the markers are cached by
    value, process-wide: a second session of the default design finds the first's objects and
    builds only its loop's curves and the five overlays that hold them."""
    first = App()
    built.clear()
    second = App()
    for key in GRID:
        assert all(a is b for a, b in zip(elements(first, key), elements(second, key)))
    loop = {id(element) for element in elements(second, "loop")}
    rest = [element for element in built if id(element) not in loop]
    assert [type(element).__name__ for element in rest] == ["Overlay"] * len(KEYS)


def test_a_page_reads_few_property_defaults_through_bokeh(monkeypatch):
    """Bokeh merges a class's overridden defaults over its whole hierarchy at every read of a
    property never set; :func:`app.patches.cache_immutable_defaults` keeps the immutable ones and
    the type of the empty lists, dicts and sets (every model's ``tags``, ``js_event_callbacks``,
    ...): a page built asks Bokeh fewer than 1 500 times (some 950; 5 500 with the immutable ones
    alone, every model made reading its empty containers)."""
    from bokeh.core.has_props import HasProps

    from app import patches

    patches.install()
    rendered(App().template())  # the classes' first reads
    asked = []
    original = HasProps._overridden_defaults.__func__

    def counted(cls):
        asked.append(cls)
        return original(cls)

    monkeypatch.setattr(HasProps, "_overridden_defaults", classmethod(counted))
    doc = rendered(App().template())
    assert len(doc.models) > 500 and len(asked) < 1500, (len(doc.models), len(asked))


def test_the_server_freezes_what_it_holds_before_its_first_session_and_collects_when_quiet(monkeypatch):
    """The objects a server process holds before its first session (the libraries, the app's
    caches) are moved out of the interpreter's collections (``gc.freeze``) when it starts serving:
    a collection of the oldest objects, which pages built trigger, no longer examines them."""
    import gc

    import panel as pn

    from app import main

    frozen = []

    class Server:
        port = 0

        def start(self):
            frozen.append(gc.get_freeze_count())

        io_loop = type("Loop", (), {"start": staticmethod(lambda: None), "stop": staticmethod(lambda: None),
                                    "asyncio_loop": type("Asyncio", (), {"add_signal_handler": staticmethod(
                                        lambda *a: None)})()})()

    class Periodic:  # the event loop's periodic call, here only recorded
        def __init__(self, callback, ms):
            self.callback, self.ms = callback, ms

        def start(self):
            looks.append((self.callback, self.ms, gc.get_threshold()))

    looks = []
    threshold = gc.get_threshold()
    monkeypatch.setattr(pn, "serve", lambda *a, **k: Server())
    monkeypatch.setattr(main, "PeriodicCallback", Periodic)
    monkeypatch.setattr(main.work, "use_processes", lambda: None)
    monkeypatch.setattr(main.patches, "route_sessions", lambda *a: [])
    try:
        main.serve(port=0)
    finally:
        gc.unfreeze()
    assert frozen and frozen[0] > 100_000, frozen
    # while it serves, its full collections wait for quiet moments (app.collector), looked for
    # once a second; CPython's own are back when it stops
    [(look, ms, serving)] = looks
    assert look.__self__.__class__.__name__ == "QuietCollector" and ms == 1000
    assert serving[2] > 10 ** 6 and gc.get_threshold() == threshold


def test_a_page_has_no_selection_glyph_models():
    """Each curve's glyph renderer holds its glyph, the one for points not selected and the muted
    one: no selection glyph model (app.patches.selection_glyphs_auto; BokehJS clones the glyph for
    it), three line glyphs per line renderer, 22 models fewer per page than HoloViews makes."""
    from bokeh.models import GlyphRenderer, Line

    from app import patches

    patches.install()
    doc = rendered(App().template())
    renderers = [m for m in doc.models if isinstance(m, GlyphRenderer)]
    lines = [r for r in renderers if isinstance(r.glyph, Line)]
    assert len(lines) >= 20 and all(r.selection_glyph is None for r in renderers)
    assert sum(isinstance(m, Line) for m in doc.models) == 3 * len(lines)


def test_the_mathjax_decision_walks_no_models_of_a_page_served(monkeypatch):
    """Panel asks, for each page served, whether its texts hold math (app.patches.holds_math): for
    all of a document's roots the answer reads the document's set of models, computed already,
    instead of walking them again; roots of no document, or some of a document's, are walked."""
    import panel as pn
    from bokeh.model import Model

    from app import patches

    doc = rendered(App().template())
    walks = []
    original = Model.references

    def counted(self):
        walks.append(self)
        return original(self)

    monkeypatch.setattr(Model, "references", counted)
    assert patches.holds_math(doc.roots) is False and walks == []
    math = rendered(pn.Column(pn.pane.Markdown("Energy $$E = mc^2$$")))
    walks.clear()  # those of its building
    assert patches.holds_math(math.roots) is True and walks == []
    assert patches.holds_math(doc.roots[:1]) is False and len(walks) == 1
