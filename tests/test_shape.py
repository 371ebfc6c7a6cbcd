"""Shape factors in every direction (core/shape.py): the energy-balance equivalent strain against
the thesis' eqs 14–15; the felupe model against torsion's exact formula at any length, against
the long-bushing formulas as the length grows, converging as h²; the shipped table against
direct solves; radial and conical stiffness as S · µ_eq(ε_eq) of the same material model."""

import functools
import math

import numpy as np
import pytest

from core import PAPER_B, stiffness
from core.bushing import factors, shape_factor
from core.rules import DesignError
from core.shape import (
    OutsideTable,
    converged_shape_factor,
    fe_shape_factor,
    finite_shape_factor,
    long_shape_factor,
    reference_shape_factor,
    strain_factor_from_shape,
    table,
)
from tests.test_material import reference_modulus

GEOMETRIES = [(0.02, 0.035, 0.09), (0.005, 0.011, 0.022), (0.01, 0.04, 0.015), (0.03, 0.036, 0.2)]


@pytest.mark.parametrize("a, b, L", GEOMETRIES)
def test_energy_balance_gives_the_thesis_equivalent_strains(a, b, L):
    """ε_eq = x̂ √(S/(4V)): eq 15 with the long axial S, eq 14 with the torsion S."""
    axial = strain_factor_from_shape(long_shape_factor(a, b, L, "axial"), a, b, L)
    torsion = strain_factor_from_shape(long_shape_factor(a, b, L, "torsion"), a, b, L)
    assert axial == pytest.approx(1 / math.sqrt(2 * (b * b - a * a) * math.log(b / a)), rel=1e-13)
    assert torsion == pytest.approx(a * b / (b * b - a * a), rel=1e-13)


@pytest.mark.parametrize("length_ratio", [0.5, 6.0])
def test_fe_torsion_is_the_exact_formula_at_any_length(length_ratio):
    a, b = 1.0, 1.75
    L = length_ratio * (b - a)
    fe = converged_shape_factor(a, b, L, "torsion", (4, 6))
    assert fe.value == pytest.approx(long_shape_factor(a, b, L, "torsion"), rel=1e-3)


def test_fe_converges_as_h_squared():
    """Three meshes of Paper B's bushing, radial: the observed order of convergence is about 2,
    which Richardson's extrapolation assumes."""
    a, b, L = PAPER_B.geometry.inner_radius, PAPER_B.geometry.outer_radius, PAPER_B.geometry.length
    s4, s6, s8 = (fe_shape_factor(a, b, L, "radial", n)[0] for n in (4, 6, 8))
    q = (s4 - s6) / (s6 - s8)
    order = next(p for p in np.linspace(1.0, 3.0, 2001) if (4**-p - 6**-p) / (6**-p - 8**-p) >= q)
    assert 1.7 < order < 2.3


@pytest.mark.parametrize("mode", ["axial", "radial"])
def test_fe_tends_to_the_long_formula_as_the_bushing_grows(mode):
    """The ends' deficit 1 − S/S_long falls as (b − a)/L: extrapolated to L → ∞ from three
    lengths, the ratio is 1 (radial: up to the compressibility of K/µ = 5000)."""
    a, b = 1.0, 1.75
    lengths = np.array([6.0, 12.0, 24.0])
    ratios = [converged_shape_factor(a, b, lam * (b - a), mode, (4, 6)).value
              / long_shape_factor(a, b, lam * (b - a), mode) for lam in lengths]
    assert np.all(np.diff(ratios) > 0)  # longer: closer to the long bushing
    coef = np.polyfit(1 / lengths, ratios, 2)  # R = R∞ + c/λ + d/λ²
    assert coef[-1] == pytest.approx(1.0, abs=0.01 if mode == "axial" else 0.02)


def test_the_table_matches_direct_solves_inside_it():
    q, lam = 1.6, 2.5  # between the table's nodes in both directions
    for mode in ("axial", "radial", "conical"):
        direct = converged_shape_factor(1.0, q, lam * (q - 1.0), mode).value
        assert finite_shape_factor(1.0, q, lam * (q - 1.0), mode) == pytest.approx(direct, rel=0.005), mode
    t = table()
    assert t.radius_ratio[0] <= 1.25 and t.radius_ratio[-1] >= 4 and t.length_ratio[-1] >= 12


def test_outside_the_table_or_without_a_closed_form_is_a_clear_message():
    with pytest.raises(OutsideTable, match="b/a .* L/\\(b − a\\)"):
        finite_shape_factor(0.01, 0.2, 0.1, "radial")  # b/a = 20
    with pytest.raises(ValueError, match="conical: no closed form"):
        long_shape_factor(0.02, 0.035, 0.09, "conical")
    with pytest.raises(DesignError, match="shape"):
        PAPER_B.replace(mode="conical", shape="long")
    with pytest.raises(ValueError, match="0 < a < b"):
        long_shape_factor(0.03, 0.02, 0.09, "axial")


def test_finite_length_is_an_option_for_axial_and_torsion():
    axial_long, axial_finite = PAPER_B, PAPER_B.replace(shape="finite")
    g = PAPER_B.geometry
    ratio = shape_factor(g, "axial", "finite") / shape_factor(g, "axial", "long")
    assert 0.95 < ratio < 0.99  # Paper B: the ends take about 3.5 % off
    k_long = stiffness(axial_long, [10.0], [1e-4]).stiffness[0, 0]
    k_finite = stiffness(axial_finite, [10.0], [1e-4]).stiffness[0, 0]
    assert abs(k_finite) < abs(k_long)
    torsion = PAPER_B.replace(mode="torsion")
    # eq 17 is exact at any length: the finite torsion S is that closed form, to round-off
    exact = 4 * math.pi * (g.inner_radius * g.outer_radius) ** 2 * g.length / (g.outer_radius**2 - g.inner_radius**2)
    assert shape_factor(g, "torsion", "finite") == pytest.approx(exact, rel=1e-13)
    assert shape_factor(g, "torsion", "long") == pytest.approx(exact, rel=1e-13)
    assert factors(torsion.replace(shape="finite")) == pytest.approx(factors(torsion), rel=1e-12)


@functools.cache
def fe_paper_b(mode: str) -> float:
    """S of Paper B's bushing in ``mode`` from a direct FE solve, not the table: meshes of 4 and
    6 elements across the wall, extrapolated (within 0.1 % of the table's 6 and 8 here)."""
    g = PAPER_B.geometry
    return converged_shape_factor(g.inner_radius, g.outer_radius, g.length, mode, (4, 6)).value


def energy_strain_factor(s: float, geometry) -> float:
    """c = √(S/(4V)), V = π(b² − a²)L: docs/model.md's energy balance, written out here."""
    a, b, L = geometry.inner_radius, geometry.outer_radius, geometry.length
    return math.sqrt(s / (4 * math.pi * (b * b - a * a) * L))


# the table's stated accuracy against direct converged solves (tools/shape_table.py)
TABLE_ACCURACY = 0.005


@pytest.mark.parametrize("mode", ["radial", "conical"])
def test_radial_and_conical_stiffness_is_the_material_model_at_the_equivalent_strain(mode):
    """K = S · µ_eq(f, ε_eq) with ε_eq = x̂ √(S/(4V)): the Fletcher–Gent softening in every
    direction from the same five parameters. Expected by an independent route: S of a direct FE
    solve of this bushing, µ_eq by quadrature of the Berg loop (tests/test_material.py)."""
    design = PAPER_B.replace(mode=mode)
    s = fe_paper_b(mode)
    c = energy_strain_factor(s, design.geometry)
    x = np.geomspace(1e-6, 1e-3, 7) if mode == "radial" else np.geomspace(1e-5, 1e-2, 7)  # ε̂/ε½ 0.03–30
    f = np.array([1.0, 10.0])
    # the shape: an elastic rubber (no friction, no fractional branch) has K = S µ
    elastic = stiffness(design.replace(friction_stress_max=1e-9, fractional_coefficient=1e-9), f, x).stiffness
    np.testing.assert_allclose(elastic / design.material.shear_modulus, s, rtol=TABLE_ACCURACY)
    # the material at the equivalent strain: K / (S µ) is µ_eq / µ whatever S is
    k = stiffness(design, f, x).stiffness
    expected = reference_modulus(design.material, f[None, :], c * x[:, None])
    # c is uncertain by half of S's 0.5 %, which moves µ_eq by that times |d ln µ_eq / d ln ε̂|
    eps = c * x[:, None]
    slope = np.abs(np.log(reference_modulus(design.material, f, 1.001 * eps) / expected)) / np.log(1.001)
    np.testing.assert_allclose(k / elastic * design.material.shear_modulus, expected,
                               rtol=TABLE_ACCURACY / 2 * slope.max() + 1e-9)
    assert np.all(np.diff(np.abs(k[:, 1])) < 0)  # softer as the amplitude grows


def test_reference_of_the_conical_table_is_the_radial_stiffness_per_length_with_its_lever_arm():
    """The long radial S is the plane-strain, incompressible closed form, written out here; the
    conical table's scale is it with the lever arm² summed over the length, S · L²/12."""
    a, b, L = 0.02, 0.035, 0.09
    q = a * a + b * b
    radial = 4 * math.pi * L * q / (q * math.log(b / a) - (b * b - a * a))
    assert long_shape_factor(a, b, L, "radial") == pytest.approx(radial, rel=1e-13)  # round-off
    assert reference_shape_factor(a, b, L, "conical") == pytest.approx(radial * L**2 / 12, rel=1e-13)


def test_bushing_card_on_the_command_line(tmp_path, capsys):
    """`bushing card`: four rows in the documented order and columns, each the core's
    stiffness of the design in that direction; the ratios of docs/model.md."""
    import csv
    import io

    from cli.main import main
    from core import write_design
    from core.bushing import stiffness_points
    from core.card import card_design, ratios

    path = tmp_path / "d.json"
    write_design(PAPER_B, path)
    assert main(["card", str(path), "--freq", "10", "--amp-mm", "0.1", "--amp-rad", "0.01"]) == 0
    out = capsys.readouterr().out
    rows = list(csv.DictReader(io.StringIO(out)))
    assert list(rows[0]) == ["mode", "amplitude", "stiffness_real", "stiffness_imag", "magnitude", "loss_factor",
                             "shape_factor"]
    assert [r["mode"] for r in rows] == ["axial", "radial", "torsion", "conical"]
    for r in rows:
        d = card_design(PAPER_B, r["mode"])  # no shape in the file: its rule in each direction
        assert d.shape_kind == ("long" if r["mode"] in ("axial", "torsion") else "finite")
        k = complex(stiffness_points(d, 10.0, float(r["amplitude"])))
        assert float(r["stiffness_real"]) == pytest.approx(k.real, rel=1e-9)
        assert float(r["magnitude"]) == pytest.approx(abs(k), rel=1e-9)
    assert [float(r["amplitude"]) for r in rows] == [1e-4, 1e-4, 0.01, 0.01]
    numbers = [{k: (v if k == "mode" else float(v)) for k, v in r.items()} for r in rows]
    q = ratios(PAPER_B, numbers)
    assert q["radial/axial"] == pytest.approx(numbers[1]["magnitude"] / numbers[0]["magnitude"])
    assert 3 < q["radial/axial"] < 10  # radially a bonded rubber tube is several times stiffer
    with pytest.raises(SystemExit) as refused:
        main(["card", str(path), "--freq", "10", "--amp-mm", "-1", "--amp-rad", "0.01"])
    assert refused.value.code == 2 and "--amp-mm" in capsys.readouterr().err


def test_a_radial_measurement_identifies_the_material():
    """Synthetic radial data (five displacements, 0.5 % noise): the fit in radial mode recovers
    the five parameters within its intervals; the same material predicts the axial card."""
    from core.identify.fit import fit_global
    from core.registry import parameter_values
    from core.synthetic import synthetic_stiffness

    truth = PAPER_B.replace(mode="radial")
    data = synthetic_stiffness(truth, np.linspace(5, 155, 30), [2e-6, 6e-6, 2e-5, 5e-5, 1.5e-4], seed=5)
    start = truth.replace(shear_modulus=1.5e6, fractional_coefficient=1e6, fractional_order=0.4,
                          friction_stress_max=4e4, friction_strain_half=1e-3)
    result = fit_global(start, data)
    assert result.undetermined == [] and result.gap < 0.01
    expected = parameter_values(PAPER_B)
    for name, (lo, hi) in result.intervals.items():
        assert lo <= expected[name] <= hi, name


@pytest.mark.parametrize("shape", [None, "long", "finite"])
def test_an_unknown_mode_is_refused_by_name_with_or_without_a_shape(shape):
    # with no shape the mode's default shape was looked up first: a KeyError, not the rule
    from core.shape import shape_factor, strain_factor

    for factor in (shape_factor, strain_factor):
        with pytest.raises(ValueError, match="mode must be one of axial, torsion, radial, conical, got 'sideways'"):
            factor(PAPER_B.geometry, "sideways", shape)
