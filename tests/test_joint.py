"""One compound, every direction: measured files with a mode column, the joint fit of all modes,
cross-mode prediction (fit on a subset, predict the rest), and the messages for bad files."""

import json

import numpy as np
import pandas as pd
import pytest

from app import curves
from cli.main import main
from core import PAPER_B, write_design
from core.data import DataError, MeasuredStiffness
from core.identify.fit import fit_global, model_stiffness, predicted, selection
from core.io.measured import combined, parse_stiffness
from core.registry import parameter_values
from core.synthetic import synthetic_stiffness

NOISE = 0.005
AMPS = {"axial": [1e-5, 1e-4, 3.5e-4], "radial": [2e-6, 2e-5, 6e-5], "torsion": [1e-4, 1e-3, 1e-2],
        "conical": [2e-4, 2e-3, 2e-2]}


def multi_mode(design=PAPER_B, modes=("axial", "radial", "torsion", "conical"), per_amplitude=50, seed=0,
               materials=None):
    parts = []
    for i, mode in enumerate(modes):
        source = (materials or {}).get(mode, design)
        d = synthetic_stiffness(source.in_mode(mode), np.linspace(5, 155, per_amplitude), AMPS[mode],
                                noise=NOISE, seed=seed + i)
        parts.append(MeasuredStiffness(d.frequency_hz, d.amplitude, d.stiffness, None,
                                       np.full(len(d), mode, dtype=object)))
    return combined(parts, design.mode)


START = PAPER_B.replace(shear_modulus=1.5e6, fractional_coefficient=1e6, fractional_order=0.4,
                        friction_stress_max=4e4, friction_strain_half=1e-3)


def test_a_mode_column_is_read_checked_and_written():
    data = multi_mode(per_amplitude=3)
    back = parse_stiffness(data.to_csv())
    assert list(back.mode) == list(data.mode)
    np.testing.assert_allclose(back.stiffness, data.stiffness, rtol=1e-9)
    text = "mode,frequency_hz,amplitude,magnitude,loss_factor\naxial,10,1e-4,4e6,0.1\nshear,10,1e-4,4e6,0.1\n"
    with pytest.raises(DataError, match="line 3: mode must be one of axial, torsion, radial, conical"):
        parse_stiffness(text)
    plain = parse_stiffness("frequency_hz,amplitude,magnitude,loss_factor\n10,1e-4,4e6,0.1\n")
    both = combined([plain, back], "torsion")
    assert both.mode[0] == "torsion" and len(both) == len(back) + 1  # a file without modes: the design's


def test_the_joint_fit_recovers_one_material_from_four_directions():
    data = multi_mode()
    result = fit_global(START, data)
    assert result.points == 600 and set(result.gap_by_mode) == {"axial", "radial", "torsion", "conical"}
    for mode, g in result.gap_by_mode.items():  # each direction fitted to its noise, 0.005·√2
        assert g == pytest.approx(NOISE * np.sqrt(2), rel=0.15), mode
    truth = parameter_values(PAPER_B)
    for name, (lo, hi) in result.intervals.items():
        assert lo <= truth[name] <= hi, name
    assert result.undetermined == []


def test_one_direction_predicts_the_others_to_the_noise():
    """The sequel's protocol: fit on the axial rows only, predict radial, torsion and conical."""
    data = multi_mode(seed=10)
    chosen = selection(data, "axial", "mode=axial")
    result = fit_global(START, data.select(chosen))
    report = predicted(result, data, chosen, "mode=axial")
    assert report["points_fitted"] == 150
    assert report["gap_held_out"] == pytest.approx(NOISE * np.sqrt(2), rel=0.2)
    held = [g for g in report["groups"] if not g["fitted"]]
    assert len(held) == 9 and all(g["gap"] < 3 * NOISE for g in held)


def test_two_materials_in_two_directions_show_in_the_gap_per_mode():
    softer = PAPER_B.replace(shear_modulus=1.6e6, friction_stress_max=3e4)
    data = multi_mode(modes=("axial", "radial"), materials={"radial": softer}, seed=20)
    result = fit_global(START, data)
    assert max(result.gap_by_mode.values()) > 5 * NOISE * np.sqrt(2)  # far above the noise


def test_selection_messages():
    data = multi_mode(per_amplitude=3)
    assert selection(data, "axial", "mode=axial+radial,amplitude=1e-4+2e-5").sum() == 6
    for bad, needle in (("mode=axial,amplitude=9", "chooses none"), ("temperature=20", "give mode="),
                        ("amplitude=big", "numbers"), ("mode=", "give mode=")):
        with pytest.raises(ValueError, match=needle):
            selection(data, "axial", bad)


def test_the_command_line_fits_several_files_and_predicts(tmp_path, capsys):
    data = multi_mode(modes=("axial", "torsion"), per_amplitude=20, seed=30)
    axial, torsion = data.select(data.mode == "axial"), data.select(data.mode == "torsion")
    (tmp_path / "axial.csv").write_text(MeasuredStiffness(axial.frequency_hz, axial.amplitude, axial.stiffness).to_csv())
    torsion.to_csv(tmp_path / "torsion.csv")
    write_design(START, tmp_path / "d.json")
    argv = ["fit", tmp_path / "axial.csv", tmp_path / "torsion.csv", "--design", tmp_path / "d.json",
            "--fit-on", "mode=torsion"]
    assert main([str(a) for a in argv]) == 0
    report = json.loads(capsys.readouterr().out)["fit"]
    assert report["points"] == 60 and report["prediction"]["points_fitted"] == 60
    assert report["prediction"]["gap_held_out"] < 3 * NOISE  # the axial file (no mode column: the design's)
    argv = ["diagnose", tmp_path / "axial.csv", tmp_path / "torsion.csv", "--design", tmp_path / "d.json",
            "--predictions", tmp_path / "pred.csv"]
    assert main([str(a) for a in argv]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["added"] == [] and report["modes"]["disagree"] is False  # one material, to the noise
    assert set(report["modes"]["gap_joint_by_mode"]) == {"axial", "torsion"}
    pred = pd.read_csv(tmp_path / "pred.csv")
    assert list(pred.columns) == ["frequency_hz", "amplitude", "baseline_magnitude", "baseline_loss_factor",
                                  "final_magnitude", "final_loss_factor", "mode"]  # docs/files.md's six first
    assert set(pred["mode"]) == {"axial", "torsion"}


def test_the_explorer_reads_several_files_and_predicts_the_other_modes():
    from app.main import App

    app = App()
    data = multi_mode(modes=("axial", "radial"), per_amplitude=10, seed=40)
    axial, radial = data.select(data.mode == "axial"), data.select(data.mode == "radial")
    plain = MeasuredStiffness(axial.frequency_hz, axial.amplitude, axial.stiffness).to_csv()
    app.tabs.active = 3
    app.measured.stiffness_file.value = {"axial.csv": plain, "radial.csv": radial.to_csv()}
    s = app.state
    assert len(s.measured) == 60 and sorted(set(s.measured.mode)) == ["axial", "radial"]
    assert len(curves.measured_points(s.measured, s.design.mode)["frequency_hz"]) == 30  # the explorer's mode (axial) is drawn
    assert "60 points in axial, radial (30 axial shown)" in app.measured.summary.object
    s.shear_modulus_mpa = 1.5
    app.fit.fit_on = "mode=axial"
    app.fit.run_fit()
    r = app.fit.fit_result
    assert r.prediction["points_fitted"] == 30 and r.prediction["gap_held_out"] < 3 * NOISE
    assert "**Fitted on mode=axial** (30 points)" in app.measured.results.object
    assert "| radial | " in app.measured.results.object and "predicted" in app.measured.results.object
    assert app.measured.prediction_box.visible
    shown = {el.label: el for el in app.measured.prediction.object}
    assert set(shown) == {"axial, fitted", "radial, predicted"}
    read = s.measured.select(s.measured.mode == "radial")  # as read from the file
    k = model_stiffness(r.design, read)
    np.testing.assert_allclose(np.sort(shown["radial, predicted"].dimension_values(1)),
                               np.sort(100 * (np.abs(k) / np.abs(read.stiffness) - 1)), rtol=1e-9)
    app.fit.fit_on = "mode=shear"
    app.fit.run_fit()
    assert "chooses none" in s.data_message


def test_a_bad_file_among_several_is_left_out_with_its_message():
    from app.state import ExplorerState

    s = ExplorerState()
    good = multi_mode(modes=("axial",), per_amplitude=5, seed=50).to_csv()
    bad = "frequency_hz,amplitude,magnitude,loss_factor\n10,1e-4,,0.1\n"
    assert not s.load_measured_files({"good.csv": good, "bad.csv": bad})
    assert len(s.measured) == 15 and s.data_message.startswith("bad.csv: line 2")
    assert "not loaded; the other files are" in s.data_message
    assert s.load_measured_files({"good.csv": good}) and s.data_message == ""
    assert not s.load_measured_files({"bad.csv": bad}) and len(s.measured) == 15  # none good: the last data kept


def test_a_mode_this_bushing_cannot_compute_is_named():
    """Radial rows for a bushing outside the finite-length table (b/a = 6): the message names the
    rows and the table's range, in the fit and in the diagnosis."""
    from core.identify.diagnose import diagnose

    wide = PAPER_B.replace(outer_radius=0.12)
    data = multi_mode(modes=("axial", "radial"), per_amplitude=5)
    for run in (lambda: fit_global(wide, data), lambda: diagnose(wide, data, held_out=False)):
        with pytest.raises(ValueError, match=r"the data's radial rows: the finite-length shape factors cover b/a 1\.2–4"):
            run()
