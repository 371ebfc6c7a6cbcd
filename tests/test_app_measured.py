"""The explorer's measured-data tab without a browser: files loaded, drawn over the model and
refused with their reasons; the fits in the session against the core's."""

import re
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from app import curves
from app.main import App
from core import PAPER_B, loads_design, stiffness_points
from tests.helpers import xy


@pytest.fixture
def app():
    return App()


def example_files():
    from core.synthetic import paper_b_example

    data, loop = paper_b_example(PAPER_B)
    return data.to_csv().encode(), loop.to_csv().encode()


def test_measured_points_appear_over_the_model(app):
    stiff, loop_bytes = example_files()
    app.inputs.widgets["shear_modulus_mpa"].value = 2.0  # a design that misses the data
    assert app.state.load_measured(stiff, "s.csv")
    app.tabs.active = 0
    x, y = xy(app.plots.frame(("magnitude", "frequency")), "measured")
    assert len(x) == 150 and np.all(y > 0)
    points = curves.measured_points(app.state.measured, app.state.design.mode)
    assert_allclose(y, points["magnitude"])
    assert_allclose(x, points["frequency_hz"])
    app.tabs.active = 3  # the residual plots hold the state's numbers
    residuals = curves.measured_residuals(app.state.design, app.state.measured)
    assert_allclose(xy(app.measured.frame("magnitude", "frequency"), "residual")[1],
                    residuals["magnitude_residual_pct"])
    # exact data of a bushing 10 % longer (K ∝ L, the loss factor unchanged): the explorer's
    # design is 1/1.1 − 1 = −9.09 % off at every point, with no loss-factor residual
    from core.synthetic import synthetic_stiffness

    app.inputs.widgets["shear_modulus_mpa"].value = 2.42
    longer = synthetic_stiffness(PAPER_B.replace(geometry=PAPER_B.geometry.__class__(0.020, 0.035, 0.099)),
                                 np.linspace(1, 100, 7), [1e-5, 1e-4, 1e-3], noise=0.0)
    assert app.state.load_measured(longer.to_csv(), "longer.csv")
    residuals = curves.measured_residuals(app.state.design, app.state.measured)
    assert_allclose(residuals["magnitude_residual_pct"], 100 * (1 / 1.1 - 1), rtol=1e-8)
    assert_allclose(residuals["loss_factor_residual"], 0.0, atol=1e-9)
    assert residuals["gap"] == pytest.approx(1 / 11, rel=1e-6)  # |K_model − K_data| / |K_data| = 1 − 1/1.1
    assert_allclose(xy(app.measured.frame("magnitude", "amplitude"), "residual")[1], 100 * (1 / 1.1 - 1), rtol=1e-8)
    # the key of the data plots' colours names the file's three amplitudes in mm, in the plots' order
    # (issue #27, item 8: one colour per amplitude, as in the diagnosis)
    key = re.sub(r"<[^>]+>", "", app.measured.curve_key.object)
    assert key.split() == ["Amplitudes:", "■", "0.01", "mm", "■", "0.1", "mm", "■", "1", "mm"]
    app.tabs.active = 0
    assert app.state.load_measured_loop(loop_bytes, "l.csv")
    assert app.state.frequency_hz == pytest.approx(0.1) and app.state.amplitude == pytest.approx(1.0)
    lx, _ = xy(app.plots.frame("loop"), "measured")
    assert len(lx) == 400 and np.max(np.abs(lx)) == pytest.approx(1.0, rel=1e-6)


def test_dense_data_are_drawn_as_bin_means_with_the_gap_over_every_point(app):
    from app.curves import DISPLAY_POINTS
    from core.residuals import gap
    from core.synthetic import synthetic_loop, synthetic_stiffness

    dense = synthetic_stiffness(PAPER_B, np.geomspace(1, 100, 4000), [1e-5, 1e-4, 1e-3], seed=2)
    assert app.state.load_measured(dense.to_csv(), "dense.csv")
    app.tabs.active = 0
    x, _ = xy(app.plots.frame(("magnitude", "frequency")), "measured")
    assert len(x) == DISPLAY_POINTS
    every = gap(stiffness_points(app.state.design, dense.frequency_hz, dense.amplitude), dense.stiffness)
    assert curves.measured_residuals(app.state.design, app.state.measured)["gap"] == pytest.approx(every, rel=1e-9)
    app.tabs.active = 3
    assert f"drawn as {DISPLAY_POINTS} bin means" in app.measured.summary.object
    loop = synthetic_loop(PAPER_B, 1.0, 1e-4, periods=4, per_period=5000, seed=3)
    assert app.state.load_measured_loop(loop.to_csv(), "long_loop.csv")
    app.tabs.active = 0
    lx, _ = xy(app.plots.frame("loop"), "measured")
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
    app.fit.run_fit()
    r = app.fit.fit_result
    assert r.gap < 0.01 and not app.measured.use.disabled
    assert "Correlation" in app.measured.results.object
    f_op, x_op = app.state.frequency_hz, app.state.amplitude
    app.fit.use_fit()
    assert app.state.design.material.shear_modulus == pytest.approx(r.design.material.shear_modulus, rel=1e-9)
    assert (app.state.frequency_hz, app.state.amplitude) == (f_op, x_op)
    assert curves.measured_residuals(app.state.design, app.state.measured)["gap"] == pytest.approx(r.gap, rel=1e-6)
    fitted = loads_design(app.measured._fitted_json().getvalue())
    assert fitted.material == r.design.material


def test_a_fit_the_data_cannot_determine_says_so_in_the_app(app):
    """The single-amplitude sweep: µ and ε½ are not determined; the table says so, shows no
    standard error for them, the warnings are above the table."""
    sweep = (Path(__file__).resolve().parent.parent / "examples" / "paper_b_sweep_0.1mm.csv").read_bytes()
    assert app.state.load_measured(sweep, "paper_b_sweep_0.1mm.csv")
    app.tabs.active = 3
    app.fit.run_fit()
    r = app.fit.fit_result
    assert "shear_modulus" in r.undetermined
    text = app.measured.results.object
    row = next(line for line in text.splitlines() if line.startswith("| µ"))
    assert row.split("|")[3].strip() == "–" and "not bounded" in row and "**not determined**" in row
    assert "⚠ shear_modulus is not determined by these data" in text
    # σ_fmax has a bounded profile but no linearised error: a dash and the reason, never a 0
    # standard error nor an inf correlation
    row = next(line for line in text.splitlines() if line.startswith("| σ_fmax ("))
    assert row.split("|")[3].strip() == "–"
    table = text.partition("**Correlation between parameters**")[2]
    assert "inf" not in table and "nan" not in table
    fc = next(line for line in table.splitlines() if line.startswith("| m "))
    assert [cell.strip() for cell in fc.split("|")[1:-1]].count("–") == 3
    assert "no linearised standard error or correlation for µ, σ_fmax, ε½" in table
    cells = [c.strip() for line in table.splitlines()[3:] if line.startswith("| ") for c in line.split("|")[2:-1]]
    assert cells and all(c == "–" or re.fullmatch(r"[+−]\d\.\d\d|0\.00", c) for c in cells), cells
    assert "-" not in "".join(cells)  # a true minus sign, no "-0.00"


def test_fit_without_data_says_so(app):
    app.fit.run_fit()
    assert "load measured" in app.state.data_message and app.fit.fit_result is None


def test_the_thesis_two_step_fit_in_the_app(app):
    stiff, loop_bytes = example_files()
    app.state.load_measured(stiff)
    app.fit.fit_method = "two-step"
    app.fit.run_fit()
    assert "loop" in app.state.data_message  # needs both
    app.state.load_measured_loop(loop_bytes)
    app.tabs.active = 3
    assert len(app.measured.sweep.options) == 5 and app.measured.sweep.visible
    app.measured.sweep.value = 1e-4
    app.fit.run_fit()
    r = app.fit.fit_result
    assert r.method == "two-step" and r.points == 30  # the 0.1 mm sweep
    assert app.state.data_message == ""  # the earlier refusal is no longer shown
    assert r.design.material.shear_modulus == pytest.approx(2.42e6, rel=0.03)
    assert "two-step" in app.measured.results.object


def test_new_data_forgets_the_fit_and_each_view_refreshes_once(app):
    """A fit belongs to its data: loading new data (or clearing it) forgets it, and each view
    that shows the fit (the tab's table, a band from the fit's covariance) refreshes once, with
    the new data and no fit."""
    stiff, loop_bytes = example_files()
    app.state.load_measured(stiff)
    app.state.load_measured_loop(loop_bytes)
    app.state.param.update(band_on=True, band_from_fit=True, band_samples=50)
    app.tabs.active = 3
    app.fit.run_fit()
    assert app.fit.fit_result is not None and "Fitted" in app.measured.results.object
    views = {3: app.measured, 0: app.plots, [t for t, *_ in App.LAZY_TABS].index("Every direction") + 1: app.card,
             [t for t, *_ in App.LAZY_TABS].index("What-ifs") + 1: app.whatif}
    for view in views.values():
        view.calls, draw = [], view._update
        view._update = lambda view=view, draw=draw: view.calls.append((view.state.measured, app.fit.fit_result)) or draw()
    for load, fit_was_there in ((lambda: app.state.load_measured(stiff), True), (app.state.clear_measured, False)):
        load()
        for tab, view in views.items():  # each drawn once, when its tab is shown, with the new data and no fit
            app.tabs.active = tab
            # the card and the what-ifs draw no data: after a clear (the fit already gone), nothing new
            drawn = fit_was_there or view in (app.measured, app.plots)
            assert view.calls == [(app.state.measured, None)] * drawn, type(view).__name__
            view.calls.clear()
    app.measured.refresh()
    assert app.measured.use.disabled and app.measured.results.object == ""
