"""A mode switch in the explorer (issue #27, item 16: ≤ 300 ms to screen): the plots keep their
Bokeh models, their numbers and words are written into them (HoloViews is not asked to draw the
plots again), and they show what HoloViews itself draws for the new mode from scratch."""

import numpy as np
import pytest
from bokeh.models import HoverTool

from app import units
from app.main import App
from tests.helpers import figures, rendered


def _drawn(fig) -> dict:
    """What a figure shows in words and axes: its axis labels, hover tooltips and axis ranges
    (and where its Reset tool returns them), and the columns of its glyphs' data sources (by legend label)."""
    sources = {r.name: {k: np.asarray(v) for k, v in r.data_source.data.items()}
               for r in fig.renderers if hasattr(r, "data_source") and r.name}
    return {"x": fig.xaxis[0].axis_label, "y": fig.yaxis[0].axis_label,
            "tips": [list(t.tooltips) for t in fig.toolbar.tools if isinstance(t, HoverTool)],
            "ranges": (fig.x_range.start, fig.x_range.end, fig.y_range.start, fig.y_range.end,
                       fig.x_range.reset_start, fig.x_range.reset_end, fig.y_range.reset_start, fig.y_range.reset_end),
            "sources": sources}


def _same(a: dict, b: dict) -> bool:
    if (a["x"], a["y"], a["tips"]) != (b["x"], b["y"], b["tips"]) or set(a["sources"]) != set(b["sources"]):
        return False
    if not np.allclose(a["ranges"], b["ranges"], rtol=1e-9, atol=0):
        return False
    return all(set(a["sources"][n]) == set(b["sources"][n])
               and all(np.allclose(a["sources"][n][k], b["sources"][n][k], rtol=1e-9, equal_nan=True)
                       for k in a["sources"][n])
               for n in a["sources"])


BANDS = {"tolerance_text": "mu:10,L:1", "band_on": True}


def _fresh(state) -> dict:
    """The explorer's figures drawn by HoloViews from scratch, in the mode, at the amplitude and
    with the bands of ``state`` (an ExplorerState: a switch converts the amplitude at equal
    strain, to 3 digits)."""
    app = App()
    app.state.param.update(tolerance_text=state.tolerance_text, band_on=state.band_on)
    app.state.mode = state.mode
    app.state.amplitude = state.amplitude
    return {t: _drawn(f) for t, f in figures(rendered(app.template())).items()}


@pytest.mark.parametrize(("mode", "bands"), [("torsion", False), ("conical", False), ("radial", False),
                                             ("torsion", True)])
def test_a_mode_switch_is_written_into_the_models_holoviews_made(mode, bands):
    """Axial → ``mode`` → axial (with tolerance bands if ``bands``: their tooltips name the band's
    top in the new unit too): no plot is drawn again by HoloViews (no Pipe event: counted), the
    document keeps every model it had, and each figure shows the axis labels, tooltips (the new
    units), ranges and data HoloViews draws for that mode from scratch."""
    app = App()
    if bands:
        app.state.param.update(**BANDS)
    doc = rendered(app.template())
    asked = []
    for live in (app.plots.loop, app.plots.grid):
        live.pipe.add_subscriber(lambda **_kw: asked.append(1))
    plotted = lambda: {m.id for fig in figures(doc).values() for m in fig.references()}
    models = plotted()
    axial = {t: _drawn(f) for t, f in figures(doc).items()}
    app.state.mode = mode
    assert asked == []  # written, not sent through HoloViews
    assert plotted() == models  # no Bokeh model of a plot made again, none added or removed
    now, fresh = {t: _drawn(f) for t, f in figures(doc).items()}, _fresh(app.state)
    assert set(now) == set(fresh)
    changed = [t for t in now if now[t]["x"] != axial[t]["x"] or now[t]["y"] != axial[t]["y"]]
    assert bool(changed) == (units.amplitude_unit(mode) != units.amplitude_unit("axial"))  # new units: new words
    assert [t for t in now if not _same(now[t], fresh[t])] == []
    app.state.mode = "axial"
    assert asked == []
    back = {t: _drawn(f) for t, f in figures(doc).items()}
    assert back["Hysteresis loop at the operating point"]["x"] == axial["Hysteresis loop at the operating point"]["x"]
    fresh = _fresh(app.state)
    assert [t for t in back if not _same(back[t], fresh[t])] == []
