"""The diagnosis report's plots (issue #27, item 16): made while the data wait to be diagnosed,
the report's numbers then written into them. The report's push creates no Bokeh model and renders
no HoloViews plot again, and what it leaves in the models is what HoloViews draws from the
report itself."""

import numpy as np
import pytest
from bokeh.document import Document
from panel.io.state import set_curdoc

from app import patches
from app.live import LivePlot, one_change
from app.main import App
from app.plotting.find_the_missing_effect import diagnosis_overlays
from core import PAPER_B
from core.synthetic import synthetic_stiffness

NAMES = ("gap", "curves", "maps")


def csv(frequencies, amplitudes, seed=3) -> str:
    hidden = PAPER_B.replace(effects={"inertia": {"mass": 0.5}})
    return synthetic_stiffness(hidden, frequencies, amplitudes, noise=0.005, seed=seed).to_csv()


def page(content: str):
    """A session's page in a Bokeh document, the diagnosis tab shown, ``content`` loaded."""
    app, doc = App(), Document()
    with set_curdoc(doc):
        app.template().server_doc(doc)
        app.tabs.active = next(i for i, (_t, name, _b) in enumerate(app.LAZY_TABS, 1) if name == "diagnosis")
        assert app.diagnosis.state.load_csv(content, "inertia.csv")
    return app, doc


def push(app, doc, result):
    """The result stored as the tab stores it when its work ends."""
    with set_curdoc(doc), one_change():
        app.diagnosis.state.param.update(result=result, running=False, progress=1.0)


def drawn(plot) -> dict:
    """What a HoloViews plot's Bokeh models show: title, axes, each element's columns, lines and
    colour scales."""
    ranges = {}
    for axis in ("x_range", "y_range"):
        model = plot.handles[axis]
        ranges[axis] = list(model.factors) if hasattr(model, "factors") else (model.start, model.end)
    out = {"title": plot.state.title.text, "ranges": ranges,
           "labels": (plot.handles["xaxis"].axis_label, plot.handles["yaxis"].axis_label), "elements": {}}
    for key, sub in plot.subplots.items():
        glyph = sub.handles.get("glyph")
        columns = {k: np.asarray(v) for k, v in sub.handles["source"].data.items()}
        out["elements"][key] = {
            "columns": columns, "visible": sub.handles.get("glyph_renderer", glyph).visible,
            "location": getattr(glyph, "location", None),
            "colours": [(m.low, m.high) for k, m in sub.handles.items() if k.endswith("_color_mapper")]}
    return out


def assert_same(a, b):
    assert a["title"] == b["title"] and a["labels"] == b["labels"]
    assert a["ranges"].keys() == b["ranges"].keys()
    for axis, rng in a["ranges"].items():
        if isinstance(rng, list):
            assert rng == b["ranges"][axis]
        else:
            np.testing.assert_allclose(rng, b["ranges"][axis], rtol=1e-12)
    shown = [{k: el for k, el in x["elements"].items() if el["visible"]} for x in (a, b)]  # a plot that had
    assert shown[0].keys() == shown[1].keys()  # more elements before keeps them hidden (HoloViews)
    for key, el in shown[0].items():
        other = shown[1][key]
        assert el["columns"].keys() == other["columns"].keys(), key
        for column, values in el["columns"].items():
            if values.dtype.kind in "fi":
                np.testing.assert_allclose(values, other["columns"][column], rtol=1e-12, err_msg=str(key))
            else:
                assert list(values) == list(other["columns"][column]), key
        if el["location"] is not None:
            assert el["location"] == pytest.approx(other["location"], rel=1e-12)
        np.testing.assert_allclose(el["colours"], other["colours"], rtol=1e-12)


def plots_of(live: LivePlot) -> list:
    return [patches.holoviews_plots(pane)[0] for pane in live.panes]


def fresh(result) -> dict:
    """The report's plots as HoloViews draws them from the report alone, in a document of their own."""
    overlays, doc, out = diagnosis_overlays(result), Document(), {}
    with set_curdoc(doc):
        for name in NAMES:
            live = LivePlot(overlays[name])
            live.grid().get_root(doc)
            out[name] = [drawn(plot) for plot in plots_of(live)]
    return out


@pytest.fixture(scope="module")
def diagnosed():
    """A page with 150 points loaded, and their diagnosis (run once)."""
    content = csv(np.linspace(1, 100, 30), [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3])
    app, _doc = page(content)
    return content, app.diagnosis.state.compute()


def test_the_report_is_written_into_plots_made_for_the_data(diagnosed):
    """Loading the data makes the report's plots (hidden); the report's push then creates no Bokeh
    model and no HoloViews plot (on 63e5360: 560 models, seven plots built after the work)."""
    content, result = diagnosed
    app, doc = page(content)
    view = app.diagnosis
    assert not view._results.visible and set(view.live) == set(NAMES)
    plots = {name: plots_of(view.live[name]) for name in NAMES}
    assert all(len(p) == n for (name, p), n in zip(plots.items(), (1, 2, 4)))
    models = {m.id for m in doc.models}
    push(app, doc, result)
    assert view._results.visible and "What is left is noise" in view.report.object
    assert {m.id for m in doc.models} == models
    assert {name: plots_of(view.live[name]) for name in NAMES} == plots
    # and what the models show is what HoloViews draws from the report itself
    expected = fresh(app.diagnosis.state.shown())
    for name in NAMES:
        for plot, want in zip(plots[name], expected[name], strict=True):
            assert_same(drawn(plot), want)


def test_other_data_then_their_report_draw_as_holoviews_does(diagnosed):
    """After a report, data of another shape (three amplitudes, other frequencies): the plots take
    their shape, and their report is again what HoloViews draws from it."""
    content, result = diagnosed
    app, doc = page(content)
    push(app, doc, result)
    state = app.diagnosis.state
    with set_curdoc(doc):
        assert state.load_csv(csv(np.geomspace(2, 60, 12), [0.02e-3, 0.1e-3, 0.3e-3], seed=5), "other.csv")
    assert not app.diagnosis._results.visible
    models = {m.id for m in doc.models}
    push(app, doc, state.compute())
    assert {m.id for m in doc.models} == models
    expected = fresh(state.shown())
    for name in NAMES:
        for plot, want in zip(plots_of(app.diagnosis.live[name]), expected[name], strict=True):
            assert_same(drawn(plot), want)
