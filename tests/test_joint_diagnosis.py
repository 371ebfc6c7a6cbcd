"""The discrepancy workflow on data of several modes: one material for every mode, each step's
support mode by mode, an apparent mass found on the rig that has it, and modes that disagree."""

import re

import numpy as np
import pytest

from core import PAPER_B
from core.bushing import stiffness_points
from core.data import MeasuredStiffness
from core.identify.diagnose import diagnose, summary
from core.identify.diagnose.statistics import runs
from core.identify.fit import fit_global, model_stiffness
from core.io.design_file import design_from_dict
from core.io.measured import combined
from core.rules import DesignError
from core.synthetic import synthetic_stiffness

NOISE = 0.005
AMPS = {"axial": [1e-5, 1e-4, 3.5e-4], "torsion": [1e-4, 1e-3, 1e-2]}
FREQ = np.linspace(5, 300, 30)


def two_modes(axial=PAPER_B, torsion=PAPER_B, seed=0):
    parts = []
    for i, (mode, source) in enumerate((("axial", axial), ("torsion", torsion))):
        d = synthetic_stiffness(source.in_mode(mode), FREQ, AMPS[mode], noise=NOISE, seed=seed + i)
        parts.append(MeasuredStiffness(d.frequency_hz, d.amplitude, d.stiffness, None,
                                       np.full(len(d), mode, dtype=object)))
    return combined(parts, "axial")


# ---- a rig effect stays with its mode ---------------------------------------------------------

def test_an_apparent_mass_acts_in_its_own_mode_only():
    axial = PAPER_B.replace(effects={"inertia": {"mass": 0.5}})
    torsion = axial.in_mode("torsion")
    assert torsion.effect_parameters == {} and torsion.every_effect == {"inertia@axial": {"mass": 0.5}}
    f, amp = np.array([50.0, 200.0]), np.array([1e-3, 1e-3])
    plain = stiffness_points(PAPER_B.in_mode("torsion"), f, amp)
    np.testing.assert_array_equal(stiffness_points(torsion, f, amp), plain)  # kg is no kg·m²
    back = torsion.in_mode("axial")  # and back on its own rig it acts again: K − ω²M
    assert back.effect_parameters == {"inertia": {"mass": 0.5}}
    k = stiffness_points(back, f, np.array([1e-4, 1e-4]))
    np.testing.assert_allclose(k, stiffness_points(PAPER_B, f, np.array([1e-4, 1e-4])) - (2 * np.pi * f) ** 2 * 0.5)
    again = design_from_dict(torsion.to_dict())  # the design file keeps the tie
    assert again == torsion


def test_the_card_puts_a_rigs_mass_on_its_own_direction_only():
    from core.card import card

    plain, massive = (card(d, 100.0, 1e-4, 1e-2) for d in (PAPER_B, PAPER_B.replace(effects={"inertia": {"mass": 0.5}})))
    for r0, r1 in zip(plain, massive):
        if r0["mode"] == "axial":  # K − ω²M on the axial rig
            assert r1["stiffness_real"] == pytest.approx(r0["stiffness_real"] - (2 * np.pi * 100.0) ** 2 * 0.5, rel=1e-12)
        else:
            assert r1["magnitude"] == r0["magnitude"], r0["mode"]


@pytest.mark.parametrize("effects, match", [
    ({"viscous@axial": {"viscosity": 1.0}}, "only an effect of the test rig"),
    ({"inertia@shear": {"mass": 1.0}}, "the mode after @ must be one of"),
    ({"inertia": {"mass": 1.0}, "inertia@axial": {"mass": 2.0}}, "given for the axial mode twice"),
])
def test_bad_mode_ties_are_refused_by_name(effects, match):
    with pytest.raises(DesignError, match=match):
        PAPER_B.replace(effects=effects)


def test_a_tie_to_the_designs_own_mode_is_the_plain_effect():
    assert PAPER_B.replace(effects={"inertia@axial": {"mass": 1.0}}).every_effect == {"inertia": {"mass": 1.0}}


def test_noise_runs_never_cross_modes():
    data = two_modes()
    data = data.select(np.isin(data.amplitude, [1e-4]))  # one amplitude value in both modes
    triples = runs(data)
    assert triples and all(len({data.mode[i], data.mode[j], data.mode[k]}) == 1 for i, j, k, *_ in triples)


# ---- the diagnosis across modes ---------------------------------------------------------------

def test_one_material_in_two_modes_needs_nothing_and_the_modes_agree():
    result = diagnose(PAPER_B, two_modes(), held_out=False)
    assert result.added == [] and not result.unexplained and not result.modes_disagree
    # one material per mode buys nothing: the extra five parameters only cost
    assert result.modes["bic_drop"] < 0
    for mode, g in result.modes["gap_joint_by_mode"].items():
        assert g == pytest.approx(NOISE * np.sqrt(2), rel=0.2), mode
    assert "the modes agree" in summary(result)


@pytest.mark.parametrize("design_mode", ["axial", "torsion"])
def test_a_fixture_mass_on_the_axial_rig_is_found_there(design_mode):
    data = two_modes(axial=PAPER_B.replace(effects={"inertia": {"mass": 0.4}}))
    result = diagnose(PAPER_B.in_mode(design_mode), data, held_out=False)
    assert result.added == ["inertia"] and not result.modes_disagree and not result.unexplained
    step = result.steps[0]
    assert step.mode == "axial" and step.report()["mode"] == "axial"
    assert step.parameters["mass"] == pytest.approx(0.4, abs=3 * step.standard_errors["mass"])
    assert "on the axial rig only" in summary(result)
    # the mass in the unit of the rig it was found on, whatever the design's mode (issue #27, item 5)
    assert re.search(r"mass = [0-9.]+ kg ± [0-9.]+ kg;", summary(result)), summary(result)
    final = result.final.design
    assert final.in_mode("axial").effect_parameters["inertia"]["mass"] == pytest.approx(step.parameters["mass"])
    assert final.in_mode("torsion").effect_parameters == {}
    # the report's design reproduces the final gap on every row
    k = model_stiffness(design_from_dict(result.report()["design"]), data)
    assert np.sqrt(np.mean(np.abs((k - data.stiffness) / np.abs(data.stiffness)) ** 2)) == pytest.approx(
        result.final.gap, rel=1e-6)


def test_an_effect_of_the_rubber_is_named_once_and_every_mode_supports_it():
    viscous = PAPER_B.replace(effects={"viscous": {"viscosity": 300.0}})
    result = diagnose(PAPER_B, two_modes(viscous, viscous), held_out=False)
    assert result.added == ["viscous"] and not result.modes_disagree
    step = result.steps[0]
    assert step.mode is None and step.supported_by == ["axial", "torsion"]
    assert step.parameters["viscosity"] == pytest.approx(300.0, abs=3 * step.standard_errors["viscosity"])
    for mode, evidence in step.by_mode.items():  # each mode's own misfit falls to its noise
        assert evidence["gap_after"] < evidence["gap_before"], mode
    assert "supported by every mode" in summary(result)


def test_two_materials_in_two_modes_are_flagged():
    other = PAPER_B.replace(shear_modulus=PAPER_B.material.shear_modulus * 1.3,
                            friction_stress_max=PAPER_B.material.friction_stress_max * 0.6)
    data = two_modes(torsion=other)
    joint = fit_global(PAPER_B, data)  # the joint fit's gap per mode shows it: far above the noise
    assert min(joint.gap_by_mode.values()) > 3 * NOISE * np.sqrt(2)
    result = diagnose(PAPER_B, data, held_out=False)
    assert result.modes_disagree and result.unexplained
    modes = result.modes
    assert modes["bic_drop"] > 100
    for mode in ("axial", "torsion"):  # alone, each mode is fitted to its noise…
        assert modes["gap_alone_by_mode"][mode] == pytest.approx(NOISE * np.sqrt(2), rel=0.2)
        assert modes["gap_joint_by_mode"][mode] > 3 * modes["gap_alone_by_mode"][mode]
    alone = modes["parameters_alone"]  # …and recovers its own material
    assert alone["torsion"]["shear_modulus"] / alone["axial"]["shear_modulus"] == pytest.approx(1.3, rel=0.05)
    assert "the modes disagree" in summary(result)
