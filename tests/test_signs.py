"""Measured stiffness of any sign: a negative loss factor (a blocked stiffness above a standing-wave
resonance) and Re K < 0 (a mass-dominated one) are measurements, read, fitted, diagnosed, plotted
and exported with their signs (docs/files.md, "Measured dynamic stiffness")."""

import json
import math

import holoviews as hv
import numpy as np
import pytest
from numpy.testing import assert_allclose

from app import plots
from cli.commands import main
from core import PAPER_B
from core.data import DataError
from core.io.design_file import design_from_dict
from core.io.measured import parse_stiffness
from core.synthetic import synthetic_stiffness

HEADERS = {"polar": "magnitude,loss_factor", "cartesian": "stiffness_real,stiffness_imag",
           "phase": "magnitude,phase_deg"}
# one point in each quadrant of the complex plane (N/m)
QUADRANTS = [4e6 + 5e5j, 4e6 - 3e4j, -3.5e6 + 6.8e5j, -2e6 - 1e5j]


def row_of(form: str, k: complex) -> str:
    """One file row written the way a rig would, straight from K (not through the reader's
    inverse): |K| and η = Im/Re, the two parts, or |K| and the angle in degrees."""
    if form == "polar":
        return f"{abs(k)!r},{k.imag / k.real!r}"
    if form == "cartesian":
        return f"{k.real!r},{k.imag!r}"
    return f"{abs(k)!r},{math.degrees(math.atan2(k.imag, k.real))!r}"


def file_of(form: str, ks) -> str:
    return (f"frequency_hz,amplitude,{HEADERS[form]}\n"
            + "".join(f"{10 * (i + 1)},1e-4,{row_of(form, k)}\n" for i, k in enumerate(ks)))


def test_the_users_row_with_a_negative_loss_factor_is_read():
    data = parse_stiffness("frequency_hz,amplitude,magnitude,loss_factor\n800,0.008,7950.23,-0.0075\n")
    k = data.stiffness[0]
    # |K| e^{iδ} with tan δ = η: the phase is atan(−0.0075), Re K > 0, Im K < 0
    assert_allclose([k.real, k.imag], [7950.23 * math.cos(math.atan(-0.0075)),
                                       7950.23 * math.sin(math.atan(-0.0075))], rtol=1e-14)
    assert k.real > 0 > k.imag
    assert_allclose(data.loss_factor, [-0.0075], rtol=1e-13)


@pytest.mark.parametrize("form", ["cartesian", "phase"])
def test_every_quadrant_reads_back_in_the_forms_that_carry_the_sign(form):
    data = parse_stiffness(file_of(form, QUADRANTS))
    # the same complex numbers (rounding of the decimal text and of the degrees: 1e-15 relative)
    assert_allclose(data.stiffness, QUADRANTS, rtol=1e-13)
    assert_allclose(data.loss_factor, [k.imag / k.real for k in QUADRANTS], rtol=1e-12)
    assert np.sum(data.loss_factor < 0) == 2


def test_the_loss_factor_form_reads_the_right_half_plane_the_same_as_the_others():
    right = [k for k in QUADRANTS if k.real > 0]
    forms = {form: parse_stiffness(file_of(form, right)).stiffness for form in HEADERS}
    assert_allclose(forms["polar"], right, rtol=1e-13)
    assert_allclose(forms["phase"], forms["cartesian"], rtol=1e-13)


@pytest.mark.parametrize("phase", ["180", "-180", "0", "90", "-90"])
def test_phase_limits_are_inclusive(phase):
    data = parse_stiffness(f"frequency_hz,amplitude,magnitude,phase_deg\n10,1e-4,2e6,{phase}\n")
    assert_allclose(data.stiffness[0], 2e6 * np.exp(1j * math.radians(float(phase))), atol=1e-9)


@pytest.mark.parametrize("text,needle", [
    ("frequency_hz,amplitude,magnitude,phase_deg\n10,1e-4,2e6,180.5\n", "line 2: phase_deg must be within"),
    ("frequency_hz,amplitude,magnitude,phase_deg\n10,1e-4,2e6,1\n20,1e-4,2e6,-270\n", "line 3: phase_deg"),
    ("frequency_hz,amplitude,magnitude,phase_deg\n10,1e-4,-2e6,10\n", "line 2: magnitude must be positive"),
    ("frequency_hz,amplitude,magnitude,phase_deg\n10,1e-4,2e6,ten\n", "line 2: phase_deg is not a number"),
    ("frequency_hz,amplitude,magnitude,loss_factor,phase_deg\n10,1e-4,2e6,0.1,5\n", "line 2: the two forms of the stiffness disagree"),
    ("frequency_hz,amplitude,stiffness_real,stiffness_imag\n10,1e-4,1.5e308,1.5e308\n", "line 2: the stiffness is zero or too large"),
    ("frequency_hz,amplitude,stiffness_real,stiffness_imag\n10,1e-4,0,0\n", "line 2: the stiffness is zero"),
])
def test_malformed_values_stay_refused_with_one_line(text, needle):
    with pytest.raises(DataError, match=needle):
        parse_stiffness(text)


def run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    assert "Traceback" not in out.err
    return code, out


def test_a_blocked_torsion_stiffness_past_its_wave_resonance_is_diagnosed(tmp_path, capsys):
    """The user's case: torsion through a blocking fixture, Im K < 0 above ~780 Hz."""
    base = {"name": "blocked torsion", "mode": "torsion",
            "geometry": {"inner_radius": 0.02, "outer_radius": 0.05, "length": 0.1},
            "material": {"shear_modulus": 2e6, "fractional_coefficient": 2e5, "fractional_order": 0.4,
                         "friction_stress_max": 4e3, "friction_strain_half": 1e-3}}
    truth = design_from_dict({**base, "effects": {"wave_effects": {"density": 1100.0}}})
    data = synthetic_stiffness(truth, np.linspace(20, 900, 45), [0.002, 0.008], noise=0.003, seed=3)
    assert np.sum(data.loss_factor < 0) >= 4  # the file really has negative loss factors
    (tmp_path / "d.json").write_text(json.dumps(base))
    data.to_csv(tmp_path / "m.csv")
    code, out = run(["diagnose", str(tmp_path / "m.csv"), "--design", str(tmp_path / "d.json"),
                     "--json", str(tmp_path / "r.json"), "--predictions", str(tmp_path / "p.csv")], capsys)
    assert code == 0, out.err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["added"] == ["wave_effects"]  # and nothing spurious beside it
    step = report["steps"][0]
    assert abs(step["parameters"]["density"] - 1100.0) < 3 * step["standard_errors"]["density"]
    # noise 0.3 % in each part: the relative complex misfit of pure noise is √2 · 0.003
    assert report["gap_final"] < 1.5 * math.sqrt(2) * 0.003
    pred = np.genfromtxt(tmp_path / "p.csv", delimiter=",", names=True)
    assert np.all(np.isfinite(pred["final_loss_factor"])) and np.min(pred["final_loss_factor"]) < 0


@pytest.mark.parametrize("form", ["cartesian", "phase"])
def test_a_mass_dominated_stiffness_gives_the_fixture_mass_back(form, tmp_path, capsys):
    """Paper B behind a 20 kg fixture: Re K < 0 above √(K/M)/2π ≈ 70 Hz."""
    truth = PAPER_B.replace(effects={"inertia": {"mass": 20.0}})
    data = synthetic_stiffness(truth, np.linspace(1, 100, 30), [1e-5, 1e-4, 3e-4], noise=0.003, seed=4)
    assert np.sum(data.stiffness.real < 0) >= 10
    (tmp_path / "m.csv").write_text(file_of_rows(form, data))
    (tmp_path / "d.json").write_text(json.dumps(PAPER_B.to_dict()))
    code, out = run(["diagnose", str(tmp_path / "m.csv"), "--design", str(tmp_path / "d.json"),
                     "--json", str(tmp_path / "r.json")], capsys)
    assert code == 0, out.err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["added"] == ["inertia"]
    step = report["steps"][0]
    assert abs(step["parameters"]["mass"] - 20.0) < 3 * step["standard_errors"]["mass"]


def file_of_rows(form: str, data) -> str:
    return (f"frequency_hz,amplitude,{HEADERS[form]}\n"
            + "".join(f"{float(f)!r},{float(a)!r},{row_of(form, complex(k))}\n"
                      for f, a, k in zip(data.frequency_hz, data.amplitude, data.stiffness)))


def overlays_of(layout):
    return [o for o in layout.traverse(lambda x: x, [hv.Overlay])]


def test_plots_draw_the_loss_factor_with_its_sign_and_log_axes_only_over_positive_values():
    truth = PAPER_B.replace(effects={"inertia": {"mass": 20.0}})
    data = synthetic_stiffness(truth, np.linspace(1, 100, 12), [1e-4], noise=0.0, seed=1)
    layout = hv.Layout([*plots.explorer_plots(PAPER_B, 10.0, 0.1, measured=data, width=None),
                        *plots.residual_plots(PAPER_B, data, width=None)])
    drawn = []
    for overlay in overlays_of(layout):
        opts = hv.Store.lookup_options("bokeh", overlay, "plot").kwargs
        for element in overlay:
            for axis, log in ((0, opts.get("logx")), (1, opts.get("logy"))):
                values = np.asarray(element.dimension_values(axis), dtype=float)
                if log and values.size:
                    assert np.all(values[np.isfinite(values)] > 0), overlay.label
            if element.label == "measured" and element.vdims[0].name == "loss_factor":
                drawn.append(np.asarray(element.dimension_values(1), dtype=float))
    assert drawn, "no measured loss factor was drawn"
    # the file's loss factor, sign and all: Im K / Re K of each point
    for values in drawn:
        assert_allclose(np.sort(values), np.sort(data.stiffness.imag / data.stiffness.real), rtol=1e-12)
        assert np.sum(values < 0) >= 2


def test_exports_carry_the_sign_of_a_mass_dominated_stiffness(tmp_path, capsys):
    massive = PAPER_B.to_dict()
    massive["effects"] = {"inertia": {"mass": 20.0}}
    (tmp_path / "d.json").write_text(json.dumps(massive))
    code, out = run(["export", str(tmp_path / "d.json"), "--format", "table", "--freq", "1", "100", "3",
                     "--amp", "1e-4", "-o", str(tmp_path / "t.csv")], capsys)
    assert code == 0, out.err
    rows = np.genfromtxt(tmp_path / "t.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    axial = rows[rows["mode"] == "axial"]
    # K = K_bushing − ω² M at 100 Hz: 20 kg · (2π · 100)² ≈ 7.9 MN/m outweighs ~4.4 MN/m
    top = axial[axial["frequency_hz"] == 100][0]
    assert top["stiffness_real"] < 0 < top["stiffness_imag"]
    assert top["loss_factor"] == pytest.approx(top["stiffness_imag"] / top["stiffness_real"], rel=1e-9)
    assert top["loss_factor"] < 0
