"""The bulk modulus (issue #29): the series law of the finite-length table against direct FE
solves at other K/µ; the long radial closed form against Navier's equations solved as ODEs; the
correspondence principle (K* = µ*·S(µ*/K)) for the loss factor against the series law built from
direct FE solves; the design file and the bounds."""

import functools
import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from core import PAPER_B, DesignError, stiffness
from core.bushing import modulus_function
from core.identify.fit import fit_global
from core.io.design_file import design_from_dict, dumps_design, loads_design
from core.parameters import MATERIAL
from core.shape import (
    BULK_RATIO,
    converged_shape_factor,
    long_radial_compressible,
    long_shape_factor,
    table,
)


@functools.cache
def direct(q: float, lam: float, mode: str, ratio: float) -> float:
    """S of a bushing a = 1, b = q, L = lam·(b − a) at K/µ = ``ratio``: a direct FE solve (meshes
    of 4 and 6 elements across the wall, extrapolated), not the table."""
    return converged_shape_factor(1.0, q, lam * (q - 1.0), mode, (4, 6), ratio).value


# geometries between the table's nodes (thin to medium walls, where the bulk modulus matters)
OFF_GRID = [(1.27, 5.0), (1.62, 2.6)]


@pytest.mark.parametrize(("q", "lam"), OFF_GRID)
@pytest.mark.parametrize("mode", ["radial", "conical"])
@pytest.mark.parametrize("ratio", [700.0, 1500.0, 20000.0])
def test_the_tables_series_law_is_a_direct_solve_at_another_bulk_modulus(q, lam, mode, ratio):
    """S(K/µ)/S(5000) of the table (its slope from solves at 1000 and 5000 on its nodes) against
    direct solves at K/µ 700, 1500 and 20000 off its nodes: within 0.3 %."""
    solved = direct(q, lam, mode, ratio) / direct(q, lam, mode, BULK_RATIO)
    tabled = table().compressible_factor(mode, q, lam, 1.0 / ratio)
    assert tabled == pytest.approx(solved, rel=0.003)
    if ratio < BULK_RATIO:
        assert solved < 1.0  # a more compressible wall is softer


@pytest.mark.parametrize(("q", "lam"), OFF_GRID)
@pytest.mark.parametrize("mode", ["radial", "conical"])
@pytest.mark.parametrize("ratio", [800.0, 2000.0])
def test_the_shape_factor_with_a_bulk_modulus_is_a_direct_solve(q, lam, mode, ratio):
    """S itself, as the stiffness takes it (the shipped table's S at K/µ 5000 times its series
    law) against a direct FE solve at K/µ 800 and 2000 on the table's own meshes (6 and 8
    elements across the wall, extrapolated), off its nodes (b/a 1.27 and 1.62): within 1 %
    (issue #29's bound for |K|; S is |K|/|µ| of an elastic rubber). Measured: 0.09–0.75 %; the
    coarser meshes of :func:`direct` put the thinnest wall's radial S 1.0 % off, finer ones 0.6 %."""
    from core.design import Geometry
    from core.shape import shape_factor

    tabled = shape_factor(Geometry(1.0, q, lam * (q - 1.0)), mode, "finite")
    tabled *= table().compressible_factor(mode, q, lam, 1.0 / ratio)
    solved = converged_shape_factor(1.0, q, lam * (q - 1.0), mode, (6, 8), ratio).value
    assert tabled == pytest.approx(solved, rel=0.01)


def test_axial_hardly_cares_and_thin_walls_care_most():
    t = table()
    for q, lam in [(1.2, 12.0), (1.75, 6.0), (3.0, 1.5)]:
        assert abs(t.compressible_factor("axial", q, lam, 1e-3) - 1) < 2e-4
    # radial at K/µ 1000: thinner walls care more, and longer ones
    radial = [1 - t.compressible_factor("radial", q, 6.0, 1e-3) for q in (1.2, 1.5, 2.0, 3.0)]
    assert np.all(np.diff(radial) < 0) and radial[0] > 0.02 and radial[-1] < 0.01
    thin = [1 - t.compressible_factor("radial", 1.2, lam, 1e-3) for lam in (1.0, 3.0, 6.0, 12.0)]
    assert np.all(np.diff(thin) > 0) and thin[-1] > 0.05


def navier_radial(q: float, nu: float) -> float:
    """The long radial stiffness per length (µ = 1, a = 1, b = q) from Navier's equations in plane
    strain, solved as ODEs: u_r = U(r) cos θ, u_θ = −V(r) sin θ; the dilatation D and rotation
    W obey r(rD')' = D, W = (λ + 2µ)/µ · rD', so D = c₁r + c₂/r; U, V are integrated from r = 1
    for four unit choices of (c₁, c₂, U(1), V(1)), and the bonded conditions U = V = 1 at r = 1,
    0 at r = q fix them. The force on the inner tube is π(λ + 2µ)U'(1) + πµV'(1)."""
    lam = 2 * nu / (1 - 2 * nu)
    m = lam + 2

    def shoot(c1, c2, u0, v0):
        def rhs(r, y):
            u, v = y
            d, w = c1 * r + c2 / r, m * (c1 * r - c2 / r)
            return [d - (u - v) / r, (u - v - r * w) / r]

        return solve_ivp(rhs, (1.0, q), [u0, v0], rtol=1e-11, atol=1e-13).y[:, -1]

    rows = np.array([[*basis[2:], *shoot(*basis)] for basis in np.eye(4)]).T
    c1, c2, u0, v0 = np.linalg.solve(rows, [1.0, 1.0, 0.0, 0.0])
    d, w = c1 + c2, m * (c1 - c2)
    du, dv = d - (u0 - v0), (u0 - v0 - w)
    return math.pi * (m * du + dv)


@pytest.mark.parametrize("q", [1.2, 1.5, 2.5])
@pytest.mark.parametrize("nu", [0.3, 0.45, 0.49, 0.4999])
def test_the_long_radial_closed_form_solves_navier_s_equations(q, nu):
    x = 1.5 * (1 - 2 * nu) / (1 + nu)  # µ/K of Poisson's ratio ν
    assert long_radial_compressible(1.0, q, 1.0, x) == pytest.approx(abs(navier_radial(q, nu)), rel=1e-6)


def test_the_long_radial_closed_form_at_its_limits():
    assert long_radial_compressible(1.0, 1.5, 2.0, 0.0) == pytest.approx(long_shape_factor(1.0, 1.5, 2.0, "radial"),
                                                                          rel=1e-13)
    t, nu = 1e-3, 0.3  # a thin layer: compression (λ + 2µ) across it, shear µ along it
    lam = 2 * nu / (1 - 2 * nu)
    x = 1.5 * (1 - 2 * nu) / (1 + nu)
    assert long_radial_compressible(1.0, 1.0 + t, 1.0, x) == pytest.approx(math.pi * (lam + 3) / t, rel=2e-3)


def test_the_loss_factor_follows_the_correspondence_principle():
    """Radial Paper B with K = 2 GPa: K* = µ*·S(µ*/K). The series law built here from two direct
    FE solves (K/µ 5000 and 800), 1/K* = 1/(S∞µ*) + d/K with µ* the equivalent modulus at the
    shear layer's own strain amplitude (its strain factor √(S∞/(4V)), the bulk spring's share of
    the drive taken off), gives |K| and the loss factor; the bulk spring is elastic, so the loss
    factor falls below the shear's by its share of the compliance; torsion (pure shear) is
    unchanged."""
    g = PAPER_B.geometry
    a, b, L = g.inner_radius, g.outer_radius, g.length
    s5000 = converged_shape_factor(a, b, L, "radial", (4, 6)).value
    s800 = converged_shape_factor(a, b, L, "radial", (4, 6), 800.0).value
    d = (1 / s800 - 1 / s5000) / (1 / 800 - 1 / BULK_RATIO)
    s_inf = 1 / (1 / s5000 - d / BULK_RATIO)
    radial = PAPER_B.in_mode("radial")
    compressible = radial.replace(bulk_modulus=2.0e9)
    f, x = np.array([1.0, 30.0]), np.array([2e-5, 5e-4])
    ff, xx = np.meshgrid(f, x)
    strain = math.sqrt(s_inf / (4 * math.pi * (b * b - a * a) * L)) * xx  # the shear layer's c∞·x̂
    for _ in range(40):  # the fixed point ε̂ = c∞ x̂ / |1 + d S∞ µ*(ε̂)/K|
        mu = modulus_function(radial)(ff, strain)
        strain = math.sqrt(s_inf / (4 * math.pi * (b * b - a * a) * L)) * xx / np.abs(1 + d * s_inf * mu / 2.0e9)
    expected = 1 / (1 / (s_inf * mu) + d / 2.0e9)
    got = stiffness(compressible, f, x)
    assert np.abs(got.stiffness) == pytest.approx(np.abs(expected), rel=0.003)
    assert got.loss_factor == pytest.approx(expected.imag / expected.real, rel=0.01)
    assert np.all(got.loss_factor < stiffness(radial, f, x).loss_factor)
    torsion = PAPER_B.in_mode("torsion")
    assert stiffness(torsion.replace(bulk_modulus=2.0e9), f, x).stiffness == pytest.approx(
        stiffness(torsion, f, x).stiffness, rel=1e-14)


def test_without_a_bulk_modulus_nothing_changes():
    for mode in ("axial", "radial", "torsion", "conical"):
        design = PAPER_B.in_mode(mode)
        assert design.material.bulk_modulus is None
        assert "bulk_modulus" not in design.to_dict()["material"]
        assert "bulk_modulus" not in dumps_design(design)
        # K/µ = 5000 is the table's own: the same numbers to round-off
        same = design.replace(bulk_modulus=BULK_RATIO * design.material.shear_modulus)
        if mode == "conical" or mode == "radial":
            ratio = stiffness(same, [10.0], [1e-6]).magnitude / stiffness(design, [10.0], [1e-6]).magnitude
            # |µ*| at 1e-6 is a little above µ (friction's tangent, the fractional branch)
            assert 0.97 < ratio[0, 0] <= 1.0


def test_the_design_file_carries_the_bulk_modulus_and_refuses_what_is_off():
    data = json.loads(dumps_design(PAPER_B.in_mode("radial")))
    data["material"]["bulk_modulus"] = 2.0e9
    design = design_from_dict(data)
    assert design.material.bulk_modulus == 2.0e9
    assert loads_design(dumps_design(design)) == design
    for value, words in [(1.0e7, "between 50 and 1000000 times the shear modulus .*: with µ = 2.42 MPa, 0.121 GPa to 2420 GPa; got 0.01 GPa"), (None, "must be a number"),
                         (-2.0e9, "positive"), ("2e9", "number")]:
        data["material"]["bulk_modulus"] = value
        with pytest.raises(DesignError, match=words) as caught:
            design_from_dict(data)
        assert caught.value.key == "material.bulk_modulus"


THIN = PAPER_B.replace(inner_radius=0.02, outer_radius=0.025, length=0.06)  # b/a 1.25, L/(b − a) 12


def test_the_model_of_many_parameter_sets_honours_the_bulk_modulus():
    """A fit's batched model (core.points.PointsModel), the bulk modulus known or free, against
    stiffness_points design by design: the same numbers."""
    from core.bushing import stiffness_points
    from core.points import PointsModel
    from core.registry import parameter_values, with_values

    design = THIN.in_mode("radial").replace(bulk_modulus=1.5e9)
    f = np.repeat(np.linspace(1, 100, 10), 3)
    x = np.tile([2e-6, 2e-5, 6e-5], 10)
    for names in (MATERIAL, MATERIAL + ("bulk_modulus",)):
        base = np.array([parameter_values(design)[n] for n in names])
        rows = np.array([base, base * 1.01, base * np.where(np.arange(base.size) == base.size - 1, 1.2, 1.0)])
        k = PointsModel(design, names, f, x)(rows)
        for row, values in zip(k, rows, strict=True):
            assert np.array_equal(row, stiffness_points(with_values(design, dict(zip(names, values))), f, x))


def test_a_joint_fit_of_axial_and_radial_data_identifies_the_bulk_modulus():
    """Axial and radial data of one thin-walled compound (K = 1.5 GPa, 0.5 % noise): with K known
    as the nearly incompressible rubber the two directions cannot agree; freed, the joint fit
    finds K and an interval around it (radial is sensitive to it, axial is not)."""
    from tests.test_joint import multi_mode

    data = multi_mode(THIN.replace(bulk_modulus=1.5e9), modes=("axial", "radial"), per_amplitude=30)
    start = THIN.replace(shear_modulus=1.5e6, fractional_coefficient=1e6, fractional_order=0.4,
                         friction_stress_max=4e4, friction_strain_half=1e-3)
    known = fit_global(start, data)
    freed = fit_global(start.replace(bulk_modulus=5e9), data, free=MATERIAL + ("bulk_modulus",))
    assert all(g > 0.05 for g in known.gap_by_mode.values())
    assert all(g == pytest.approx(0.005 * math.sqrt(2), rel=0.3) for g in freed.gap_by_mode.values())
    low, high = freed.intervals["bulk_modulus"]
    assert low < 1.5e9 < high and high / low < 1.1
    assert "bulk_modulus" not in freed.undetermined
    # from axial data alone the bulk modulus is not determined
    axial = fit_global(start.replace(bulk_modulus=5e9), data.select(data.modes("axial") == "axial"),
                       free=MATERIAL + ("bulk_modulus",))
    assert "bulk_modulus" in axial.undetermined


def test_the_card_says_how_far_each_direction_is_from_an_incompressible_rubber():
    """core.card.against_incompressible against the card of the same bushing with the stiffest
    bulk modulus a design takes (1e12 Pa: K/µ 4×10⁵, within 0.03 % of the limit here)."""
    from core.card import against_incompressible, card

    design = THIN.replace(bulk_modulus=2.0e9)
    rows = card(design, 10.0, 1e-4, 1e-2)
    stiff = {r["mode"]: r for r in card(design.replace(bulk_modulus=1e12), 10.0, 1e-4, 1e-2)}
    moved = against_incompressible(design, 10.0, rows)
    for r in rows:
        far = stiff[r["mode"]]
        assert moved[r["mode"]][0] == pytest.approx(r["magnitude"] / far["magnitude"] - 1, abs=3e-4)
        assert moved[r["mode"]][1] == pytest.approx(r["loss_factor"] / far["loss_factor"] - 1, abs=3e-4)
    assert moved["torsion"] == (0.0, 0.0)
    assert moved["radial"][0] < -0.1 and moved["radial"][0] < moved["conical"][0] < moved["axial"][0] <= 0


def test_the_command_line_fits_the_bulk_modulus_when_asked(tmp_path, capsys):
    from cli.main import main
    from core import write_design
    from tests.test_joint import multi_mode

    data = multi_mode(THIN.replace(bulk_modulus=1.5e9), modes=("axial", "radial"), per_amplitude=20)
    (tmp_path / "ar.csv").write_text(data.to_csv(), encoding="utf-8")
    write_design(THIN.replace(shear_modulus=2e6), tmp_path / "thin.json")
    assert main(["fit", str(tmp_path / "ar.csv"), "--design", str(tmp_path / "thin.json"), "--free-bulk-modulus"]) in (0, None)
    report = json.loads(capsys.readouterr().out)
    low, high = report["fit"]["intervals"]["bulk_modulus"]
    assert low < 1.5e9 < high and "bulk_modulus" in report["fit"]["standard_errors"]
    assert main(["fit", str(tmp_path / "ar.csv"), "--design", str(tmp_path / "thin.json")]) in (0, None)
    known = json.loads(capsys.readouterr().out)
    assert "bulk_modulus" not in known["material"] and "bulk_modulus" not in known["fit"]["standard_errors"]
    # K given and held known: the standard errors still have the keys of `material` (FORMATS), K's 0
    write_design(THIN.replace(shear_modulus=2e6, bulk_modulus=1.5e9), tmp_path / "thin_k.json")
    assert main(["fit", str(tmp_path / "ar.csv"), "--design", str(tmp_path / "thin_k.json")]) in (0, None)
    held = json.loads(capsys.readouterr().out)
    assert list(held["fit"]["standard_errors"]) == list(held["material"])
    assert held["fit"]["standard_errors"]["bulk_modulus"] == 0.0 and held["material"]["bulk_modulus"] == 1.5e9
    assert all(held["fit"]["standard_errors"][k] > 0 for k in MATERIAL)


def test_the_loop_puts_the_bulk_spring_in_series_and_the_explorer_draws_it():
    """A radial design with a bulk modulus: the loop is no longer the incompressible rubber's
    (tests/test_compressibility_loop.py checks its numbers); the explorer draws that loop;
    torsion and the long axial bushing, pure shear, draw theirs unchanged."""
    from app.curves import hysteresis_loop
    from core.bushing import material_model
    from core.loops import loop

    radial = THIN.in_mode("radial").replace(bulk_modulus=2e9)
    squeezed, incompressible = loop(radial, 10.0, 1e-4, 200), loop(radial.replace(bulk_modulus=None), 10.0, 1e-4, 200)
    assert np.max(np.abs(squeezed.force - incompressible.force)) > 0.05 * np.max(np.abs(incompressible.force))
    assert material_model(radial).material.bulk_modulus is None  # the branch-by-branch views' model
    drawn = hysteresis_loop(radial, 10.0, 0.1)
    assert np.array_equal(drawn["force"][:-1], squeezed.force)
    long = radial.replace(shape="long")  # the closed form's series, matched at the drawn point
    drawn = hysteresis_loop(long, 10.0, 0.1)
    squeezed, incompressible = loop(long, 10.0, 1e-4, 200), loop(long.replace(bulk_modulus=None), 10.0, 1e-4, 200)
    assert np.array_equal(drawn["force"][:-1], squeezed.force)
    assert np.max(np.abs(squeezed.force - incompressible.force)) > 0.05 * np.max(np.abs(incompressible.force))
    for mode in ("torsion", "axial"):
        design = THIN.in_mode(mode).replace(bulk_modulus=2e9)
        assert np.array_equal(loop(design, 10.0, 1e-3).force, loop(design.replace(bulk_modulus=None), 10.0, 1e-3).force)


def test_the_views_say_what_includes_the_bulk_modulus():
    from app.shapes import shape_phrase

    radial = shape_phrase(PAPER_B.in_mode("radial").replace(bulk_modulus=2e9))
    assert "Bulk modulus K = 2 GPa" in radial and "the loss factor and the loop include it" in radial
    assert "the branches are the material's" in radial
    long = shape_phrase(PAPER_B.in_mode("radial").replace(shape="long", bulk_modulus=2e9))
    assert "the loss factor and the loop include it" in long and "matched to the plane-strain closed form" in long
    assert "Bulk" not in shape_phrase(PAPER_B.in_mode("torsion").replace(bulk_modulus=2e9))  # pure shear
    assert "Bulk" not in shape_phrase(PAPER_B.in_mode("radial"))


# off the table's nodes: the thinnest wall it covers, long, and a thick, short one
INDEPENDENT = [(1.22, 10.5), (1.85, 4.5)]


@pytest.mark.parametrize(("q", "lam"), INDEPENDENT)
@pytest.mark.parametrize("mode", ["radial", "conical"])
def test_an_independent_fe_gives_the_stiffness_and_its_loss_factor(q, lam, mode):
    """|K| and the loss factor of a compressible rubber (K = 2 GPa, µ 2.42 MPa: K/µ 826) against
    an FE route that shares nothing with the shipped table but the library
    (tests/independent_fe.py: triquadratic mixed hexahedra, uniform mesh on the true circles).
    Its two solves at K/µ 800 and 2000 give its own series law 1/S = 1/S∞ + d·µ/K, taken at the
    complex µ* = µ + m(iω)^α/2 (eqs 8, 9 and 16, friction off so that µ* does not depend on the
    amplitude) by the correspondence principle. Issue #29's bound: |K| within 1 % (measured
    −0.76 % to +0.1 % on six geometries, b/a 1.22–1.95, K/µ 800 and 2000); the loss factor's
    drop below the shear's within 3 % of itself."""
    from tests.independent_fe import extrapolated

    a = 0.02
    design = PAPER_B.replace(mode=mode, inner_radius=a, outer_radius=q * a, length=lam * (q - 1.0) * a,
                             friction_stress_max=1e-3, bulk_modulus=2.0e9)
    m = design.material
    f = np.array([1.0, 10.0, 100.0])
    mu = m.shear_modulus + m.fractional_coefficient * (2j * math.pi * f) ** m.fractional_order / 2
    s800, s2000 = (extrapolated(q, lam, mode, ratio) for ratio in (800.0, 2000.0))
    d = (1 / s800 - 1 / s2000) / (1 / 800 - 1 / 2000)
    inv_long = 1 / s2000 - d / 2000  # 1/S∞ (a = 1)
    scale = a if mode == "radial" else a**3  # S of a = 1 at the bushing's size: m, m³
    expected = mu * scale / (inv_long + d * mu / m.bulk_modulus)
    got = stiffness(design, f, [1e-5])
    assert got.magnitude[0] == pytest.approx(np.abs(expected), rel=0.01)  # (amplitude, frequency)
    shear = mu.imag / mu.real
    drop = 1 - (expected.imag / expected.real) / shear
    assert 1 - got.loss_factor[0] / shear == pytest.approx(drop, rel=0.03)
    assert np.all(drop > 0)
