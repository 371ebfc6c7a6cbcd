"""Bushing stiffness, slices and continuum, loops and histories, against independent routes."""

from itertools import pairwise

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from scipy import integrate

from core import (
    PAPER_B,
    TABLE_1,
    Design,
    Geometry,
    Material,
    force_history,
    loop,
    shape_factor,
    stiffness,
    strain_factor,
)
from core.bushing import cache_info
from core.material import equivalent_modulus
from core.slices import continuum_nodes, solve_series
from tests.test_material import reference_modulus

DESIGNS = [PAPER_B, TABLE_1]


def local_strain(design, r, x):
    """Eqs 10–11: the tensor shear strain at radius r for the drive x."""
    a, b = design.geometry.inner_radius, design.geometry.outer_radius
    if design.mode == "torsion":
        return a * a * b * b * x / ((b * b - a * a) * r * r)
    return x / (2 * r * np.log(b / a))


@pytest.mark.parametrize("design", DESIGNS)
def test_equivalent_strain_balances_distortion_energy(design):
    """Eqs 12–15: ε_eq² is the volume average of ε(r)² over the rubber."""
    a, b = design.geometry.inner_radius, design.geometry.outer_radius
    mean_sq = integrate.quad(lambda r: local_strain(design, r, 1.0) ** 2 * 2 * np.pi * r, a, b)[0]
    mean_sq /= np.pi * (b * b - a * a)
    assert_allclose(strain_factor(design.geometry, design.mode) ** 2, mean_sq, rtol=1e-12)


@pytest.mark.parametrize("design", DESIGNS)
def test_elastic_stiffness_from_strain_energy(design):
    """Eqs 17–18: K x²/2 is the strain energy ∫ 2µ ε(r)² dV of the linear-elastic bushing."""
    a, b, L = design.geometry.inner_radius, design.geometry.outer_radius, design.geometry.length
    energy = integrate.quad(lambda r: 2 * local_strain(design, r, 1.0) ** 2 * 2 * np.pi * r * L, a, b)[0]
    assert_allclose(shape_factor(design.geometry, design.mode), 2 * energy, rtol=1e-12)


def test_result_object_shape_units_and_table():
    r = stiffness(PAPER_B, [1, 10, 100], [1e-4, 1e-3])
    assert r.stiffness.shape == (2, 3) and r.units["stiffness"] == "N/m"
    assert stiffness(TABLE_1, 10, 1e-3).units == {
        "frequency_hz": "Hz",
        "amplitude": "rad",
        "stiffness": "N·m/rad",
        "force": "N·m",
        "drive": "angle",
    }
    t = r.table()
    assert list(t) == [
        "frequency_hz", "amplitude", "stiffness_real", "stiffness_imag", "magnitude", "loss_factor"
    ]
    assert_allclose(t["frequency_hz"], [1, 10, 100, 1, 10, 100])
    assert_allclose(t["magnitude"], np.abs(r.stiffness).ravel())
    assert_allclose(t["loss_factor"], (r.stiffness.imag / r.stiffness.real).ravel())
    with pytest.raises(ValueError):
        r.stiffness[0, 0] = 0  # cached results are read-only


def test_grid_is_the_outer_product_of_single_points():
    r = stiffness(TABLE_1, [10, 55, 100], [1e-5, 1e-3, 1e-1])
    for i, x in enumerate(r.amplitude):
        for j, f in enumerate(r.frequency_hz):
            assert_allclose(r.stiffness[i, j], stiffness(TABLE_1, f, x).stiffness[0, 0], rtol=1e-14)


def test_repeated_queries_come_from_the_cache():
    f, x = np.linspace(1, 100, 17), np.geomspace(1e-5, 1e-3, 13)
    first = stiffness(PAPER_B, f, x)
    hits = cache_info().hits
    again = stiffness(PAPER_B, f.copy(), list(x))
    assert again is first and cache_info().hits == hits + 1
    assert cache_info().maxsize is not None


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"frequency_hz": [10, -1]}, "frequency_hz"),
        ({"frequency_hz": []}, "frequency_hz"),
        ({"amplitude": [np.nan]}, "amplitude"),
        ({"amplitude": [0.0]}, "amplitude"),
        ({"slices": 0}, "slices"),
        ({"slices": 2.5}, "slices"),
        ({"route": "guess"}, "route"),
    ],
)
def test_bad_grid_refused(kwargs, match):
    args = {"frequency_hz": [10], "amplitude": [1e-4], **kwargs}
    with pytest.raises(ValueError, match=match):
        stiffness(PAPER_B, args.pop("frequency_hz"), args.pop("amplitude"), **args)


# --- reference data ----------------------------------------------------------------------


def test_paper_b_figure_7_loop_peaks_near_3000_newton():
    lp = loop(PAPER_B, 0.1, 1e-3)
    assert 2700 < lp.force.max() < 3300 and 2700 < -lp.force.min() < 3300


def test_paper_b_figure_8_at_0_1_mm():
    r = stiffness(PAPER_B, np.linspace(1, 100, 100), 1e-4)
    assert 3.8e6 < r.magnitude.min() and r.magnitude.max() < 4.8e6
    assert 0.12 < r.loss_factor.min() and r.loss_factor.max() < 0.16
    assert r.magnitude[0, 0] < 4.1e6 and r.magnitude[0, -1] > 4.5e6


def test_paper_b_figures_9_10_range():
    r = stiffness(PAPER_B, np.linspace(1, 100, 20), [0.013e-3, 0.04e-3, 0.17e-3, 0.25e-3, 0.35e-3])
    assert 3e6 < r.magnitude.min() and r.magnitude.max() < 6e6


def test_table_1_figures_5_6_trends():
    angles = np.geomspace(1.74e-6, 1.74e-1, 41)
    r = stiffness(TABLE_1, [10, 50, 100], angles)
    assert 0 < r.magnitude.min() and r.magnitude.max() < 50
    assert np.all(np.diff(r.magnitude, axis=0) < 0)  # falls with amplitude
    assert np.all(np.diff(r.magnitude, axis=1) > 0)  # rises with frequency
    assert np.all(np.diff(r.loss_factor, axis=1) > 0)
    for j in range(3):  # loss factor rises, then falls, with amplitude
        eta = r.loss_factor[:, j]
        peak = int(np.argmax(eta))
        assert 0 < peak < angles.size - 1
        assert np.all(np.diff(eta[: peak + 1]) > 0) and np.all(np.diff(eta[peak:]) < 0)


# --- physical trends (properties) ---------------------------------------------------------

designs = st.builds(
    lambda mode, a, ratio, L, mu, m_rel, alpha, smax_rel, ehalf: Design(
        mode,
        Geometry(a, a * ratio, L),
        Material(mu, mu * m_rel, alpha, mu * ehalf * smax_rel, ehalf),
    ),
    mode=st.sampled_from(["axial", "torsion"]),
    a=st.floats(2e-3, 5e-2),
    ratio=st.floats(1.2, 4.0),
    L=st.floats(5e-3, 0.2),
    mu=st.floats(3e5, 1e7),
    m_rel=st.floats(0.01, 0.3),
    alpha=st.floats(0.05, 0.6),
    smax_rel=st.floats(0.05, 2.0),  # σ_fmax/(2ε½) relative to 2µ: friction modulus share
    ehalf=st.floats(1e-4, 1e-2),
)


@settings(max_examples=60, deadline=None)
@given(designs)
def test_stiffness_falls_with_amplitude_and_rises_with_frequency(design):
    c = strain_factor(design.geometry, design.mode)
    x = np.geomspace(1e-4, 1e2, 25) * design.material.friction_strain_half / c
    r = stiffness(design, np.geomspace(0.5, 200, 9), x)
    assert np.all(np.diff(r.magnitude, axis=0) < 0)
    assert np.all(np.diff(r.magnitude, axis=1) > 0)
    assert np.all(r.stiffness.imag >= 0)


@settings(max_examples=25, deadline=None)
@given(designs, st.sampled_from([2, 3, "continuum"]))
def test_slices_keep_the_trends_and_stay_dissipative(design, slices):
    c = strain_factor(design.geometry, design.mode)
    x = np.geomspace(1e-3, 1e2, 9) * design.material.friction_strain_half / c
    r = stiffness(design, [1.0, 100.0], x, slices=slices)
    assert np.all(np.diff(r.magnitude, axis=0) < 0)
    assert np.all(r.stiffness.imag >= 0)


# --- slices and continuum ------------------------------------------------------------------


def thesis_factors(design):
    """(S, c) of eqs 17/18 and 14/15, written out here: the closed forms the code must give."""
    a, b, L = design.geometry.inner_radius, design.geometry.outer_radius, design.geometry.length
    if design.mode == "torsion":
        return 4 * np.pi * a * a * b * b * L / (b * b - a * a), a * b / (b * b - a * a)  # eqs 17, 14
    return 2 * np.pi * L / np.log(b / a), 1 / np.sqrt(2 * (b * b - a * a) * np.log(b / a))  # eqs 18, 15


@pytest.mark.parametrize("design", DESIGNS)
def test_one_slice_is_eq_17_18(design):
    """K = S µ_eq(ω, c x̂) with the thesis' S and c written out and µ_eq by quadrature of the
    Berg loop (tests/test_material.py), not by the code under test."""
    s, c = thesis_factors(design)
    f = np.array([1.0, 10.0, 100.0])
    x = np.geomspace(1e-6, 1e-1, 11) / c
    direct = s * reference_modulus(design.material, f[None, :], c * x[:, None])
    nodes = __import__("core.slices", fromlist=["slice_nodes"]).slice_nodes(design.geometry, design.mode, 1)
    ff, xx = np.meshgrid(f, x)
    solved = solve_series(
        nodes, xx.ravel(), lambda e: equivalent_modulus(design.material, ff.ravel()[:, None], e), c * xx.ravel()
    ).reshape(xx.shape)
    # the quadrature holds 1e-10 and the series its load continuity 1e-11: 1e-9 between them
    assert_allclose(solved, direct, rtol=1e-9)
    assert_allclose(stiffness(design, f, x).stiffness, direct, rtol=1e-9)


@pytest.mark.parametrize("design", DESIGNS)
def test_uniform_modulus_makes_every_slicing_exact(design):
    """With (nearly) no friction the modulus is uniform and eqs 17/18 are exact elasticity:
    slices and continuum must reproduce them."""
    soft = design.replace(friction_stress_max=1e-9)
    x = np.array([1e-4, 1e-2])
    k1 = stiffness(soft, [3.0, 30.0], x).stiffness
    for slices in (2, 3, 7, "continuum"):
        assert_allclose(stiffness(soft, [3.0, 30.0], x, slices=slices).stiffness, k1, rtol=1e-10)


@pytest.mark.parametrize("design", DESIGNS)
def test_slices_converge_monotonically_to_the_continuum(design):
    c = strain_factor(design.geometry, design.mode)
    x = np.geomspace(3e-2, 30, 7) * design.material.friction_strain_half / c
    f = [1.0, 10.0, 100.0]
    k_inf = stiffness(design, f, x, slices="continuum").stiffness
    errors = [np.abs(stiffness(design, f, x, slices=n).stiffness / k_inf - 1) for n in (1, 2, 3, 5, 10, 20, 40)]
    for coarse, fine in pairwise(errors):
        assert np.all(fine < coarse)
    # second order in 1/N: Richardson extrapolation of N = 20 and 40 lands on the continuum
    k20 = stiffness(design, f, x, slices=20).stiffness
    k40 = stiffness(design, f, x, slices=40).stiffness
    assert_allclose((4 * k40 - k20) / 3, k_inf, rtol=2e-7)


def test_paper_a_one_two_three_slices_differ_little():
    angles = np.geomspace(1.74e-6, 1.74e-1, 11)
    k = [stiffness(TABLE_1, [10, 100], angles, slices=n) for n in (1, 2, 3)]
    for other in k[1:]:
        assert np.max(np.abs(other.magnitude / k[0].magnitude - 1)) < 0.05
        assert np.max(np.abs(other.loss_factor - k[0].loss_factor)) < 0.02


@pytest.mark.parametrize("mode", ["axial", "torsion"])
def test_continuum_quadrature_is_converged_for_a_thick_bushing(mode):
    design = Design(mode, Geometry(0.005, 0.05, 0.03), TABLE_1.material)
    c = strain_factor(design.geometry, mode)
    x = np.geomspace(1e-4, 1e3, 30) * design.material.friction_strain_half / c
    ff, xx = np.meshgrid([1.0, 100.0], x)
    fine = solve_series(
        continuum_nodes(design.geometry, mode, 128),
        xx.ravel(),
        lambda e: equivalent_modulus(design.material, ff.ravel()[:, None], e),
        c * xx.ravel(),
    ).reshape(xx.shape)
    assert_allclose(stiffness(design, [1.0, 100.0], x, slices="continuum").stiffness, fine, rtol=1e-10)


def test_continuum_load_is_continuous_and_drive_adds_up():
    """Check the continuum solution itself: integrate the local strains it implies."""
    design, f, phi = TABLE_1, 20.0, 2e-2
    K = stiffness(design, f, phi, slices="continuum").stiffness[0, 0]
    T = abs(K) * phi
    a, b, L = design.geometry.inner_radius, design.geometry.outer_radius, design.geometry.length
    from scipy.optimize import brentq

    def local_modulus(r):  # solve 2|µ(ε)| ε = T/(2π r² L) at this radius
        tau = T / (2 * np.pi * r * r * L)
        eps = brentq(lambda e: 2 * abs(equivalent_modulus(design.material, f, e)) * e - tau, 1e-12, 1.0, xtol=1e-16, rtol=1e-14)
        return equivalent_modulus(design.material, f, eps)

    angle = integrate.quad(lambda r: (1 / (2 * np.pi * r**3 * L * local_modulus(r))).real, a, b, epsrel=1e-12)[0]
    angle += 1j * integrate.quad(lambda r: (1 / (2 * np.pi * r**3 * L * local_modulus(r))).imag, a, b, epsrel=1e-12)[0]
    assert_allclose(abs(T * angle), phi, rtol=1e-8)
    assert_allclose(1 / angle, K, rtol=1e-8)


# --- loops and histories -------------------------------------------------------------------


@pytest.mark.parametrize("design,f,x", [(PAPER_B, 0.1, 1e-3), (PAPER_B, 50, 1e-4), (TABLE_1, 20, 0.05)])
def test_analytic_loop_equals_simulated_steady_period(design, f, x):
    an = loop(design, f, x, 64)
    td = loop(design, f, x, 64, route="time-domain")
    scale = np.abs(an.force).max()
    assert_allclose(td.displacement, an.displacement, atol=1e-12 * x)
    for part in ("force_elastic", "force_viscoelastic", "force_friction"):
        assert_allclose(getattr(td, part), getattr(an, part), atol=1e-3 * scale)


@pytest.mark.parametrize("design,f,x", [(PAPER_B, 5.0, 2e-4), (TABLE_1, 20.0, 1e-2)])
def test_loop_first_harmonic_is_the_stiffness(design, f, x):
    lp = loop(design, f, x, 512)
    c = 2 * np.mean(lp.force * np.sin(lp.phase)) + 2j * np.mean(lp.force * np.cos(lp.phase))
    assert_allclose(c / x, stiffness(design, f, x).stiffness[0, 0], rtol=1e-9)


def test_loop_area_is_the_energy_dissipated_per_cycle():
    f, x = 10.0, 3e-4
    lp = loop(PAPER_B, f, x, 4096)
    area = -np.trapezoid(np.append(lp.displacement, lp.displacement[0]), np.append(lp.force, lp.force[0]))
    k = stiffness(PAPER_B, f, x).stiffness[0, 0]
    assert_allclose(area, np.pi * x * x * k.imag, rtol=1e-5)


def test_force_history_of_a_sine_settles_on_the_loop():
    f, x, n_p, periods = 5.0, 2e-4, 1024, 64
    t = np.arange(1, n_p * periods + 1) / (f * n_p)
    hist = force_history(PAPER_B, x * np.sin(2 * np.pi * f * t), 1 / (f * n_p))
    last = hist.force[-n_p - 1 : -1]  # phases 0 … 2π(n_p−1)/n_p
    lp = loop(PAPER_B, f, x, n_p)
    assert_allclose(last, lp.force, atol=2e-3 * np.abs(lp.force).max())
    assert_allclose(hist.time_s[1] - hist.time_s[0], 1 / (f * n_p))


def test_force_history_is_linear_for_a_purely_elastic_path_scaling():
    """With negligible friction the history is linear in the drive (elastic + fractional)."""
    soft = PAPER_B.replace(friction_stress_max=1e-12)
    rng = np.random.default_rng(3)
    x = np.cumsum(rng.normal(size=5000)) * 1e-6
    h1, h2 = force_history(soft, x, 1e-3), force_history(soft, 3 * x, 1e-3)
    assert_allclose(h2.force, 3 * h1.force, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("bad", [[], [[1.0, 2.0]], [1.0, np.nan]])
def test_force_history_refuses_bad_input(bad):
    with pytest.raises(ValueError, match="displacement"):
        force_history(PAPER_B, bad, 1e-3)
    with pytest.raises(ValueError, match="dt"):
        force_history(PAPER_B, [0.0, 1e-4], -1.0)


def test_loop_refuses_bad_points():
    with pytest.raises(ValueError, match="points"):
        loop(PAPER_B, 1.0, 1e-3, 2)


EXTENDED = {"viscous": {"viscosity": 200.0}, "strain_stiffening": {"stiffening": 30.0},
            "rate_amplitude_coupling": {"rate_exponent": 0.2}}


def _first_harmonic_modulus(stress, theta, eps_amp):
    """µ with σ = Im(2µ ε̂ e^{iθ}) for ε = ε̂ sin θ, by quadrature over whole periods."""
    n = theta.size
    return (np.sum(stress * np.sin(theta)) + 1j * np.sum(stress * np.cos(theta))) / (n * eps_amp)


@pytest.mark.parametrize("effects", [{}, EXTENDED])
def test_each_branch_is_the_time_domain_simulation_of_that_branch(effects):
    """branch_stiffness against the thesis' time-domain route, branch by branch: the elastic and
    friction branches are the first harmonics of their simulated stresses (steady after the
    first quarter period), the viscoelastic branch what the converged time-domain modulus leaves."""
    from core import shape_factor, strain_factor
    from core.bushing import branch_stiffness
    from core.material import branch_stresses, equivalent_modulus_time_domain

    design = TABLE_1.replace(effects=effects)
    f, x = 30.0, 0.02
    eps_amp = strain_factor(design.geometry, design.mode) * x
    s = shape_factor(design.geometry, design.mode)
    parts = {k: complex(v[0, 0]) / s for k, v in branch_stiffness(design, f, x).items()}
    n = 4096
    t = np.arange(3 * n) / (n * f)
    theta = 2 * np.pi * f * t
    simulated = branch_stresses(design.material, eps_amp * np.sin(theta), t[1], effects, frequency_hz=f)
    last = slice(-n, None)
    elastic = _first_harmonic_modulus(simulated.elastic[last], theta[last], eps_amp)
    friction = _first_harmonic_modulus(simulated.friction[last], theta[last], eps_amp)
    assert parts["elastic"] == pytest.approx(elastic, rel=1e-9)
    assert parts["friction"] == pytest.approx(friction, rel=1e-4)  # the sampled reversals: O(1/n²)
    total = complex(equivalent_modulus_time_domain(design.material, f, eps_amp, effects=effects).modulus)
    assert parts["viscoelastic"] == pytest.approx(total - elastic - friction, rel=1e-4)


def test_branches_refuse_stiffness_level_effects():
    from core.bushing import branch_stiffness

    assert np.all(branch_stiffness(TABLE_1.replace(effects=EXTENDED), [1.0, 30.0], [1e-5, 0.1])["elastic"].imag == 0)
    with pytest.raises(ValueError, match="inertia"):
        branch_stiffness(PAPER_B.replace(effects={"inertia": {"mass": 1.0}}), 1.0, 1e-4)
