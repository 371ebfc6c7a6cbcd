"""The public plotting API (app.plots) from plain Python: no server, no notebook, no hv.extension."""

import holoviews as hv
import numpy as np
import pytest
from bokeh.models import Plot
from numpy.testing import assert_allclose

from app import plots
from app.plotting import explorer, fletcher_gent
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


def axes(overlay):
    """Every dimension of every element of ``overlay``, with its range."""
    return [(d.name, tuple(d.range)) for el in overlay for d in el.dimensions()]


def test_a_plot_keeps_its_axes_when_the_same_dimensions_draw_another_design():
    """Ranges are set per plot: drawing a very different design on the same dimensions (as a live
    view does) leaves the plots built before, and the dimensions passed, as they were."""
    from app import curves

    dims = plots.dimensions("axial")
    given = [(d.name, tuple(d.range)) for d in dims.values()]
    stiff = PAPER_B.replace(shear_modulus=100 * PAPER_B.material.shear_modulus)
    first = explorer.explorer_overlays(curves.explorer_data(PAPER_B, 10.0, 0.1), dims)
    shape = fletcher_gent.loop_shape_overlay(curves.hysteresis_loop(PAPER_B, 10.0, 0.1), dims)
    before = {k: axes(ov) for k, ov in first.items()}
    k_f = first[("magnitude", "frequency")]
    assert k_f.get(0).vdims[0].range[1] < 1e3  # |K| in kN/mm: PAPER_B's
    second = explorer.explorer_overlays(curves.explorer_data(stiff, 50.0, 0.5, freq_range=(100.0, 200.0)), dims)
    assert second[("magnitude", "frequency")].get(0).vdims[0].range[0] > k_f.get(0).vdims[0].range[1]
    assert {k: axes(ov) for k, ov in first.items()} == before
    assert [(d.name, tuple(d.range)) for d in dims.values()] == given
    assert ("drive_rel", (-1.05, 1.05)) in axes(shape) and ("drive_rel", (None, None)) in given


def test_importing_the_plotting_api_changes_nothing_global():
    """Importing app.plots leaves HoloViews' Bokeh renderer (WebGL on by default) and its
    options as they were; the plots ask for canvas themselves."""
    import subprocess
    import sys

    code = """
import holoviews as hv, holoviews.plotting.bokeh
def snapshot():
    r = hv.renderer("bokeh")
    return (sorted((k, repr(v)) for k, v in r.param.values().items()), hv.Store.current_backend,
            sorted(hv.Store.options().keys()), len(hv.Store.custom_options()))
before = snapshot()
import app.plots, app.plotting.style
print(before == snapshot(), hv.renderer("bokeh").webgl)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["True", "True"], out.stdout


def test_the_plots_draw_on_canvas_with_webgl_asked_for():
    renderer = hv.renderer("bokeh")
    webgl = renderer.webgl
    renderer.webgl = True  # HoloViews' default, as in a notebook
    try:
        layout = plots.explorer_plots(PAPER_B, 10.0, 0.1)
        figs = list(hv.render(layout).select({"type": Plot}))
    finally:
        renderer.webgl = webgl
    assert len(figs) == 5 and {f.output_backend for f in figs} == {"canvas"}


def test_the_explorer_s_sweeps_are_built_once_per_design_sweep_range_and_axes():
    """The sweep curves of a plot are a cached function of their values (explorer.sweep_layer):
    moving the operating point along them finds the same curve objects (a live plot sends them
    no data); another design builds new ones; each carries its plot's ranges."""
    from app import curves

    def sweeps(design, f, x):
        data = curves.explorer_data(design, f, x)
        return data, [el for el in explorer.explorer_overlays(data)[("magnitude", "frequency")]
                      if el.label.startswith("ε̂")]

    data, first = sweeps(PAPER_B, 10.0, 0.1)
    _, moved = sweeps(PAPER_B, 20.0, 0.11)
    _, other = sweeps(PAPER_B.replace(length=0.05), 10.0, 0.1)
    assert len(first) == len(curves.SWEEP_STRAINS) and all(a is b for a, b in zip(first, moved))
    assert not any(a is b for a, b in zip(first, other))
    assert tuple(first[0].vdims[0].range) == tuple(data.ranges["magnitude"])
    k = stiffness(PAPER_B, data.sweeps["frequency"]["frequency_hz"],
                  PAPER_B.drive(curves.SWEEP_STRAINS[0] * PAPER_B.material.friction_strain_half)).magnitude[0]
    assert_allclose(first[0].dimension_values(1), k / 1e6, rtol=1e-12)
