"""The explorer without a browser: build a session, set parameters, check what the plots hold
against the core."""

import csv
import io
import logging
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from app.main import App, create_app
from app.state import ExplorerState
from core import PAPER_B, TABLE_1, loads_design, loop, stiffness, stiffness_points
from tests.helpers import element, figures, marker_at, rendered, xy


@pytest.fixture
def app():
    return App()


def overlay(app, quantity, axis):
    """What one of the explorer's four stiffness plots shows now (a HoloViews Overlay)."""
    return app.plots.frame((quantity, axis))


def data(ov, label):
    return xy(ov, label)


def test_factory_builds_a_fresh_session_each_time():
    a, b = create_app(), create_app()
    assert a is not b
    s1, s2 = ExplorerState(), ExplorerState()
    s1.shear_modulus_mpa = 3.0
    assert s2.shear_modulus_mpa == 2.42  # sessions never share state


def test_the_page_gets_the_mathjax_script_only_if_a_text_holds_math():
    import panel as pn
    from bokeh.document import Document
    from panel.io.resources import Resources, bundle_resources

    def scripts(viewable):
        doc = Document()
        viewable.server_doc(doc)
        return [str(f).split("?")[0].rsplit("/", 1)[-1] for f in bundle_resources(doc.roots, Resources(mode="server")).js_files]

    explorer = scripts(create_app())
    assert {"bokeh.min.js", "bokeh-widgets.min.js", "panel.min.js"} <= set(explorer)
    assert "bokeh-mathjax.min.js" not in explorer
    assert "bokeh-mathjax.min.js" in scripts(pn.Column(pn.pane.Markdown("Energy $$E = mc^2$$")))
    assert "bokeh-mathjax.min.js" not in scripts(pn.Column(pn.pane.Markdown("It costs $5, or $6.")))


def test_defaults_are_the_paper_b_bushing(app):
    assert app.state.design == PAPER_B
    assert app.state.errors == {}


def test_frequency_plot_holds_the_core_stiffness(app):
    s = app.state
    f, k = data(overlay(app, "magnitude", "frequency"), "operating point")
    ref = stiffness(PAPER_B, f, s.amplitude * 1e-3)
    assert_allclose(k, ref.magnitude[0] / 1e6, rtol=1e-12)
    _, eta = data(overlay(app, "loss_factor", "frequency"), "operating point")
    assert_allclose(eta, ref.loss_factor[0], rtol=1e-12)
    curve = element(overlay(app, "magnitude", "frequency"), "operating point")
    assert [(d.name, d.label, d.unit) for d in curve.dimensions()] == [
        ("frequency_hz", "Frequency", "Hz"), ("magnitude", "|K|", "kN/mm")]
    # the sweeps are at equivalent strains of 0.01, 0.1, 1 and 10 times ε½
    from core import strain_factor

    c = strain_factor(PAPER_B.geometry, "axial")
    for ratio, label in zip((0.01, 0.1, 1, 10), ("ε̂ = 0.01 ε½", "ε̂ = 0.1 ε½", "ε̂ = ε½", "ε̂ = 10 ε½")):
        x = ratio * PAPER_B.material.friction_strain_half / c
        _, k = data(overlay(app, "magnitude", "frequency"), label)
        assert_allclose(k, stiffness(PAPER_B, f, x).magnitude[0] / 1e6, rtol=1e-12)


def test_amplitude_plot_holds_the_core_stiffness_in_torsion(app):
    s = app.state
    s.preset = "Table 1 bushing (torsion)"
    assert s.design == TABLE_1
    x, k = data(overlay(app, "magnitude", "amplitude"), "operating point")
    ref = stiffness(TABLE_1, s.frequency_hz, x)
    assert_allclose(k, ref.magnitude[:, 0], rtol=1e-12)
    fig = figures(rendered(app.template()))["|K| against amplitude"]
    assert fig.xaxis[0].axis_label == "Amplitude (rad)" and fig.yaxis[0].axis_label == "|K| (N·m/rad)"
    # the amplitude axis spans the Fletcher–Gent range: ε̂/ε½ from 1e-3 to 1e2
    from core import strain_factor

    z = strain_factor(TABLE_1.geometry, "torsion") * x / TABLE_1.material.friction_strain_half
    assert_allclose([z.min(), z.max()], [1e-3, 1e2], rtol=1e-9)


def test_loop_holds_the_core_loop_and_its_branches(app):
    s = app.state
    s.amplitude, s.frequency_hz = 0.5, 3.0
    ref = loop(PAPER_B, 3.0, 0.5e-3, 200)
    x, force = data(app.plots.frame("loop"), "total")
    assert_allclose(x[:-1], ref.displacement * 1e3, atol=1e-12)
    assert_allclose(force[:-1], ref.force, rtol=1e-12, atol=1e-9)
    assert force[0] == force[-1]  # closed
    for name in ("elastic", "viscoelastic", "friction"):
        assert_allclose(data(app.plots.frame("loop"), name)[1][:-1], getattr(ref, f"force_{name}"), rtol=1e-12,
                        atol=1e-9)
    assert "0.5 mm, 3 Hz" in app.plots.summary.object


def test_moving_a_widget_changes_the_plots(app):
    before = data(overlay(app, "magnitude", "frequency"), "operating point")[1]
    app.inputs.widgets["shear_modulus_mpa"].value = 3.0
    after = data(overlay(app, "magnitude", "frequency"), "operating point")[1]
    assert app.state.design.material.shear_modulus == pytest.approx(3.0e6)
    assert np.all(after > before)


def test_log_slider_sets_the_amplitude_and_follows_it(app):
    slider = app.inputs.amplitude.slider
    slider.value = np.log10(0.5)
    assert app.state.amplitude == pytest.approx(0.5, rel=1e-3)
    app.state.amplitude = 2.0
    assert slider.value == pytest.approx(np.log10(2.0))


def test_tap_moves_the_operating_point_in_every_plot(app):
    tap = app.plots.grid.tap_streams[0]  # the HoloViews Tap stream of |K| against frequency
    tap.event(x=42.0, y=5.0)
    assert app.state.frequency_hz == pytest.approx(42.0)
    for quantity in ("magnitude", "loss_factor"):
        assert marker_at(overlay(app, quantity, "frequency")) == pytest.approx(42.0)
        x, k = data(overlay(app, quantity, "amplitude"), "operating point")
        ref = stiffness(PAPER_B, 42.0, x * 1e-3)
        expected = ref.magnitude[:, 0] / 1e6 if quantity == "magnitude" else ref.loss_factor[:, 0]
        assert_allclose(k, expected, rtol=1e-12)
    app.plots.grid.tap_streams[3].event(x=0.03, y=0.1)  # loss factor against amplitude
    assert app.state.amplitude == pytest.approx(0.03)
    assert marker_at(overlay(app, "magnitude", "amplitude")) == pytest.approx(0.03)
    assert "0.03 mm, 42 Hz" in app.plots.summary.object
    app.plots.tap_amplitude(-1.0)  # outside: ignored
    assert app.state.amplitude == pytest.approx(0.03)


def test_invalid_input_keeps_the_last_good_design_and_says_why(app):
    good = data(overlay(app, "magnitude", "frequency"), "operating point")[1]
    app.state.outer_radius_mm = 15.0  # below a = 20 mm
    assert app.state.errors == {"outer_radius_mm": "Must be larger than the inner radius a."}
    assert app.state.design == PAPER_B
    assert_allclose(data(overlay(app, "magnitude", "frequency"), "operating point")[1], good)
    app.state.fractional_order = 1.4
    app.state.length_mm = None
    assert set(app.state.errors) == {"outer_radius_mm", "fractional_order", "length_mm"}
    app.state.param.update(outer_radius_mm=35.0, fractional_order=0.2, length_mm=90.0)
    assert app.state.errors == {} and app.state.design == PAPER_B


def test_sweep_range_errors(app):
    app.state.freq_max = 0.5
    assert "freq_max" in app.state.errors
    f = data(overlay(app, "magnitude", "frequency"), "operating point")[0]
    assert f.min() > 0 and f.max() > f.min()


def test_mode_change_keeps_the_equivalent_strain(app):
    from core import strain_factor

    s = app.state
    s.amplitude = 0.2  # mm, axial
    eps = strain_factor(s.design.geometry, "axial") * 0.2e-3
    s.mode = "torsion"
    assert s.design.mode == "torsion"
    assert strain_factor(s.design.geometry, "torsion") * s.amplitude == pytest.approx(eps, rel=1e-2)


def test_link_values_are_applied_one_by_one():
    s = ExplorerState()
    s.apply_url_values({"shear_modulus_mpa": 3.1, "amplitude": -1.0, "length_mm": 80.0})
    assert s.shear_modulus_mpa == 3.1 and s.length_mm == 80.0
    assert "amplitude" in s.errors


def test_slices_view_holds_the_core_numbers(app):
    data = app.state.slice_comparison()
    x = data["amplitude"] * 1e-3
    for sl in (1, 2, 3, "continuum"):
        ref = stiffness(PAPER_B, app.state.frequency_hz, x, slices=sl)
        assert_allclose(data["magnitude"][sl], ref.magnitude[:, 0] / 1e6, rtol=1e-12)
    k1 = stiffness(PAPER_B, app.state.frequency_hz, x).magnitude[:, 0]
    k3 = stiffness(PAPER_B, app.state.frequency_hz, x, slices=3).magnitude[:, 0]
    assert_allclose(data["magnitude_diff_pct"][3], 100 * (k3 / k1 - 1), rtol=1e-9)
    assert "3 slices" in app.slices.summary(data)
    app.tabs.active = 1  # shown: its figures hold the same numbers
    x, k = xy(app.slices.frame("magnitude"), "3 slices")
    assert_allclose(k, stiffness(PAPER_B, app.state.frequency_hz, x * 1e-3, slices=3).magnitude[:, 0] / 1e6, rtol=1e-12)


def test_teaching_branches_add_up_to_the_stiffness(app):
    d = app.state.branch_breakdown()
    x = d["amplitude"] * 1e-3
    ref = stiffness(PAPER_B, app.state.frequency_hz, x)
    assert_allclose(sum(d["real"].values()), ref.stiffness.real[:, 0] / 1e6, rtol=1e-12)
    assert_allclose(sum(d["loss"].values()), ref.loss_factor[:, 0], rtol=1e-12)
    assert np.all(d["loss"]["elastic"] == 0)
    app.tabs.active = 2
    band = element(app.teaching.frame("real"), "friction")  # the top band: from the others to the total
    assert_allclose(band.dimension_values(1), ref.stiffness.real[:, 0] / 1e6, rtol=1e-12)
    assert_allclose(band.dimension_values(2), (d["real"]["elastic"] + d["real"]["viscoelastic"]), rtol=1e-12)
    app.teaching.player.value = 3
    x = np.geomspace(*app.state.amplitude_bounds, app.teaching.FRAMES)[3]
    assert f"{x:.3g} mm" in app.teaching.frame_label.object
    shape = loop(PAPER_B, app.state.frequency_hz, x * 1e-3, 200)
    _, f = xy(app.teaching.frame("loop"), "total")
    assert_allclose(f[:-1], shape.force / np.max(np.abs(shape.force)), rtol=1e-9, atol=1e-12)


def test_comparison_with_a_pinned_reference(app):
    s = app.state
    assert s.comparison() is None
    s.pin_reference()
    s.length_mm = 99.0  # stiffness ∝ L: +10 %
    c = s.comparison()
    assert c["operating"]["magnitude"][2] == pytest.approx(10.0, rel=1e-9)
    assert c["operating"]["loss_factor"][2] == pytest.approx(0.0, abs=1e-9)
    assert c["largest_over_frequency"]["magnitude"] == pytest.approx(10.0, rel=1e-9)
    ref = data(overlay(app, "magnitude", "frequency"), "reference")[1]
    assert_allclose(ref * 1.1, data(overlay(app, "magnitude", "frequency"), "operating point")[1], rtol=1e-12)
    _, ref_loop = data(app.plots.frame("loop"), "reference")
    assert_allclose(ref_loop * 1.1, data(app.plots.frame("loop"), "total")[1], rtol=1e-12)
    assert "+10.00 %" in app.compare.table(s.reference, s.design, s.frequency_hz, s.amplitude, s.errors)
    s.clear_reference()
    assert s.comparison() is None
    assert "reference" not in [el.label for el in overlay(app, "magnitude", "frequency")]


def test_exports_are_the_public_formats(app):
    app.state.shear_modulus_mpa = 2.9
    design = loads_design(app.export._design_json().getvalue())
    assert design == app.state.design
    rows = list(csv.reader(io.StringIO(app.export._table_csv().getvalue())))
    assert rows[0] == ["frequency_hz", "amplitude", "stiffness_real", "stiffness_imag", "magnitude", "loss_factor"]
    data = np.array(rows[1:], dtype=float)
    ref = stiffness(app.state.design, data[:, 0], data[0, 1])
    assert_allclose(data[data[:, 1] == data[0, 1], 4], ref.magnitude[0, data[:, 1] == data[0, 1]], rtol=1e-10)


def test_a_failing_refresh_keeps_the_last_plots_and_logs_one_line(app, caplog):
    good = data(overlay(app, "magnitude", "frequency"), "operating point")[1]
    original = app.state.explorer_data
    app.state.explorer_data = lambda *a, **k: 1 / 0
    try:
        with caplog.at_level(logging.WARNING, logger="bushing.app"):
            app.state.shear_modulus_mpa = 3.0
    finally:
        app.state.explorer_data = original
    assert_allclose(data(overlay(app, "magnitude", "frequency"), "operating point")[1], good)
    assert len(caplog.records) == 1 and caplog.records[0].exc_info is None
    assert "ZeroDivisionError" in caplog.records[0].getMessage()


def test_other_tabs_are_built_when_opened_and_catch_up_when_shown(app):
    assert [len(app.tabs[i].objects) for i in range(1, 5)] == [0, 0, 0, 0]  # a load builds the Explorer
    app.tabs.active = 2
    assert len(app.tabs[2].objects) > 0
    assert len(app.tabs[1].objects) == 0
    app.tabs.active = 0
    assert app.slices is app.slices and len(app.tabs[1].objects) > 0  # built once, on demand
    app.state.shear_modulus_mpa = 3.0  # the Slices tab is hidden: not refreshed yet
    stale = xy(app.slices.frame("magnitude"), "1 slice (eqs 17/18)")[1]
    app.tabs.active = 1
    fresh = xy(app.slices.frame("magnitude"), "1 slice (eqs 17/18)")[1]
    assert np.all(fresh > stale)


# ---- measured data and fitting ------------------------------------------------------------


def example_files():
    from core.synthetic import paper_b_example

    data, loop = paper_b_example(PAPER_B)
    return data.to_csv().encode(), loop.to_csv().encode()


def test_measured_points_appear_over_the_model(app):
    stiff, loop_bytes = example_files()
    app.inputs.widgets["shear_modulus_mpa"].value = 2.0  # a design that misses the data
    assert app.state.load_measured(stiff, "s.csv")
    app.tabs.active = 0
    x, y = data(overlay(app, "magnitude", "frequency"), "measured")
    assert len(x) == 150 and np.all(y > 0)
    points = app.state.measured_points()
    assert_allclose(y, points["magnitude"])
    assert_allclose(x, points["frequency_hz"])
    app.tabs.active = 3  # the residual plots hold the state's numbers
    residuals = app.state.measured_residuals()
    assert_allclose(xy(app.measured.frame("magnitude", "frequency"), "residual")[1],
                    residuals["magnitude_residual_pct"])
    # exact data of a bushing 10 % longer (K ∝ L, the loss factor unchanged): the explorer's
    # design is 1/1.1 − 1 = −9.09 % off at every point, with no loss-factor residual
    from core.synthetic import synthetic_stiffness

    app.inputs.widgets["shear_modulus_mpa"].value = 2.42
    longer = synthetic_stiffness(PAPER_B.replace(geometry=PAPER_B.geometry.__class__(0.020, 0.035, 0.099)),
                                 np.linspace(1, 100, 7), [1e-5, 1e-4, 1e-3], noise=0.0)
    assert app.state.load_measured(longer.to_csv(), "longer.csv")
    residuals = app.state.measured_residuals()
    assert_allclose(residuals["magnitude_residual_pct"], 100 * (1 / 1.1 - 1), rtol=1e-8)
    assert_allclose(residuals["loss_factor_residual"], 0.0, atol=1e-9)
    assert residuals["gap"] == pytest.approx(1 / 11, rel=1e-6)  # |K_model − K_data| / |K_data| = 1 − 1/1.1
    assert_allclose(xy(app.measured.frame("magnitude", "amplitude"), "residual")[1], 100 * (1 / 1.1 - 1), rtol=1e-8)
    app.tabs.active = 0
    assert app.state.load_measured_loop(loop_bytes, "l.csv")
    assert app.state.frequency_hz == pytest.approx(0.1) and app.state.amplitude == pytest.approx(1.0)
    lx, _ = data(app.plots.frame("loop"), "measured")
    assert len(lx) == 400 and np.max(np.abs(lx)) == pytest.approx(1.0, rel=1e-6)


def test_dense_data_are_drawn_as_bin_means_with_the_gap_over_every_point(app):
    from app.curves import DISPLAY_POINTS
    from core.residuals import gap
    from core.synthetic import synthetic_loop, synthetic_stiffness

    dense = synthetic_stiffness(PAPER_B, np.geomspace(1, 100, 4000), [1e-5, 1e-4, 1e-3], seed=2)
    assert app.state.load_measured(dense.to_csv(), "dense.csv")
    app.tabs.active = 0
    x, _ = data(overlay(app, "magnitude", "frequency"), "measured")
    assert len(x) == DISPLAY_POINTS
    every = gap(stiffness_points(app.state.design, dense.frequency_hz, dense.amplitude), dense.stiffness)
    assert app.state.measured_residuals()["gap"] == pytest.approx(every, rel=1e-9)
    app.tabs.active = 3
    assert f"drawn as {DISPLAY_POINTS} bin means" in app.measured.summary.object
    loop = synthetic_loop(PAPER_B, 1.0, 1e-4, periods=4, per_period=5000, seed=3)
    assert app.state.load_measured_loop(loop.to_csv(), "long_loop.csv")
    app.tabs.active = 0
    lx, _ = data(app.plots.frame("loop"), "measured")
    assert len(lx) == DISPLAY_POINTS and np.max(np.abs(lx)) == pytest.approx(0.1, rel=0.01)  # 1e-4 m in mm


def test_bad_files_leave_a_message_and_the_session_going(app):
    assert not app.state.load_measured(b"frequency_hz,amplitude,magnitude,loss_factor\n10,1e-4,abc,0.1\n", "bad.csv")
    assert app.state.data_message == "bad.csv: line 2: magnitude is not a number ('abc')"
    assert app.state.measured is None
    app.tabs.active = 3
    assert "line 2" in app.measured.message.object
    assert not app.state.load_measured_loop(b"", "empty.csv")
    assert "empty" in app.state.data_message
    app.measured.stiffness_file.value = {"binary.csv": b"\xff\xfe"}  # not even text (as the drop area gives it)
    assert "UTF-8" in app.state.data_message and "binary.csv" in app.state.data_message
    assert app.state.errors == {} and app.state.design == PAPER_B


def test_fit_in_the_app_and_take_it_into_the_explorer(app):
    stiff, loop_bytes = example_files()
    app.state.load_measured(stiff)
    app.state.load_measured_loop(loop_bytes)
    app.state.param.update(shear_modulus_mpa=1.5, friction_strain_half=2e-3)
    app.tabs.active = 3
    app.state.run_fit()
    r = app.state.fit_result
    assert r.gap < 0.01 and not app.measured.use.disabled
    assert "Correlation" in app.measured.results.object
    f_op, x_op = app.state.frequency_hz, app.state.amplitude
    app.state.use_fit()
    assert app.state.design.material.shear_modulus == pytest.approx(r.design.material.shear_modulus, rel=1e-9)
    assert (app.state.frequency_hz, app.state.amplitude) == (f_op, x_op)
    assert app.state.measured_residuals()["gap"] == pytest.approx(r.gap, rel=1e-6)
    fitted = loads_design(app.measured._fitted_json().getvalue())
    assert fitted.material == r.design.material


def test_a_fit_the_data_cannot_determine_says_so_in_the_app(app):
    """The single-amplitude sweep: µ and ε½ are not determined; the table says so, shows no
    standard error for them, the warnings are above the table."""
    sweep = (Path(__file__).resolve().parent.parent / "examples" / "paper_b_sweep_0.1mm.csv").read_bytes()
    assert app.state.load_measured(sweep, "paper_b_sweep_0.1mm.csv")
    app.tabs.active = 3
    app.state.run_fit()
    r = app.state.fit_result
    assert "shear_modulus" in r.undetermined
    text = app.measured.results.object
    row = next(line for line in text.splitlines() if line.startswith("| µ"))
    assert row.split("|")[3].strip() == "–" and "not bounded" in row and "**not determined**" in row
    assert "⚠ shear_modulus is not determined by these data" in text


def test_fit_without_data_says_so(app):
    app.state.run_fit()
    assert "load measured" in app.state.data_message and app.state.fit_result is None


def test_the_thesis_two_step_fit_in_the_app(app):
    stiff, loop_bytes = example_files()
    app.state.load_measured(stiff)
    app.state.fit_method = "two-step"
    app.state.run_fit()
    assert "loop" in app.state.data_message  # needs both
    app.state.load_measured_loop(loop_bytes)
    app.tabs.active = 3
    assert len(app.measured.sweep.options) == 5 and app.measured.sweep.visible
    app.measured.sweep.value = 1e-4
    app.state.run_fit()
    r = app.state.fit_result
    assert r.method == "two-step" and r.points == 30  # the 0.1 mm sweep
    assert app.state.data_message == ""  # the earlier refusal is no longer shown
    assert r.design.material.shear_modulus == pytest.approx(2.42e6, rel=0.03)
    assert "two-step" in app.measured.results.object


# ---- what the browser gets: ranges, legends, linked axes, changed data only -----------------


def test_axes_of_a_quantity_are_shared_and_cover_every_curve(app):
    """Plots of the same quantity share one Bokeh range (linked by their HoloViews dimension);
    after a design change it covers every curve on it, padded by 5 % of the span each side."""
    doc = rendered(app.template())
    app.state.shear_modulus_mpa = 3.3
    figs = figures(doc)
    k_f, k_a = figs["|K| against frequency"], figs["|K| against amplitude"]
    eta_f = figs["Loss factor against frequency"]
    assert k_f.y_range is k_a.y_range and k_f.x_range is eta_f.x_range
    shown = [np.concatenate([el.dimension_values(1) for el in overlay(app, "magnitude", a) if el.label])
             for a in ("frequency", "amplitude")]
    both = np.concatenate(shown)
    span = both.max() - both.min()
    assert (k_f.y_range.start, k_f.y_range.end) == pytest.approx((both.min() - 0.05 * span, both.max() + 0.05 * span))
    x = data(overlay(app, "magnitude", "amplitude"), "operating point")[0]
    lo, hi = np.log10(x.min()), np.log10(x.max())
    assert np.log10([k_a.x_range.start, k_a.x_range.end]) == pytest.approx([lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)])
    assert x.min() == pytest.approx(app.state.amplitude_bounds[0])


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
    assert shown == [el.label for el in overlay(app, "magnitude", "frequency") if el.label]
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
    from app.plots import _curve

    x, y = hv.Dimension("x"), hv.Dimension("y")
    a = _curve([1.0, np.nan], [2.0, 3.0], x, y, "a")
    same = _curve([1.0, np.nan], [2.0, 3.0], x, y, "a")
    other = _curve([1.0, np.nan], [2.0, 3.5], x, y, "a")
    relabelled = _curve([1.0, np.nan], [2.0, 3.0], x, y, "b")
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


def test_the_mathjax_patch_is_in_effect():
    """app.patches changes one Panel internal: fail loudly when a Panel upgrade removes it."""
    from panel.io import resources

    from app import patches

    assert patches.PATCHED and resources._panel_use_mathjax is patches.holds_math


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
    lo, hi = app.state.amplitude_bounds
    assert np.log10(lo) <= slider.value <= np.log10(hi)
    assert abs(slider.value - np.log10(app.state.amplitude)) <= slider.step / 2


def test_a_change_walks_the_document_only_when_it_adds_models(app):
    """app.patches.frozen_models: a change that only moves data recomputes no model set; one that
    adds glyphs (a pinned reference) does, so the new models are in the document."""
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
    assert walks
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

    code = ("import sys, app.state, app.curves, app.diagnosis_state; "
            "print(sorted(m for m in ('panel', 'holoviews', 'bokeh') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_changes_add_no_styles_and_no_options_entries(app):
    """Every plotted element is a clone of a styled template: changes add no template and no
    entry to HoloViews' options store (a session's memory stays flat however long it runs)."""
    import holoviews as hv

    from app import plots

    app.state.shear_modulus_mpa = 2.5  # every style in use once
    app.state.amplitude = 0.3
    templates, entries = plots._template.cache_info().currsize, len(hv.Store.custom_options())
    for i in range(15):
        app.state.shear_modulus_mpa = 2.0 + 0.01 * i
        app.state.amplitude = 0.05 + 0.01 * i
    assert plots._template.cache_info().currsize == templates
    assert len(hv.Store.custom_options()) == entries


def test_hostile_values_from_the_page_leave_a_message_or_nothing(app, caplog):
    """Values a hostile page (or a slip) sends: a message beside the field, or nothing moves;
    no traceback in the log, the session goes on."""
    slider = app.inputs.amplitude.slider
    before = app.state.amplitude
    slider.value = 400.0  # 10^400 mm: beyond any float
    assert app.state.amplitude == pytest.approx(app.state.amplitude_bounds[1], rel=1e-3)
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
    assert "outside this bushing's amplitude axis" in app.state.data_message
    app.tabs.active = 3
    app.measured.stiffness_file.value = {"empty.csv": ""}  # an empty file: its own message, not the last one
    assert app.state.data_message.startswith("empty.csv: ") and "empty" in app.state.data_message
    assert not [r for r in caplog.records if r.exc_info]
