"""The public plotting API (app.plots) from plain Python: no server, no notebook, no hv.extension."""

import holoviews as hv
import numpy as np
import pytest
from bokeh.models import Plot
from numpy.testing import assert_allclose

from app import plots
from core import PAPER_B, TABLE_1, stiffness, stiffness_points
from core.synthetic import paper_b_example
from tests.helpers import marker_at, xy


def titles(layout):
    return [ov.opts.get().kwargs["title"] for ov in layout]


def test_explorer_plots_hold_the_core_numbers_on_named_dimensions():
    layout = plots.explorer_plots(PAPER_B, frequency_hz=20.0, amplitude=0.2)
    assert titles(layout) == ["Hysteresis loop at the operating point", "|K| against frequency",
                              "Loss factor against frequency", "|K| against amplitude", "Loss factor against amplitude"]
    k_f = layout[1]
    f, k = xy(k_f, "operating point")
    assert_allclose(k, stiffness(PAPER_B, f, 0.2e-3).magnitude[0] / 1e6, rtol=1e-12)
    assert marker_at(k_f) == 20.0 and marker_at(layout[3]) == 0.2
    dims = {d.name: (d.label, d.unit) for d in k_f.get(0).dimensions()}
    assert dims == {"frequency_hz": ("Frequency", "Hz"), "magnitude": ("|K|", "kN/mm")}
    # plots of the same quantity carry the same axis range, covering every curve on them
    y = np.concatenate([el.dimension_values(1) for ov in (layout[1], layout[3]) for el in ov if el.label])
    low, high = k_f.get(0).vdims[0].range
    assert low < y.min() and y.max() < high and layout[3].get(0).vdims[0].range == (low, high)
    widths = {p.width for p in hv.render(layout).select({"type": Plot})}
    assert widths == {600}


def test_torsion_units_and_measured_points():
    data, _loop = paper_b_example(PAPER_B)
    layout = plots.explorer_plots(PAPER_B, 10.0, 0.1, measured=data, width=None)
    x, k = xy(layout[1], "measured")
    assert_allclose(k, data.magnitude / 1e6) and len(x) == len(data)
    torsion = plots.explorer_plots(TABLE_1)
    assert (torsion[0].get(0).kdims[0].unit, torsion[1].get(0).vdims[0].unit) == ("rad", "N·m/rad")
    assert torsion[0].get(0).kdims[0].label == "Angle"


def test_slices_branches_residuals_and_diagnosis_plots():
    from core.identify.diagnose import diagnose

    sl = plots.slices_plots(PAPER_B, 10.0, 0.1)
    x, k3 = xy(sl[0], "3 slices")
    assert_allclose(k3, stiffness(PAPER_B, 10.0, x * 1e-3, slices=3).magnitude[:, 0] / 1e6, rtol=1e-12)
    br = plots.branch_plots(PAPER_B, 10.0, 0.1)
    top = br[0].get(2)  # the friction band, on top: it ends at Re K
    assert_allclose(top.dimension_values(1), stiffness(PAPER_B, 10.0, top.dimension_values(0) * 1e-3).stiffness.real[:, 0] / 1e6,
                    rtol=1e-12)
    data, _ = paper_b_example(PAPER_B)
    res = plots.residual_plots(PAPER_B, data)
    _, r = xy(res[0], "residual")
    k = stiffness_points(PAPER_B, data.frequency_hz, data.amplitude)
    assert_allclose(r, 100 * (np.abs(k) / data.magnitude - 1))
    d = diagnose(PAPER_B, data, held_out=False)
    diag = plots.diagnosis_plots(d)
    assert len(diag) == 7 and titles(diag)[0].startswith("Gap")
    for layout in (sl, br, res, diag):
        assert hv.render(layout) is not None


@pytest.mark.parametrize("width, expected", [(None, (None, "stretch_width")), (450, (450, "fixed")),
                                             ("default", (800, "fixed"))])
def test_widths(width, expected):
    """A width in pixels is that width, fixed; None is no width, stretched to the container's."""
    layout = plots.slices_plots(PAPER_B) if width == "default" else plots.slices_plots(PAPER_B, width=width)
    rendered = list(hv.render(layout).select({"type": Plot}))
    assert len(rendered) == 3 and {(p.width, p.sizing_mode) for p in rendered} == {expected}
    assert all(ov.opts.get().kwargs.get("responsive") is (width is None) for ov in layout)
