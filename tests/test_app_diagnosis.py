"""The "Find the missing effect" tab without a browser: the data its plots hold against the core."""

import csv
import io
import itertools
import json

import numpy as np
import pytest

from app.main import App
from core import PAPER_B, stiffness, stiffness_points
from core.numbers import format_value
from core.synthetic import MYSTERIES, synthetic_stiffness
from tests.helpers import element, run_async, xy

F = np.linspace(1, 100, 30)
AMPS = (0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3)


@pytest.fixture
def app():
    return App()


def inertia_csv() -> str:
    return synthetic_stiffness(PAPER_B.replace(effects={"inertia": {"mass": 0.5}}), F, AMPS, seed=3).to_csv()


def run(app):
    run_async(app.diagnosis._run(None))


def test_every_mystery_is_diagnosed_right():
    """The demo's data sets: the workflow finds what each hides (and nothing where nothing is)."""
    from core.identify.diagnose import diagnose

    for m in MYSTERIES:
        result = diagnose(m.design, m.data(), baseline=m.baseline, held_out=False)
        assert sorted(result.added) == sorted(m.missing), m.missing
        assert not result.unexplained


def test_a_diagnosis_in_the_tab_holds_the_core_numbers(app):
    view, state = app.diagnosis, app.diagnosis.state
    assert view.run.disabled  # nothing to diagnose yet
    assert state.load_csv(inertia_csv(), "inertia.csv")
    assert not view.run.disabled and "150 points" in view.source.object and "axial 150 points at 5 amplitudes" in view.source.object
    run(app)
    r = state.result
    assert r.added == ["inertia"] and state.message == "" and not state.running
    assert "Step 1: add Apparent mass seen by the force sensor" in view.report.object
    mass, error = r.steps[0].parameters["mass"], r.steps[0].standard_errors["mass"]  # axial: kg
    assert f"mass = {format_value(mass, 'kg')} ± {format_value(error, 'kg', 'error')}" in view.report.object
    assert "What is left is noise" in view.report.object
    # the gap bars: the baseline's and after each step; the noise line
    gap = view.live["gap"].current[0]
    bars = gap.get(0)
    assert list(bars.dimension_values(0)) == ["baseline", "+ inertia"]
    np.testing.assert_allclose(bars.dimension_values(1), [r.baseline.gap, r.steps[0].gap_after])
    assert gap.get(1).data == pytest.approx(r.noise_gap)  # the noise line
    # the final model's curve at 0.1 mm is the core's stiffness of the final design, in kN/mm
    magnitude, loss = view.live["curves"].current
    f, k = xy(magnitude, "0.1 mm final")
    np.testing.assert_allclose(k, np.abs(stiffness_points(r.final.design, f, 0.1e-3)) / 1e6, rtol=1e-12)
    # each curve plot's axis takes in the data and both models' curves
    for ov in (magnitude, loss):
        y = np.concatenate([el.dimension_values(1) for el in ov])
        low, high = element(ov, "0.1 mm final").vdims[0].range
        assert low < y.min() and y.max() < high
    # the misfit map: model − data in % of |K|, the amplitude in mm
    final_map = view.live["maps"].current[2]
    points = final_map.get(0)
    d = state.data
    expected = 100 * (np.abs(stiffness_points(r.final.design, d.frequency_hz, d.amplitude)) / d.magnitude - 1)
    np.testing.assert_allclose(points.dimension_values(2), expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(points.dimension_values(1), d.amplitude * 1e3)
    assert final_map.opts.get().kwargs["title"] == "Final: |K| misfit (%)"
    # the downloads are the command line's report and predictions
    assert json.loads(state.report_json()) == json.loads(json.dumps(r.report()))
    rows = list(csv.reader(io.StringIO(state.predictions_csv())))
    assert rows[0][-2:] == ["final_magnitude", "final_loss_factor"] and len(rows) == 151


def test_the_final_model_goes_into_the_explorer(app):
    state = app.diagnosis.state
    state.load_csv(inertia_csv())
    run(app)
    f_op, x_op = app.state.frequency_hz, app.state.amplitude
    state.use_final()
    design = app.state.design
    assert design.effect_parameters["inertia"]["mass"] == pytest.approx(
        state.result.final.design.effect_parameters["inertia"]["mass"])
    assert (app.state.frequency_hz, app.state.amplitude) == (f_op, x_op)
    # every explorer plot still draws: |K| with the inertia, the loop from the material model
    x, y = xy(app.plots.frame(("magnitude", "frequency")), "operating point")
    expected = stiffness(design, x, app.state.amplitude * 1e-3).magnitude[0] / 1e6
    np.testing.assert_allclose(y, expected, rtol=1e-9)
    loop_x, _ = xy(app.plots.frame("loop"), "total")
    assert len(loop_x) > 0
    assert "inertia act on the stiffness plots" in app.template().main[0].object


def test_the_mystery_demo_hides_then_reveals_the_truth(app):
    view, state = app.diagnosis, app.diagnosis.state
    state._next_mystery = 1  # the teaching case: no friction in the baseline
    state.load_mystery()
    assert state.baseline == ["elastic", "fractional"]
    assert app.state.design.name == PAPER_B.name
    assert "mystery" in view.source.object and view.truth.object == ""
    run(app)
    assert state.result.added == ["friction"]
    assert view.reveal.visible and view.truth.object == ""  # not before it is asked for
    state.revealed = True
    assert "Amplitude dependence (Fletcher–Gent effect)" in view.truth.object
    assert "found exactly that" in view.truth.object
    assert not view.reveal.visible
    # the hidden values with their units (issue #27, item 5): Paper B's σ_fmax in Pa, ε½ a number
    assert "friction_stress_max = 19200 Pa, friction_strain_half = 0.004)" in view.truth.object
    state._next_mystery = 0  # a fixture mass hidden in axial data: in kg
    state.load_mystery()
    assert "(`inertia`: mass = 0.5 kg)" in state.truth()


def test_bad_input_leaves_a_message_and_the_session_going(app):
    view, state = app.diagnosis, app.diagnosis.state
    assert not state.load_csv(b"frequency_hz,amplitude,magnitude,loss_factor\n10,1e-4,-5,0.1\n", "bad.csv")
    assert "bad.csv" in view.message.object and state.data is None
    assert not state.use_measured()
    assert "No measured stiffness" in view.message.object
    state.load_csv(inertia_csv())
    state.baseline = []
    run(app)
    assert "at least one baseline branch" in view.message.object
    assert state.result is None and not state.running
    # too few points for the baseline: a message, no traceback
    state.load_csv(b"frequency_hz,amplitude,magnitude,loss_factor\n10,1e-4,4e6,0.1\n20,1e-4,4.1e6,0.11\n")
    state.baseline = ["elastic", "fractional", "friction"]
    run(app)
    assert "cannot determine" in view.message.object


def test_progress_is_reported_while_fitting(app):
    state = app.diagnosis.state
    seen = []
    state.load_csv(inertia_csv())
    state.compute(progress=lambda f, m: seen.append((f, m)))
    fractions = [f for f, _ in seen]
    assert fractions[0] == 0.0 and fractions[-1] == 1.0
    assert all(b >= a for a, b in itertools.pairwise(fractions))  # never backwards
    assert any("apparent mass" in m for _, m in seen)


def test_data_of_two_modes_are_diagnosed_jointly_and_plotted_in_the_explorers_mode(app):
    """An apparent mass on the axial rig only, with torsion data of the same compound: the tab
    names it for the axial rig, says the modes agree, plots the explorer's mode's rows, and the
    mass follows the design into the explorer, acting in axial only."""
    from core.data import MeasuredStiffness
    from core.io.measured import combined

    parts = []
    for mode, amps, effects in (("axial", AMPS, {"inertia": {"mass": 0.5}}), ("torsion", (1e-3, 1e-2), {})):
        d = synthetic_stiffness(PAPER_B.in_mode(mode).replace(effects=effects), F, amps, seed=5)
        parts.append(MeasuredStiffness(d.frequency_hz, d.amplitude, d.stiffness, None, np.full(len(d), mode, dtype=object)))
    app.state.mode = "torsion"
    state, view = app.diagnosis.state, app.diagnosis
    assert state.load_csv(combined(parts, "axial").to_csv(), "two.csv")
    assert "axial 150 points at 5 amplitudes; torsion 60 points at 2 amplitudes" in view.source.object
    run(app)
    r = state.result
    assert r.added == ["inertia"] and r.steps[0].mode == "axial" and not r.modes_disagree
    assert "on the axial rig only" in view.report.object and "The modes agree" in view.report.object
    assert "The plots show the torsion rows" in view.report.object
    magnitude, _ = view.live["curves"].current  # torsion rows only, the final model in torsion
    f, k = xy(magnitude, "0.01 rad final")
    np.testing.assert_allclose(k, np.abs(stiffness_points(r.final.design, f, 1e-2)), rtol=1e-12)  # N·m/rad
    assert len(view.live["maps"].current[2].get(0).dimension_values(0)) == len(F) * 2
    state.use_final()
    assert app.state.design.mode == "torsion" and app.state.design.effect_parameters == {}
    app.state.mode = "axial"  # on its own rig the mass acts
    assert app.state.design.effect_parameters["inertia"]["mass"] == pytest.approx(r.steps[0].parameters["mass"])


def test_the_click_starts_the_work_then_makes_the_plots_not_ready_while_it_runs(app, monkeypatch):
    """Diagnose clicked before the report's plots were made ready for the data (on a served page
    they are made one plot at a time after the data are shown): the work is started first, and
    the plots left of the report's first tab (the gap, the curves) are made while it runs, one at
    a time in the page's order (the work waits here until they are), then the report is written
    into them; the misfit maps, in the report's second tab, are not made while the work runs but
    with the report. On 5d78637 the click made them all before it started the work."""
    import threading

    from app import work
    from app.diagnosis_state import DiagnosisState
    from app.tabs.find_the_missing_effect import (
        LATER_GROUPS,
        PLOT_GROUPS,
        PREPARE_STEPS,
        DiagnosisView,
    )

    first_tab = {step for step in PREPARE_STEPS if step[0] not in LATER_GROUPS}

    order, made = [], threading.Event()
    submit, prepare, task = work._submit, DiagnosisView._prepare, DiagnosisState.task

    def submitted(job, latest):
        order.append("work started")
        return submit(job, latest)

    def prepared(self, name, index):
        prepare(self, name, index)
        order.append((name, index))
        made.set() if self._ready == first_tab else None

    def waits_for_the_plots(self):
        t = task(self)

        def function(*args, **kwargs):
            assert made.wait(60), "the plots were not made while the work ran"
            return t.function(*args, **kwargs)

        return work.Task(function, t.args, t.kwargs)

    monkeypatch.setattr(work, "_submit", submitted)
    monkeypatch.setattr(DiagnosisView, "_prepare", prepared)
    monkeypatch.setattr(DiagnosisState, "task", waits_for_the_plots)
    monkeypatch.setattr(DiagnosisView, "_on_data", lambda self, *_e: setattr(self, "_ready", set()))
    view = app.diagnosis
    view.state.load_csv(inertia_csv())
    run(app)
    assert order == ["work started", ("gap", 0), ("curves", 0), ("curves", 1)]
    assert "What is left is noise" in view.report.object and set(view.live) == set(PLOT_GROUPS)
    # each plot in its own place, once, in the page's order
    assert {name: [slot.objects for slot in view._slots[name]] for name in PLOT_GROUPS} == \
        {name: [[pane] for pane in view.live[name].panes] for name in PLOT_GROUPS}
