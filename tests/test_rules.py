"""The input rules of core/rules.py: every refusal of a design, a measured-data file, a tolerance
file or a targets file carries the code of the rule it breaks (the codes are the documented
strings, written out here as a program reading them would), its key and its words; numbers written
as text follow one rule on the command line and in the data files."""

import json

import numpy as np
import pytest

from cli.main import main
from core import PAPER_B, write_design
from core.bushing import MAX_STRAIN
from core.io.design_file import loads_design, read_design
from core.io.measured import parse_loop, parse_stiffness, read_stiffness
from core.io.targets import loads_problem
from core.io.tolerances import loads_tolerances
from core.rules import CODES, RuleError
from core.sampling import latin_hypercube
from core.whatif.tolerance import MAX_EVALUATIONS, Tolerances, band


def _design(**section) -> str:
    data = PAPER_B.to_dict()
    for where, changes in section.items():
        data[where] = {**data[where], **changes} if isinstance(changes, dict) else changes
    return json.dumps(data)


def _refused(read, text) -> RuleError:
    with pytest.raises(RuleError) as info:
        read(text)
    assert info.value.code in CODES
    return info.value


@pytest.mark.parametrize("text, key, code", [
    (_design(geometry={"outer_radius": 0.01}), "geometry.outer_radius", "outer_not_larger"),
    (_design(geometry={"outer_radius": 0.02}), "geometry.outer_radius", "outer_not_larger"),  # b = a
    (_design(material={"fractional_order": 1.5}), "material.fractional_order", "order_range"),
    (_design(material={"fractional_order": 0}), "material.fractional_order", "order_range"),
    (_design(material={"shear_modulus": -1}), "material.shear_modulus", "not_positive"),
    (_design(material={"shear_modulus": "2e6"}), "material.shear_modulus", "not_a_number"),
    (_design(material={"shear_modulus": True}), "material.shear_modulus", "not_a_number"),
    (_design(geometry={"length": 10**400}), "geometry.length", "overflow"),
    (_design(geometry={"length": 1e4}), "geometry.length", "out_of_range"),
    (_design(material={"shear_modulus": 1e13}), "material.shear_modulus", "out_of_range"),
    (_design().replace("0.09", "NaN"), "geometry.length", "not_finite"),
    (_design(material={"density": 1100}), "material.density", "unknown_key"),
    (_design(mode="shear"), "mode", "bad_choice"),
    (_design(mode="conical", shape="long"), "shape", "bad_choice"),
    (_design(geometry="big"), "geometry", "bad_type"),
    (_design().replace('"mode": "axial"', '"mode": "axial", "mode": "torsion"'), "mode", "duplicate_key"),
    (json.dumps({"mode": "axial", "material": PAPER_B.to_dict()["material"]}), "geometry", "missing_key"),
    ("{", "", "bad_json"),
    ("[" * 50_000 + "]" * 50_000, "", "bad_json"),
    (" " * 1_000_001, "", "too_large"),
])
def test_a_design_refusal_names_its_key_and_its_rule_code(text, key, code):
    err = _refused(loads_design, text)
    assert (err.key, err.code) == (key, code), str(err)
    assert str(err) == (f"{key}: {err.rule}" if key else err.rule)


def test_a_design_file_names_the_rule_of_the_file(tmp_path):
    assert _refused(read_design, tmp_path / "none.json").code == "unreadable"
    (tmp_path / "latin1.json").write_bytes('{"name": "é"}'.encode("latin-1"))
    assert _refused(read_design, tmp_path / "latin1.json").code == "not_utf8"
    (tmp_path / "big.json").write_text(" " * 1_000_001)
    assert _refused(read_design, tmp_path / "big.json").code == "too_large"
    (tmp_path / "bad.json").write_text(_design(geometry={"outer_radius": 0.01}))
    err = _refused(read_design, tmp_path / "bad.json")
    assert (err.key, err.code) == ("geometry.outer_radius", "outer_not_larger") and "(in bad.json)" in err.rule


def _effects(effects) -> str:
    return json.dumps({**PAPER_B.to_dict(), "effects": effects})


@pytest.mark.parametrize("effects, key, code", [
    ("inertia", "effects", "bad_type"),
    ({"colour": {}}, "effects.colour", "unknown_key"),
    ({"viscous@torsion": {"viscosity": 1.0}}, "effects.viscous@torsion", "bad_choice"),  # the rubber's
    ({"inertia@shear": {"mass": 0.5}}, "effects.inertia@shear", "bad_choice"),
    ({"friction": {"friction_stress_max": 1e4, "friction_strain_half": 1e-3}}, "effects.friction",
     "bad_choice"),  # a branch: its parameters belong in material
    ({"inertia": 0.5}, "effects.inertia", "bad_type"),
    ({"inertia": {"mass": 0.5, "colour": 1}}, "effects.inertia.colour", "unknown_key"),
    ({"inertia": {}}, "effects.inertia.mass", "missing_key"),
    ({"inertia": {"mass": -0.5}}, "effects.inertia.mass", "negative"),
])
def test_an_effect_refusal_names_its_key_and_its_rule_code(effects, key, code):
    err = _refused(loads_design, _effects(effects))
    assert (err.key, err.code) == (key, code), str(err)


def test_a_band_too_large_is_refused_as_too_large():
    """5000 samples × 4001 points: past the evaluations a band may take, refused before any."""
    tolerances = Tolerances({"shear_modulus": 0.1}, samples=5000, seed=1)
    points = MAX_EVALUATIONS // 5000 + 1
    err = _refused(lambda f: band(PAPER_B, f, 1e-4, tolerances), np.linspace(1.0, 100.0, points))
    assert (err.key, err.code) == ("", "too_large"), str(err)


@pytest.mark.parametrize("effects", [{}, {"inertia": {"mass": 0.5}}])  # all samples at once; one by one
def test_a_band_sample_beyond_the_models_strain_is_refused_as_out_of_range(effects):
    """At 99 % of the largest drive the nominal design takes, a sample whose outer radius is
    10 % smaller strains the rubber more (axial c = 1 / √(2 (b² − a²) ln(b/a)), eq 15): beyond
    what the model takes."""
    design = PAPER_B.replace(effects=effects)
    tolerances = Tolerances({"outer_radius": 0.1}, samples=50, seed=1)
    err = _refused(lambda x: band(design, 10.0, x, tolerances), 0.99 * design.drive(MAX_STRAIN))
    assert (err.key, err.code) == ("", "out_of_range"), str(err)
    assert "within these tolerances the bushing leaves what the model computes" in err.rule


HEAD = "frequency_hz,amplitude,magnitude,loss_factor\n"


@pytest.mark.parametrize("text, key, code", [
    (HEAD + "10,1e-4,four,0.1\n", "line 2", "not_a_number"),
    (HEAD + "10,1e-4,4e6,nan\n", "line 2", "not_finite"),
    (HEAD + "10,1e-4,1e999,0.1\n", "line 2", "overflow"),
    (HEAD + "10,1e-4,4e6,0.1\n20,1e-4,,0.1\n", "line 3", "missing_key"),
    (HEAD + "-10,1e-4,4e6,0.1\n", "line 2", "not_positive"),
    (HEAD + "1e6,1e-4,4e6,0.1\n", "line 2", "out_of_range"),
    (HEAD + "10,1e-4,1e300,0.1\n", "line 2", "out_of_range"),
    ("frequency_hz,amplitude,magnitude\n10,1e-4,4e6\n", "line 1", "missing_key"),
    (HEAD.strip() + ",comment\n10,1e-4,4e6,0.1,ok\n", "line 1", "unknown_key"),
    (HEAD.strip() + ",phase_deg\n10,1e-4,4e6,0.1,7\n", "line 2", "conflict"),
    ("mode," + HEAD + "shear,10,1e-4,4e6,0.1\n", "line 2", "bad_choice"),
    (HEAD + "10,1e-4,4e6,0.1,7\n", "", "bad_table"),
    (HEAD, "", "empty"),
    ("", "", "empty"),
    (b"\xff\xfe\x00", "", "not_utf8"),
])
def test_a_stiffness_file_refusal_names_its_line_and_its_rule_code(text, key, code):
    err = _refused(parse_stiffness, text)
    assert (err.key, err.code) == (key, code), str(err)


def test_a_loop_refusal_names_its_rule_code(tmp_path):
    head, t = "time_s,displacement,force\n", np.arange(40) * 0.01
    rows = [f"{a},{1e-3 * np.sin(2 * np.pi * a)},{100 * np.sin(2 * np.pi * a)}\n" for a in t]
    backwards = head + "".join(rows[:3] + rows[2:])
    err = _refused(parse_loop, backwards)
    assert (err.key, err.code) == ("line 5", "bad_signal"), str(err)
    assert _refused(parse_loop, head.replace("force", "load") + "".join(rows)).code == "unknown_key"
    assert _refused(parse_loop, head + "".join(f"{a},0,1\n" for a in t)).code == "bad_signal"  # never moves
    assert _refused(read_stiffness, tmp_path / "none.csv").code == "unreadable"


TOLERANCES = {"tolerances": {"shear_modulus": "10%"}, "samples": 50}


@pytest.mark.parametrize("change, key, code", [
    ({"tolerances": {"colour": "10%"}}, "tolerances.colour", "unknown_key"),
    ({"tolerances": {"length": -0.001}}, "tolerances.length", "negative"),
    ({"tolerances": {"length": "-1%"}}, "tolerances.length", "not_a_number"),
    ({"tolerances": {"length": "95%"}}, "tolerances.length", "out_of_range"),
    ({"tolerances": {"length": None}}, "tolerances.length", "not_a_number"),
    ({"distribution": "lognormal"}, "distribution", "bad_choice"),
    ({"samples": 5}, "samples", "out_of_range"),
    ({"samples": "many"}, "samples", "not_a_number"),
    ({"percentiles": "all"}, "percentiles", "bad_type"),
    ({"tolerances": {"shear_modulus": "0%"}}, "tolerances", "empty"),
    ({"fit_covariance": True}, "fit_covariance", "missing_key"),
    ({"colour": 1}, "colour", "unknown_key"),
])
def test_a_tolerance_refusal_names_its_key_and_its_rule_code(change, key, code):
    err = _refused(loads_tolerances, json.dumps({**TOLERANCES, **change}))
    assert (err.key, err.code) == (key, code), str(err)


def test_a_tolerance_file_is_strict_json():
    assert _refused(loads_tolerances, '{"samples": 50, "samples": 60}').code == "duplicate_key"
    assert _refused(loads_tolerances, '{"samples": ').code == "bad_json"
    assert _refused(loads_tolerances, " " * 100_001).code == "too_large"


def _targets(**change) -> str:
    target = {"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": 4e6}
    return json.dumps({"design": PAPER_B.to_dict(), "targets": [{**target, **change}]})


@pytest.mark.parametrize("text, key, code", [
    (_targets(frequency_hz=0), "targets[0].frequency_hz", "not_positive"),
    (_targets(frequency_hz=1e9), "targets[0].frequency_hz", "out_of_range"),
    (_targets(frequency_hz="10 Hz"), "targets[0].frequency_hz", "not_a_number"),
    (_targets(magnitude={"min": 5e6, "max": 4e6}), "targets[0].magnitude", "conflict"),
    (_targets(mode="shear"), "targets[0]", "bad_choice"),
    (_targets(colour="red"), "targets[0].colour", "unknown_key"),
    (_targets(amplitude=100.0), "targets[0]", "out_of_range"),  # beyond the strain the model takes
    (_targets().replace('"outer_radius": 0.035', '"outer_radius": 0.01'), "design.geometry.outer_radius",
     "outer_not_larger"),
    ('{"solutions": 1, "solutions": 2}', "", "duplicate_key"),
    (json.dumps({"targets": []}), "design", "missing_key"),
])
def test_a_targets_refusal_names_its_key_and_its_rule_code(text, key, code):
    err = _refused(loads_problem, text)
    assert (err.key, err.code) == (key, code), str(err)


@pytest.mark.parametrize("text", ["١٠", "１０"])
def test_a_command_line_number_follows_the_data_files_rule(tmp_path, capsys, text):
    """``--freq`` takes what a CSV cell takes: plain ASCII decimals (Python's float() would also
    take Arabic-Indic and full-width digits, as it takes underscores, nan and inf)."""
    design = tmp_path / "d.json"
    write_design(PAPER_B, design)
    with pytest.raises(SystemExit) as status:
        main(["loop", str(design), "--freq", text, "--amp", "1e-3"])
    assert status.value.code == 2
    assert f"--freq must be a number, got {text!r}" in capsys.readouterr().err


def test_a_latin_hypercube_puts_one_point_in_each_stratum_of_every_column():
    points = latin_hypercube(12, 3, seed=4)
    assert points.shape == (12, 3)
    for column in points.T:
        assert sorted(np.floor(column * 12).astype(int)) == list(range(12))
    assert np.array_equal(points, latin_hypercube(12, 3, seed=4))
    assert not np.array_equal(points, latin_hypercube(12, 3, seed=5))


def test_the_first_key_given_twice_is_named_in_any_object_size():
    # the keys of one object are counted in one pass: a file of a hundred thousand keys (within
    # the 1 MB limit) is read in one pass, and of several repeated keys the first in order is named
    from core.rules import Words, strict_json

    keys = [f"k{i}" for i in range(100_000)] + ["k7", "k3", "k7"]
    text = "{" + ",".join(f'"{k}": 1' for k in keys) + "}"
    with pytest.raises(RuleError) as info:
        strict_json(text, 10**7, Words(twice="{key} twice", key_twice=True), RuleError)
    assert (info.value.key, info.value.code) == ("k3", "duplicate_key")
    assert len(strict_json("{" + ",".join(f'"{k}": 1' for k in keys[:100_000]) + "}", 10**7, Words(),
                           RuleError)) == 100_000
