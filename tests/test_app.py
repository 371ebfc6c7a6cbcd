"""The explorer without a browser: build a session, set parameters, check what the plots hold
against the core (the measured-data tab in test_app_measured, what the page gets in
test_app_page)."""

import csv
import io
import logging
import re

import numpy as np
import pytest
from numpy.testing import assert_allclose

from app import curves
from app.main import App, create_app
from app.state import ExplorerState
from core import PAPER_B, TABLE_1, loads_design, loop, stiffness
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
    s = app.state
    data = curves.slice_comparison(s.design, s.frequency_hz, curves.amplitude_grid(s.design, 60))
    x = data["amplitude"] * 1e-3
    for sl in (1, 2, 3, "continuum"):
        ref = stiffness(PAPER_B, app.state.frequency_hz, x, slices=sl)
        assert_allclose(data["magnitude"][sl], ref.magnitude[:, 0] / 1e6, rtol=1e-12)
    k1 = stiffness(PAPER_B, app.state.frequency_hz, x).magnitude[:, 0]
    k3 = stiffness(PAPER_B, app.state.frequency_hz, x, slices=3).magnitude[:, 0]
    assert_allclose(data["magnitude_diff_pct"][3], 100 * (k3 / k1 - 1), rtol=1e-9)
    assert "3 slices" in app.slices.summary(data)
    # the largest difference of 3 slices, signed with a true minus sign (it read "-0.32 %")
    worst = data["magnitude_diff_pct"][3][np.argmax(np.abs(100 * (k3 / k1 - 1)))]
    assert worst < 0 and f"| 3 slices | −{abs(worst):.2f} % at " in app.slices.summary(data)
    app.tabs.active = 1  # shown: its figures hold the same numbers
    x, k = xy(app.slices.frame("magnitude"), "3 slices")
    assert_allclose(k, stiffness(PAPER_B, app.state.frequency_hz, x * 1e-3, slices=3).magnitude[:, 0] / 1e6, rtol=1e-12)


def test_teaching_branches_add_up_to_the_stiffness(app):
    s = app.state
    d = curves.branch_breakdown(s.design, s.frequency_hz, curves.amplitude_grid(s.design, 80))
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
    x = np.geomspace(*curves.amplitude_bounds(s.design), app.teaching.FRAMES)[3]
    assert f"{x:.3g} mm" in app.teaching.frame_label.object
    shape = loop(PAPER_B, app.state.frequency_hz, x * 1e-3, 200)
    _, f = xy(app.teaching.frame("loop"), "total")
    assert_allclose(f[:-1], shape.force / np.max(np.abs(shape.force)), rtol=1e-9, atol=1e-12)


def test_comparison_with_a_pinned_reference(app):
    s = app.state

    def comparison():
        return curves.comparison(s.design, s.reference, s.frequency_hz, s.amplitude, s.freq_range)

    assert comparison() is None
    s.pin_reference()
    s.length_mm = 99.0  # stiffness ∝ L: +10 %
    c = comparison()
    assert c["operating"]["magnitude"][2] == pytest.approx(10.0, rel=1e-9)
    assert c["operating"]["loss_factor"][2] == pytest.approx(0.0, abs=1e-9)
    assert c["largest_over_frequency"]["magnitude"] == pytest.approx(10.0, rel=1e-9)
    ref = data(overlay(app, "magnitude", "frequency"), "reference")[1]
    assert_allclose(ref * 1.1, data(overlay(app, "magnitude", "frequency"), "operating point")[1], rtol=1e-12)
    _, ref_loop = data(app.plots.frame("loop"), "reference")
    assert_allclose(ref_loop * 1.1, data(app.plots.frame("loop"), "total")[1], rtol=1e-12)
    assert "+10.00 %" in app.compare.text.object
    s.length_mm = 81.0  # −10 %, with a true minus sign (issue #27, item 7)
    assert "−10.00 %" in app.compare.text.object and not re.search(r"-\d", app.compare.text.object)
    s.clear_reference()
    assert comparison() is None
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


def test_a_failing_refresh_keeps_the_last_plots_and_logs_one_line(app, caplog, monkeypatch):
    good = data(overlay(app, "magnitude", "frequency"), "operating point")[1]
    monkeypatch.setattr(curves, "explorer_data", lambda *a, **k: 1 / 0)
    with caplog.at_level(logging.WARNING, logger="bushing.app"):
        app.state.shear_modulus_mpa = 3.0
    monkeypatch.undo()
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
