"""What the explorer's page gets, without a browser: shared and padded axes, legends, only the
data that changed, no WebGL, a PNG name per plot, the patched Panel and Bokeh internals, a
session's memory kept flat, and hostile values from the page."""


import math

import numpy as np
import pytest

from app.curves import amplitude_bounds
from app.main import App
from core import PAPER_B
from tests.helpers import figures, rendered, xy


@pytest.fixture
def app():
    return App()


def test_axes_of_a_quantity_are_shared_and_cover_every_curve(app):
    """Plots of the same quantity share one Bokeh range (linked by their HoloViews dimension);
    after a design change it covers every curve on it, padded by 5 % of the span each side."""
    doc = rendered(app.template())
    app.state.shear_modulus_mpa = 3.3
    figs = figures(doc)
    k_f, k_a = figs["|K| against frequency"], figs["|K| against amplitude"]
    eta_f = figs["Loss factor against frequency"]
    assert k_f.y_range is k_a.y_range and k_f.x_range is eta_f.x_range
    shown = [np.concatenate([el.dimension_values(1) for el in app.plots.frame(("magnitude", a)) if el.label])
             for a in ("frequency", "amplitude")]
    both = np.concatenate(shown)
    span = both.max() - both.min()
    assert (k_f.y_range.start, k_f.y_range.end) == pytest.approx((both.min() - 0.05 * span, both.max() + 0.05 * span))
    x = xy(app.plots.frame(("magnitude", "amplitude")), "operating point")[0]
    lo, hi = np.log10(x.min()), np.log10(x.max())
    assert np.log10([k_a.x_range.start, k_a.x_range.end]) == pytest.approx([lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)])
    assert x.min() == pytest.approx(amplitude_bounds(app.state.design)[0])


def test_legends_hide_curves_on_click_and_follow_the_overlay(app):
    """A legend entry hides its curve on a click (muted, drawn transparent: HoloViews keeps a
    glyph muted through updates, not hidden); the entries follow the overlay's curves."""
    doc = rendered(app.template())
    fig = figures(doc)["|K| against frequency"]
    (legend,) = fig.legend
    assert legend.click_policy == "mute"  # and a muted curve is fully transparent: hidden
    assert {r.muted_glyph.line_alpha for item in legend.items for r in item.renderers
            if hasattr(r.muted_glyph, "line_alpha")} == {0.0}
    shown = [item.label["value"] for item in legend.items]
    assert shown == [el.label for el in app.plots.frame(("magnitude", "frequency")) if el.label]
    app.state.pin_reference()  # a new curve: a new legend entry, from HoloViews
    app.state.length_mm = 80.0
    assert "reference" in [item.label["value"] for item in legend.items]
    app.state.clear_reference()
    assert "reference" not in [item.label["value"] for item in legend.items]


def test_only_changed_data_are_sent(app):
    """An amplitude change sends the loop and the operating curves against frequency; the
    sweeps and the curves against amplitude keep their data sources untouched (the browser does
    not repaint them), and the markers on the amplitude axes move."""
    from bokeh.document.events import ColumnDataChangedEvent, ModelChangedEvent
    from bokeh.models import ColumnDataSource, Span

    doc = rendered(app.template())
    names = {}
    for title, fig in figures(doc).items():
        for item in fig.legend[0].items if fig.legend else []:
            for r in item.renderers:
                names[r.data_source.id] = (title, item.label["value"])
    events = []
    doc.on_change(events.append)
    app.state.amplitude = app.state.amplitude * 1.7
    changed = {names[e.model.id] for e in events if isinstance(e, (ModelChangedEvent, ColumnDataChangedEvent))
               and isinstance(e.model, ColumnDataSource) and e.model.id in names}
    loop_title = "Hysteresis loop at the operating point"
    expected = {(loop_title, name) for name in ("elastic", "viscoelastic", "friction", "total")}
    expected |= {(t, "operating point") for t in ("|K| against frequency", "Loss factor against frequency")}
    assert changed == expected
    moved = [e.model for e in events if isinstance(e, ModelChangedEvent) and isinstance(e.model, Span)]
    assert len(moved) == 2 and all(m.location == app.state.amplitude for m in moved)


def test_unchanged_elements_are_kept_as_they_were():
    import holoviews as hv

    from app.live import reuse_unchanged
    from app.plotting.style import curve

    x, y = hv.Dimension("x"), hv.Dimension("y")
    a = curve([1.0, np.nan], [2.0, 3.0], x, y, "a")
    same = curve([1.0, np.nan], [2.0, 3.0], x, y, "a")
    other = curve([1.0, np.nan], [2.0, 3.5], x, y, "a")
    relabelled = curve([1.0, np.nan], [2.0, 3.0], x, y, "b")
    old = hv.Overlay([a, hv.VLine(1.0)])
    assert reuse_unchanged(old, hv.Overlay([same, hv.VLine(1.0)])) is old
    kept = reuse_unchanged(old, hv.Overlay([other, hv.VLine(1.0)]))
    assert kept.get(0) is not a and kept.get(1) is old.get(1)
    assert reuse_unchanged(old, hv.Overlay([relabelled, hv.VLine(1.0)])).get(0) is not a
    assert reuse_unchanged(old, hv.Overlay([same, hv.VLine(2.0)])).get(0) is a
    assert reuse_unchanged(old, hv.Overlay([same])).get(0) is same  # another structure: all new


def test_the_page_has_no_webgl_and_each_plot_saves_its_own_png(app):
    from bokeh.models import SaveTool

    figs = figures(rendered(app.template()))
    assert {f.output_backend for f in figs.values()} == {"canvas"}
    names = {t: [tool.filename for tool in f.toolbar.tools if isinstance(tool, SaveTool)] for t, f in figs.items()}
    assert names["|K| against frequency"] == ["bushing-magnitude-vs-frequency"]
    assert names["Hysteresis loop at the operating point"] == ["bushing-hysteresis-loop"]


def test_the_panel_patches_are_in_effect():
    """app.patches changes two Panel internals (installed by create_app): fail loudly when a
    Panel upgrade removes them."""
    import inspect

    from panel.io import resources
    from panel.reactive import Syncable

    from app import patches

    patches.install()
    assert patches.PATCHED and resources._panel_use_mathjax is patches.holds_math
    # Panel still reads the priority list where it schedules a change from the page
    assert "in self._priority_changes" in inspect.getsource(Syncable._server_change)


def test_the_slider_keeps_its_own_position(app):
    """A slider move sets the amplitude to 4 digits; the slider is not sent back to it."""
    slider = app.inputs.amplitude.slider
    slider.value = -1.2345678
    assert app.state.amplitude == float(f"{10**-1.2345678:.4g}")
    assert slider.value == -1.2345678
    app.state.amplitude = 0.5  # set elsewhere (a tap): the slider follows
    assert slider.value == pytest.approx(np.log10(0.5))
    slider.value = -1.2345678
    app.state.shear_modulus_mpa = 2.5  # a new design with the same amplitude bounds
    assert slider.value == -1.2345678
    app.state.friction_strain_half = app.state.friction_strain_half * 1000  # new bounds
    lo, hi = amplitude_bounds(app.state.design)
    assert np.log10(lo) <= slider.value <= np.log10(hi)
    assert abs(slider.value - np.log10(app.state.amplitude)) <= slider.step / 2


def test_a_change_walks_the_document_only_when_it_drops_models(app):
    """app.patches.frozen_models: a change that only moves data recomputes no model set; one that
    adds glyphs (a pinned reference) attaches them without a walk of the document, and the new
    models are in it as Bokeh's walk would find them."""
    from bokeh.models import GlyphRenderer
    from panel.io.state import set_curdoc

    doc = rendered(app.template())
    with set_curdoc(doc):  # the first change gives the text panes the template's theme (new models)
        app.state.shear_modulus_mpa = 2.7
    walks = []
    recompute = doc.models.recompute
    doc.models.recompute = lambda: walks.append(1) or recompute()
    with set_curdoc(doc):
        app.state.shear_modulus_mpa = 2.8
        app.state.amplitude = 0.2
        assert walks == []
        app.state.pin_reference()
        app.state.length_mm = 80.0
    assert walks == []
    assert set(doc.models._models) == {m.id for root in doc.roots for m in root.references()}
    fig = figures(doc)["|K| against frequency"]
    (reference,) = [r for item in fig.legend[0].items if item.label["value"] == "reference" for r in item.renderers]
    assert isinstance(reference, GlyphRenderer) and doc.get_model_by_id(reference.id) is reference
    assert doc.get_model_by_id(reference.data_source.id) is reference.data_source


def test_the_private_internals_used_are_there():
    """app.patches relies on these Bokeh internals (checked against Bokeh 3.9)."""
    from bokeh.document.models import DocumentModelManager

    for name in ("_freeze_count", "_push_freeze", "_pop_freeze", "invalidate", "recompute"):
        assert hasattr(DocumentModelManager, name) or name == "_freeze_count"
    from bokeh.document import Document

    assert Document().models._freeze_count == 0


def test_the_state_and_the_curves_need_no_panel_and_no_plotting():
    """The session's state and the curves are plain Python: usable without a server or a plot."""
    import subprocess
    import sys

    code = ("import sys, app.state, app.curves, app.diagnosis_state, app.fit_state, app.targets_form, app.bands; "
            "print(sorted(m for m in ('panel', 'holoviews', 'bokeh') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_changes_add_no_styles_and_no_options_entries(app):
    """Every plotted element is a clone of a styled template: changes add no template and no
    entry to HoloViews' options store (a session's memory stays flat however long it runs)."""
    import holoviews as hv

    from app.plotting import style as elements

    app.state.shear_modulus_mpa = 2.5  # every style in use once
    app.state.amplitude = 0.3
    templates, entries = elements.template.cache_info().currsize, len(hv.Store.custom_options())
    for i in range(15):
        app.state.shear_modulus_mpa = 2.0 + 0.01 * i
        app.state.amplitude = 0.05 + 0.01 * i
    assert elements.template.cache_info().currsize == templates
    assert len(hv.Store.custom_options()) == entries


def test_hostile_values_from_the_page_leave_a_message_or_nothing(app, caplog):
    """Values a hostile page (or a slip) sends: a message beside the field, or nothing moves;
    no traceback in the log, the session goes on."""
    slider = app.inputs.amplitude.slider
    before = app.state.amplitude
    slider.value = 400.0  # 10^400 mm: beyond any float
    assert app.state.amplitude == pytest.approx(amplitude_bounds(app.state.design)[1], rel=1e-3)
    slider.value = float("nan")
    assert np.isfinite(app.state.amplitude)
    app.state.amplitude = before
    app.state.friction_strain_half = 1e-300
    assert "friction_strain_half" in app.state.errors and app.state.design == PAPER_B
    app.state.length_mm = 1e308
    assert "length_mm" in app.state.errors
    app.state.param.update(friction_strain_half=0.004, length_mm=90.0)
    assert app.state.errors == {}
    t = np.linspace(0, 10, 400, endpoint=False)
    tiny = "time_s,displacement,force\n" + "".join(
        f"{ti},{1e-16 * np.sin(2 * np.pi * 0.1 * ti)},{np.sin(2 * np.pi * 0.1 * ti)}\n" for ti in t)
    assert not app.state.load_measured_loop(tiny, "tiny.csv")
    # refused by the measured-data rule (an equivalent strain below any test's resolution), by name
    assert "tiny.csv" in app.state.data_message and "below any test's resolution" in app.state.data_message
    app.tabs.active = 3
    app.measured.stiffness_file.value = {"empty.csv": ""}  # an empty file: its own message, not the last one
    assert app.state.data_message.startswith("empty.csv: ") and "empty" in app.state.data_message
    assert not [r for r in caplog.records if r.exc_info]


def _shown_numbers(live) -> list:
    """Every number the Bokeh models of a LivePlot show: each plot's axis ranges, each element's
    data-source columns and each marker's position, in the overlays' order."""
    from app.patches import holoviews_plots

    out = []
    for pane, overlay in zip(live.panes, live.current):
        (plot,) = holoviews_plots(pane)
        out.append((plot.handles["x_range"].start, plot.handles["x_range"].end,
                    plot.handles["y_range"].start, plot.handles["y_range"].end))
        for key in overlay.data:
            handles = plot.subplots[key].handles
            if hasattr(handles.get("glyph"), "location"):
                out.append(handles["glyph"].location)
            else:
                out.append({k: np.asarray(v) for k, v in handles["source"].data.items()})
    return out


def _same_numbers(a, b) -> bool:
    if len(a) != len(b):
        return False
    for x, y in zip(a, b):
        if isinstance(x, dict):
            if set(x) != set(y) or not all(np.array_equal(x[k], y[k], equal_nan=True) for k in x):
                return False
        elif not np.allclose(x, y, rtol=1e-12, atol=0):
            return False
    return True


def test_a_change_of_numbers_shows_what_holoviews_draws_for_the_same_frames():
    """app.patches.written: frames that differ in their numbers only are written into the Bokeh
    models HoloViews made (HoloViews not asked); the plots then show exactly what HoloViews itself
    draws for those frames from scratch. A frame of another shape (a reference pinned) goes to
    HoloViews."""
    from bokeh.document import Document

    from app import curves
    from app.live import LivePlot
    from app.patches import holoviews_plots
    from app.plotting import explorer as plots

    def frames(amplitude, frequency_hz, design=PAPER_B, **kwargs):
        o = plots.explorer_overlays(curves.explorer_data(design, frequency_hz, amplitude, **kwargs))
        return [o["loop"], *(o[k] for k in plots.TITLES)]

    def drawn(overlays):
        live = LivePlot(overlays)
        doc = Document()
        for pane in live.panes:
            pane.get_root(doc)
        return live

    live = drawn(frames(0.1, 10.0))
    assert all(len(holoviews_plots(p)) == 1 for p in live.panes)  # Panel's private HoloViews._plots
    asked = []
    live.pipe.add_subscriber(lambda **_kw: asked.append(1))
    stiffer = PAPER_B.replace(shear_modulus=1.3 * PAPER_B.material.shear_modulus, length=0.9 * PAPER_B.geometry.length)
    later = frames(0.05, 20.0, stiffer)  # every number changes: design, amplitude, frequency
    live.show(later)
    assert asked == []  # written, not sent through HoloViews
    assert _same_numbers(_shown_numbers(live), _shown_numbers(drawn(later)))
    assert not _same_numbers(_shown_numbers(live), _shown_numbers(drawn(frames(0.1, 10.0))))
    pinned = frames(0.05, 20.0, stiffer, reference=PAPER_B)
    live.show(pinned)
    assert asked == [1]  # a new shape: HoloViews builds it
    assert _same_numbers(_shown_numbers(live), _shown_numbers(drawn(pinned)))


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True  # NaN, Bokeh's default of some numbers
    return type(a) is type(b) and a == b


def test_the_cached_property_defaults_are_bokehs_own(app):
    """app.patches.cache_immutable_defaults keeps Bokeh's property defaults per (property, class):
    for every property of every Bokeh and Panel model class, read through the cache (twice: the
    second read is the cached one) and through Bokeh's own ``themed_default``, the same immutable
    value; and any other default (a list, a dict, a set, a model) a new one at each read, as Bokeh
    makes it (an empty container: a new empty one of Bokeh's type, from the cache)."""
    import inspect

    from bokeh.core.has_props import HasProps
    from bokeh.core.property.bases import Property
    from bokeh.core.property.descriptors import PropertyDescriptor

    from app import patches

    patches.install()
    ours = Property.themed_default
    assert ours.cached_by_bushing
    assert list(inspect.signature(ours.original).parameters) == ["self", "cls", "name", "theme_overrides", "no_eval"]
    classes, seen, containers, empties = [HasProps], set(), 0, 0
    while classes:
        cls = classes.pop()
        classes.extend(c for c in cls.__subclasses__() if c not in seen)
        seen.add(cls)
    checked = 0
    for cls in seen:
        for name in cls.properties():
            prop = cls.lookup(name).property
            bokeh = ours.original(prop, cls, name, None)
            if patches._immutable(bokeh):
                for _ in range(2):
                    cached = ours(prop, cls, name, None)
                    assert _same(cached, bokeh), (cls, name, cached, bokeh)
                    checked += 1
            elif isinstance(bokeh, (list, dict, set, HasProps)):  # a new one at each read
                containers += 1
                first, second = ours(prop, cls, name, None), ours(prop, cls, name, None)
                assert first is not second, (cls, name)
                if not isinstance(bokeh, HasProps) and not bokeh:  # empty: its type kept, Bokeh's value
                    empties += 1
                    assert _same(first, bokeh) and _same(second, bokeh), (cls, name, first, bokeh)
            descriptor, bare = cls.lookup(name), object.__new__(cls)  # an instance's class is all it reads
            if isinstance(descriptor, PropertyDescriptor):  # not an alias of another property
                ask = descriptor.has_unstable_default
                assert ask(bare) is ask(bare) is ask.original(descriptor, bare), (cls, name)
    assert len(seen) > 300 and checked > 10_000 and containers > 100 and empties > 1000, (
        len(seen), checked, containers, empties)


def test_holoviews_makes_no_selection_glyph_model_where_no_selection_style(monkeypatch):
    """app.patches.selection_glyphs_auto: HoloViews' ``ElementPlot._update_glyph`` makes a Bokeh model
    of a glyph renderer's ``"auto"`` selection glyph (the internal this saves: it still does, and
    still takes these arguments); with the hook, a curve's renderer has none (BokehJS clones the
    glyph for it, as for "auto"), and a curve styled for selections keeps HoloViews' model."""
    import inspect

    import holoviews as hv
    from bokeh.models import GlyphRenderer
    from holoviews.plotting.bokeh.element import ElementPlot

    from app import patches

    patches.install()
    ours = ElementPlot._update_glyph
    assert ours.by_bushing
    assert list(inspect.signature(ours.original).parameters) == [
        "self", "renderer", "properties", "mapping", "glyph", "source", "data"]

    def selection_glyphs(element):
        fig = hv.render(element, backend="bokeh")
        return [r.selection_glyph for r in fig.references() if isinstance(r, GlyphRenderer)]

    assert selection_glyphs(hv.Curve([1, 3, 2])) == [None]
    styled = selection_glyphs(hv.Curve([1, 3, 2]).opts(selection_color="red"))
    assert [(type(g).__name__, g.line_color) for g in styled] == [("Line", "red")]
    monkeypatch.setattr(ElementPlot, "_update_glyph", ours.original)
    assert [type(g).__name__ for g in selection_glyphs(hv.Curve([1, 3, 2]))] == ["Line"]


def _sheet_names(sheets) -> list[str]:
    return [getattr(s, "url", None) or str(s)[:60] for s in sheets]


def test_the_page_design_styles_a_component_as_a_part_of_the_page():
    """Panel's Bootstrap design styles a component asked for alone (``Design.params``: Panel asks so
    for a model made after the page was built, and at every text change of an HTML pane) with
    Bootstrap's whole stylesheet and the theme's; the page's design (:class:`app.patches.PageDesign`)
    gives the stylesheets the template gives the same component at page build."""
    import panel as pn
    from panel.theme import Bootstrap

    from app import patches

    assert patches.PATCHED
    pane = pn.pane.HTML("x")
    alone = _sheet_names(Bootstrap().params(pane)[0]["stylesheets"])
    assert any("bootstrap.min.css" in n for n in alone)  # Panel's own: what the patch is for
    ours = _sheet_names(patches.PageDesign().params(pane)[0]["stylesheets"])
    modifiers, _children = Bootstrap._get_modifiers(pane, Bootstrap().theme, isolated=False)
    assert ours == [str(s) for s in modifiers["stylesheets"]]
    assert not any("bootstrap.min.css" in n or "default.css" in n for n in ours)


def test_no_component_of_a_page_carries_bootstraps_whole_stylesheet():
    """A served page, its lazily built *Find the missing effect* tab opened and its texts changed (data
    loaded): no model of the page has Bootstrap's whole stylesheet (36 had it after a diagnosis, each
    in its own shadow root, and Chromium weighed its rules at every stylesheet change of the page)."""
    from panel.io.state import set_curdoc

    from app.tabs.find_the_missing_effect import DiagnosisView
    from core.synthetic import synthetic_stiffness

    app = App()
    doc = rendered(app.template())

    with set_curdoc(doc):
        app.tabs.active = 1 + [title for title, _name, _build in App.LAZY_TABS].index("Find the missing effect")
        view = app.view("diagnosis")
        assert isinstance(view, DiagnosisView)
        data = synthetic_stiffness(PAPER_B, np.linspace(1, 100, 5), [1e-4, 3e-4], noise=0.0, seed=1)
        view.state.load_csv(data.to_csv())
    sheets = [n for m in doc.models if hasattr(m, "stylesheets") for n in _sheet_names(m.stylesheets)]
    assert len(sheets) > 100  # the page's components and their stylesheets are there
    assert not [n for n in sheets if "bootstrap.min.css" in n]
