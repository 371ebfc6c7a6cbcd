"""What the app changes outside its own objects: axis ranges only on clones of its dimensions,
and library internals (app.patches) only once ``create_app`` installs them."""


import numpy as np
import pytest

from app.main import App


@pytest.fixture
def app():
    return App()


def ranges(overlay):
    return [(d.name, tuple(d.range)) for el in overlay for d in el.dimensions()]


@pytest.mark.parametrize("view, plot", [("teaching", "real"), ("teaching", "loop"), ("slices", "magnitude"),
                                        ("card", "radial")])
def test_a_view_keeps_the_axes_of_what_it_drew_before(app, view, plot):
    """A tab redrawn for a very different design draws on new ranges; the overlay it showed before
    keeps its own (the Fletcher–Gent tab, the slices, the card)."""
    v = app.view(view)
    v.show(True)
    old = v.frame(plot)
    before = ranges(old)
    app.state.friction_strain_half *= 100  # the amplitude axis moves two decades
    app.state.shear_modulus_mpa *= 10
    app.state.outer_radius_mm *= 1.5  # and the drive of a strain (the card)
    assert v.frame(plot) is not old
    assert ranges(old) == before
    assert plot == "loop" or ranges(v.frame(plot)) != before
    assert all(tuple(d.range) == (None, None) for d in v.dims.values())


def test_the_fits_residuals_draw_on_their_own_range(app):
    from core.synthetic import paper_b_example

    m = app.view("measured")
    m.show(True)
    data, _ = paper_b_example(app.state.design)
    app.state.measured = data
    old = m.residuals.current[0]
    before = ranges(old)
    app.state.shear_modulus_mpa *= 3  # far from the data: residuals of another size
    assert ranges(old) == before and ranges(m.residuals.current[0]) != before
    assert np.isfinite(before[1][1]).all()


def test_library_internals_change_only_when_create_app_installs_them():
    """Importing app.patches, app.inputs or the whole app changes no Panel state; create_app
    installs the MathJax decision and the number widgets' priority values, once (a second
    install changes nothing) and on the app's own widget classes only."""
    import subprocess
    import sys

    code = """
import panel as pn
from panel.io import resources
from panel.reactive import Syncable
def state():
    return (resources._panel_use_mathjax, tuple(Syncable._priority_changes),
            tuple(pn.widgets.FloatInput._priority_changes), tuple(pn.widgets.IntInput._priority_changes),
            tuple(pn.widgets.FloatSlider._priority_changes))
before = state()
import app.patches, app.inputs, app.main
print(state() == before, flush=True)
from app.inputs import IMMEDIATE
print(all("value" not in c._priority_changes for c in IMMEDIATE))
app.main.create_app()
hooked = (resources._panel_use_mathjax, [list(c._priority_changes) for c in IMMEDIATE])
print(resources._panel_use_mathjax is app.patches.holds_math, all("value" in c._priority_changes for c in IMMEDIATE),
      state()[1:] == before[1:])
app.main.create_app()
app.patches.install()
print(hooked == (resources._panel_use_mathjax, [list(c._priority_changes) for c in IMMEDIATE]))
"""
    out = subprocess.run([sys.executable, "-c", code], check=False, capture_output=True, text=True)
    assert out.stdout.split() == ["True"] * 6, out.stdout + out.stderr[-300:]


def test_the_bokehjs_patches_go_into_a_page_once():
    from bokeh.document import Document

    from app import patches

    doc = Document()
    patches.install(doc)
    patches.install(doc)
    callbacks = doc.callbacks._js_event_callbacks.get("document_ready", [])
    assert [c.code for c in callbacks] == [patches.BOKEHJS_PAINT_PATCHES, patches.BOKEHJS_SERVER_MODELS,
                                             patches.LABEL_CLICKS, patches.UPLOAD_AT_ONCE, patches.IDLE_PAINTER]


def test_a_session_builds_its_stylesheets_from_this_server():
    """A component built in a session before its page is rendered addresses Panel's stylesheets
    on this server, not on the CDN (which a server without internet cannot reach; the page then
    logged a console error after an upload). Fails if Bokeh's ``Document._template_variables``
    goes, or if Panel stops addressing stylesheets by its ``dist_url``."""
    import panel as pn
    from bokeh.document import Document
    from panel.io.resources import CDN_DIST
    from panel.io.state import set_curdoc

    from app import patches

    def urls(doc):
        with set_curdoc(doc):
            model = pn.pane.HTML("x").get_root(doc)
        return [s.url for s in model.stylesheets if hasattr(s, "url")]

    assert any(u.startswith(CDN_DIST) for u in urls(Document()))  # Panel's own default, unrendered
    doc = Document()
    patches.install(doc)
    shown = urls(doc)
    assert shown and not any(u.startswith(("http:", "https:")) for u in shown), shown
