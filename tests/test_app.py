"""The explorer without a browser: build a session, set parameters, check what the plots hold
against the core."""

import csv
import io
import logging

import numpy as np
import pytest
from numpy.testing import assert_allclose

from app.main import App, create_app
from app.state import ExplorerState
from core import PAPER_B, TABLE_1, loads_design, loop, stiffness, stiffness_points


@pytest.fixture
def app():
    return App()


def data(fig, key):
    """What a figure's glyph holds (x, y)."""
    d = fig.sources[key].data
    return np.asarray(d["x"]), np.asarray(d["y"])


def figure(app, quantity, axis):
    return app.plots.figures[(quantity, axis)]


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
    f, k = data(figure(app, "magnitude", "frequency"), "operating")
    ref = stiffness(PAPER_B, f, s.amplitude * 1e-3)
    assert_allclose(k, ref.magnitude[0] / 1e6, rtol=1e-12)
    _, eta = data(figure(app, "loss_factor", "frequency"), "operating")
    assert_allclose(eta, ref.loss_factor[0], rtol=1e-12)
    fig = figure(app, "magnitude", "frequency").fig
    assert fig.xaxis[0].axis_label == "Frequency (Hz)" and fig.yaxis[0].axis_label == "|K| (kN/mm)"
    sweeps = figure(app, "magnitude", "frequency").sources["sweeps"].data
    amps = s.sweep_amplitudes()
    for ys, x in zip(sweeps["ys"], amps):
        assert_allclose(ys, stiffness(PAPER_B, f, x * 1e-3).magnitude[0] / 1e6, rtol=1e-12)


def test_amplitude_plot_holds_the_core_stiffness_in_torsion(app):
    s = app.state
    s.preset = "Table 1 bushing (torsion)"
    assert s.design == TABLE_1
    x, k = data(figure(app, "magnitude", "amplitude"), "operating")
    ref = stiffness(TABLE_1, s.frequency_hz, x)
    assert_allclose(k, ref.magnitude[:, 0], rtol=1e-12)
    fig = figure(app, "magnitude", "amplitude").fig
    assert fig.xaxis[0].axis_label == "Amplitude (rad)" and fig.yaxis[0].axis_label == "|K| (N·m/rad)"
    # the amplitude axis spans the Fletcher–Gent range: ε̂/ε½ from 1e-3 to 1e2
    from core import strain_factor

    z = strain_factor(TABLE_1.geometry, "torsion") * x / TABLE_1.material.friction_strain_half
    assert_allclose([z.min(), z.max()], [1e-3, 1e2], rtol=1e-9)


def test_loop_holds_the_core_loop_and_its_branches(app):
    s = app.state
    s.amplitude, s.frequency_hz = 0.5, 3.0
    ref = loop(PAPER_B, 3.0, 0.5e-3, 200)
    x, force = data(app.plots.loop, "total")
    assert_allclose(x[:-1], ref.displacement * 1e3, atol=1e-12)
    assert_allclose(force[:-1], ref.force, rtol=1e-12, atol=1e-9)
    assert force[0] == force[-1]  # closed
    for name in ("elastic", "viscoelastic", "friction"):
        assert_allclose(data(app.plots.loop, name)[1][:-1], getattr(ref, f"force_{name}"), rtol=1e-12, atol=1e-9)
    assert "0.5 mm, 3 Hz" in app.plots.summary.object


def test_moving_a_widget_changes_the_plots(app):
    before = data(figure(app, "magnitude", "frequency"), "operating")[1]
    app.inputs.widgets["shear_modulus_mpa"].value = 3.0
    after = data(figure(app, "magnitude", "frequency"), "operating")[1]
    assert app.state.design.material.shear_modulus == pytest.approx(3.0e6)
    assert np.all(after > before)


def test_log_slider_sets_the_amplitude_and_follows_it(app):
    slider = app.inputs.amplitude.slider
    slider.value = np.log10(0.5)
    assert app.state.amplitude == pytest.approx(0.5, rel=1e-3)
    app.state.amplitude = 2.0
    assert slider.value == pytest.approx(np.log10(2.0))


def test_tap_moves_the_operating_point_in_every_plot(app):
    app.plots._tap_frequency(42.0)
    assert app.state.frequency_hz == pytest.approx(42.0)
    for quantity in ("magnitude", "loss_factor"):
        assert figure(app, quantity, "frequency").marker.location == pytest.approx(42.0)
        x, k = data(figure(app, quantity, "amplitude"), "operating")
        ref = stiffness(PAPER_B, 42.0, x * 1e-3)
        expected = ref.magnitude[:, 0] / 1e6 if quantity == "magnitude" else ref.loss_factor[:, 0]
        assert_allclose(k, expected, rtol=1e-12)
    app.plots._tap_amplitude(0.03)
    assert app.state.amplitude == pytest.approx(0.03)
    assert figure(app, "magnitude", "amplitude").marker.location == pytest.approx(0.03)
    assert "0.03 mm, 42 Hz" in app.plots.summary.object
    app.plots._tap_amplitude(-1.0)  # outside: ignored
    assert app.state.amplitude == pytest.approx(0.03)


def test_invalid_input_keeps_the_last_good_design_and_says_why(app):
    good = data(figure(app, "magnitude", "frequency"), "operating")[1]
    app.state.outer_radius_mm = 15.0  # below a = 20 mm
    assert app.state.errors == {"outer_radius_mm": "Must be larger than the inner radius a."}
    assert app.state.design == PAPER_B
    assert_allclose(data(figure(app, "magnitude", "frequency"), "operating")[1], good)
    app.state.fractional_order = 1.4
    app.state.length_mm = None
    assert set(app.state.errors) == {"outer_radius_mm", "fractional_order", "length_mm"}
    app.state.param.update(outer_radius_mm=35.0, fractional_order=0.2, length_mm=90.0)
    assert app.state.errors == {} and app.state.design == PAPER_B


def test_sweep_range_errors(app):
    app.state.freq_max = 0.5
    assert "freq_max" in app.state.errors
    f = data(figure(app, "magnitude", "frequency"), "operating")[0]
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
    x, k = app.slices.figures["magnitude"].sources["3"].data["x"], app.slices.figures["magnitude"].sources["3"].data["y"]
    assert_allclose(k, stiffness(PAPER_B, app.state.frequency_hz, np.asarray(x) * 1e-3, slices=3).magnitude[:, 0] / 1e6, rtol=1e-12)


def test_teaching_branches_add_up_to_the_stiffness(app):
    d = app.state.branch_breakdown()
    x = d["amplitude"] * 1e-3
    ref = stiffness(PAPER_B, app.state.frequency_hz, x)
    assert_allclose(sum(d["real"].values()), ref.stiffness.real[:, 0] / 1e6, rtol=1e-12)
    assert_allclose(sum(d["loss"].values()), ref.loss_factor[:, 0], rtol=1e-12)
    assert np.all(d["loss"]["elastic"] == 0)
    app.tabs.active = 2
    band = app.teaching.figures["real"].sources["friction"].data
    assert_allclose(np.asarray(band["y2"]), sum(d["real"].values()), rtol=1e-12)
    app.teaching.player.value = 3
    x = np.geomspace(*app.state.amplitude_bounds, app.teaching.FRAMES)[3]
    assert f"{x:.3g} mm" in app.teaching.frame_label.object
    assert np.max(np.abs(app.teaching.loop.sources["total"].data["y"])) == pytest.approx(1.0)


def test_comparison_with_a_pinned_reference(app):
    s = app.state
    assert s.comparison() is None
    s.pin_reference()
    s.length_mm = 99.0  # stiffness ∝ L: +10 %
    c = s.comparison()
    assert c["operating"]["magnitude"][2] == pytest.approx(10.0, rel=1e-9)
    assert c["operating"]["loss_factor"][2] == pytest.approx(0.0, abs=1e-9)
    assert c["largest_over_frequency"]["magnitude"] == pytest.approx(10.0, rel=1e-9)
    ref = data(figure(app, "magnitude", "frequency"), "reference")[1]
    assert_allclose(ref * 1.1, data(figure(app, "magnitude", "frequency"), "operating")[1], rtol=1e-12)
    assert "+10.00 %" in app.compare.table(s.reference, s.design, s.frequency_hz, s.amplitude, s.errors)
    s.clear_reference()
    assert s.comparison() is None
    assert len(data(figure(app, "magnitude", "frequency"), "reference")[0]) == 0


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
    good = data(figure(app, "magnitude", "frequency"), "operating")[1]
    original = app.state.frequency_sweep
    app.state.frequency_sweep = lambda *a, **k: 1 / 0
    try:
        with caplog.at_level(logging.WARNING, logger="bushing.app"):
            app.state.shear_modulus_mpa = 3.0
    finally:
        app.state.frequency_sweep = original
    assert_allclose(data(figure(app, "magnitude", "frequency"), "operating")[1], good)
    assert len(caplog.records) == 1 and caplog.records[0].exc_info is None
    assert "ZeroDivisionError" in caplog.records[0].getMessage()


def test_other_tabs_are_built_when_opened_and_catch_up_when_shown(app):
    assert [len(app.tabs[i].objects) for i in range(1, 5)] == [0, 0, 0, 0]  # a load builds the Explorer
    app.tabs.active = 2
    assert len(app.tabs[2].objects) == 1
    assert len(app.tabs[1].objects) == 0
    app.tabs.active = 0
    assert app.slices is app.slices and len(app.tabs[1].objects) == 1  # built once, on demand
    app.state.shear_modulus_mpa = 3.0  # the Slices tab is hidden: not refreshed yet
    stale = np.asarray(app.slices.figures["magnitude"].sources["1"].data["y"]).copy()
    app.tabs.active = 1
    fresh = np.asarray(app.slices.figures["magnitude"].sources["1"].data["y"])
    assert np.all(fresh > stale)


# ---- measured data and fitting (issue 4) ---------------------------------------------------


def example_files():
    from core.synthetic import paper_b_example

    data, loop = paper_b_example(PAPER_B)
    return data.to_csv().encode(), loop.to_csv().encode()


def test_measured_points_appear_over_the_model(app):
    stiff, loop_bytes = example_files()
    app.inputs.widgets["shear_modulus_mpa"].value = 2.0  # a design that misses the data
    assert app.state.load_measured(stiff, "s.csv")
    app.tabs.active = 0
    x, y = data(figure(app, "magnitude", "frequency"), "measured")
    assert len(x) == 150 and np.all(y > 0)
    points = app.state.measured_points()
    assert_allclose(y, points["magnitude"])
    assert_allclose(x, points["frequency_hz"])
    k_model = stiffness_points(app.state.design, points["frequency_hz"], points["amplitude"] * 1e-3)
    residuals = app.state.measured_residuals()
    assert_allclose(residuals["magnitude_residual_pct"], 100 * (np.abs(k_model) / app.state.measured.magnitude - 1))
    app.tabs.active = 3  # the residual plots hold the same numbers
    assert_allclose(data(app.measured.figures[("magnitude", "frequency")], "points")[1],
                    residuals["magnitude_residual_pct"])
    app.tabs.active = 0
    assert app.state.load_measured_loop(loop_bytes, "l.csv")
    assert app.state.frequency_hz == pytest.approx(0.1) and app.state.amplitude == pytest.approx(1.0)
    lx, _ = data(app.plots.loop, "measured")
    assert len(lx) == 400 and np.max(np.abs(lx)) == pytest.approx(1.0, rel=1e-6)


def test_bad_files_leave_a_message_and_the_session_going(app):
    assert not app.state.load_measured(b"frequency_hz,amplitude,magnitude,loss_factor\n10,1e-4,abc,0.1\n", "bad.csv")
    assert app.state.data_message == "bad.csv: line 2: magnitude is not a number ('abc')"
    assert app.state.measured is None
    app.tabs.active = 3
    assert "line 2" in app.measured.message.object
    assert not app.state.load_measured_loop(b"", "empty.csv")
    assert "empty" in app.state.data_message
    app.measured.stiffness_file.value = b"\xff\xfe"  # not even text
    assert "UTF-8" in app.state.data_message
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


# ---- plot ranges, fitted on the server ------------------------------------------------------


def _values(fig, dim):
    """Every finite value a figure holds along x or y, read from its sources."""
    names = ("x", "xs") if dim == "x" else ("y", "ys", "y1", "y2")
    out = []
    for src in fig.sources.values():
        for name in names:
            for v in src.data.get(name, []) if name.endswith("s") else [src.data.get(name, [])]:
                out.append(np.ravel(np.asarray(v, dtype=float)))
    v = np.concatenate(out)
    return v[np.isfinite(v)]


def _expected(values, log):
    """Bokeh's DataRange1d padding, written out: the span grows by 10 %, 5 % each side (in
    log10 on a log axis)."""
    v = np.log10(values[values > 0]) if log else values
    lo, hi = v.min(), v.max()
    start, end = lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)
    return (10**start, 10**end) if log else (start, end)


def test_shared_ranges_cover_the_data_of_every_figure_on_them(app):
    app.state.shear_modulus_mpa = 3.3
    k_f, k_a = figure(app, "magnitude", "frequency"), figure(app, "magnitude", "amplitude")
    eta_f = figure(app, "loss_factor", "frequency")
    assert k_f.fig.y_range is k_a.fig.y_range and k_f.fig.x_range is eta_f.fig.x_range
    both = np.concatenate([_values(k_f, "y"), _values(k_a, "y")])
    assert (k_f.fig.y_range.start, k_f.fig.y_range.end) == pytest.approx(_expected(both, False), rel=1e-12)
    amplitudes = _values(k_a, "x")
    assert (k_a.fig.x_range.start, k_a.fig.x_range.end) == pytest.approx(_expected(amplitudes, True), rel=1e-12)
    assert amplitudes.min() == pytest.approx(app.state.amplitude_bounds[0])
    loop_fig = app.plots.loop
    assert (loop_fig.fig.y_range.start, loop_fig.fig.y_range.end) == pytest.approx(
        _expected(_values(loop_fig, "y"), False), rel=1e-12)


def test_a_zoom_is_kept_until_reset(app):
    fig = figure(app, "magnitude", "frequency")
    rng = fig.fig.y_range
    rng.update(start=4.0, end=4.2)  # as a wheel zoom in the browser arrives
    app.state.shear_modulus_mpa = 3.0
    assert (rng.start, rng.end) == (4.0, 4.2)
    fitted = _expected(np.concatenate([_values(fig, "y"), _values(figure(app, "magnitude", "amplitude"), "y")]), False)
    assert (rng.reset_start, rng.reset_end) == pytest.approx(fitted, rel=1e-12)  # where reset goes
    rng.update(start=rng.reset_start, end=rng.reset_end)  # the reset tool
    app.state.shear_modulus_mpa = 2.0
    assert rng.start < 4.0 and (rng.start, rng.end) == (rng.reset_start, rng.reset_end)


def test_a_mode_change_drops_a_zoom(app):
    rng = figure(app, "magnitude", "frequency").fig.y_range
    rng.update(start=4.0, end=4.2)
    app.state.preset = "Table 1 bushing (torsion)"
    assert rng.end > 4.2 and rng.start == rng.reset_start


def test_legend_entries_are_proxies_styled_like_their_glyphs(app):
    """Legends name empty proxy renderers (BokehJS rebuilds a legend when its renderers' data
    change); a click on a legend makes the real glyphs follow their proxies."""
    fig = figure(app, "magnitude", "frequency")
    items = fig.legend.items
    assert [it.label.value for it in items][-3:] == ["reference", "operating point", "measured"]
    follow = fig._click.args
    assert follow["targets"] == [fig.renderers[k] for k in ("reference", "operating", "measured")]
    for proxy, target in zip(follow["proxies"], follow["targets"]):
        assert np.isnan(proxy.data_source.data["x"]).all()  # one NaN point: a swatch, no line
        assert type(proxy.glyph) is type(target.glyph)
        assert proxy.glyph.properties_with_values() == target.glyph.properties_with_values()
    assert len(fig.sources["operating"].data["x"]) > 0
    (sweep_proxies,) = follow["line_proxies"]
    assert [p.glyph.line_color for p in sweep_proxies] == fig.sources["sweeps"].data["color"]
    assert follow["filters"][0].indices == list(range(len(sweep_proxies)))


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


def test_only_changed_data_are_sent(app):
    """The operating amplitude changes the loop and the operating lines against frequency; the
    sweeps (at fixed amplitudes and frequencies) and the curves against amplitude keep their
    data objects, so nothing of them is sent and their plots are not repainted."""
    def held():
        return {(q, a, key): src.data for (q, a), fig in app.plots.figures.items()
                for key, src in fig.sources.items()} | {("loop", key): src.data
                                                        for key, src in app.plots.loop.sources.items()}
    before = held()
    app.state.amplitude = app.state.amplitude * 1.7
    after = held()
    changed = {key for key in before if after[key] is not before[key]}
    expected = {("loop", name) for name in ("elastic", "viscoelastic", "friction", "total")}
    expected |= {(q, "frequency", "operating") for q in ("magnitude", "loss_factor")}
    assert changed == expected
    fig = figure(app, "magnitude", "amplitude")
    assert fig.marker.location == app.state.amplitude
    assert fig.marker.level == "overlay"  # a moved marker repaints the overlay layer only


def test_same_data_compares_values_nan_and_ragged_columns():
    from app.figures import _same_data

    a = {"x": np.array([1.0, np.nan]), "y": np.array([2.0, 3.0])}
    assert _same_data(a, {"x": np.array([1.0, np.nan]), "y": np.array([2.0, 3.0])})
    assert not _same_data(a, {"x": np.array([1.0, np.nan]), "y": np.array([2.0, 3.5])})
    assert not _same_data(a, {"x": np.array([1.0]), "y": np.array([2.0])})
    assert not _same_data(a, {"x": a["x"]})
    ragged = {"xs": [np.arange(3.0), np.arange(2.0)], "color": ["red", "blue"]}
    assert _same_data(ragged, {"xs": [np.arange(3.0), np.arange(2.0)], "color": ["red", "blue"]})
    assert not _same_data(ragged, {"xs": [np.arange(3.0), np.arange(3.0)], "color": ["red", "blue"]})
    assert not _same_data(ragged, {"xs": [np.arange(3.0), np.arange(2.0)], "color": ["red", "green"]})
    assert _same_data({"x": []}, {"x": np.array([])})
