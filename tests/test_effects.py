"""Model extensions (docs/model.md's table of effects) against independent routes."""

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_bvp

from core import PAPER_B, TABLE_1, force_history, loop, stiffness
from core.effects import EFFECTS, wave_stiffness
from core.material import equivalent_modulus, equivalent_modulus_time_domain
from tests.test_bushing import thesis_factors


def test_library_covers_model_md_table():
    assert set(EFFECTS) == {
        "friction", "fractional", "inertia", "viscous", "strain_stiffening",
        "rate_amplitude_coupling", "nonuniform_strain", "wave_effects",
    }
    for e in EFFECTS.values():
        assert e.title and len(e.physics) > 40 and len(e.signature) > 40


@pytest.mark.parametrize(
    "effects",
    [
        {"viscous": {"viscosity": 800.0}},
        {"strain_stiffening": {"stiffening": 40.0}},
        {"rate_amplitude_coupling": {"rate_exponent": 0.3}},
        {"viscous": {"viscosity": 300.0}, "strain_stiffening": {"stiffening": 10.0}},
    ],
)
def test_material_effects_simulated_in_time_domain_match_analytic(effects):
    """The stiffness with the effects' closed forms against eq 17 (S and c written out) times
    the simulated modulus."""
    design = TABLE_1.replace(effects=effects)
    s, c = thesis_factors(design)
    for f, phi in [(3.0, 0.02), (80.0, 0.15), (30.0, 1e-4)]:
        td = equivalent_modulus_time_domain(design.material, f, c * phi, effects=effects).modulus
        k = stiffness(design, f, phi).stiffness[0, 0]
        assert_allclose(s * td, k, rtol=1e-4)  # the simulation's rtol 2e-6, with room


def test_material_effects_change_what_they_should():
    base = stiffness(PAPER_B, [1.0, 100.0], [1e-4, 1e-3]).stiffness
    visc = stiffness(PAPER_B.replace(effects={"viscous": {"viscosity": 1e3}}), [1.0, 100.0], [1e-4, 1e-3]).stiffness
    assert_allclose(visc.real, base.real)
    assert_allclose((visc - base).imag[:, 1] / (visc - base).imag[:, 0], 100.0)  # ∝ ω
    rate = stiffness(PAPER_B.replace(effects={"rate_amplitude_coupling": {"rate_exponent": 0.0}}), [1.0, 100.0], [1e-4, 1e-3]).stiffness
    assert_allclose(rate, base, rtol=1e-14)  # γ = 0 is the separable model


def test_inertia_is_minus_omega_squared_mass():
    f = np.array([1.0, 50.0, 200.0])
    base = stiffness(PAPER_B, f, 1e-4).stiffness
    heavy = stiffness(PAPER_B.replace(effects={"inertia": {"mass": 3.0}}), f, 1e-4).stiffness
    assert_allclose((heavy - base)[0], -((2 * np.pi * f) ** 2) * 3.0 + 0j, rtol=1e-9)


def test_inertia_in_a_history_is_mass_times_acceleration():
    f, n_p = 20.0, 4000
    dt = 1 / (f * n_p)
    t = dt * np.arange(n_p * 3)
    x = 1e-4 * np.sin(2 * np.pi * f * t) ** 3
    plain = force_history(PAPER_B, x, dt)
    heavy = force_history(PAPER_B.replace(effects={"inertia": {"mass": 2.0}}), x, dt)
    acc = 1e-4 * (2 * np.pi * f) ** 2 * (6 * np.sin(2 * np.pi * f * t) * np.cos(2 * np.pi * f * t) ** 2 - 3 * np.sin(2 * np.pi * f * t) ** 3)
    assert_allclose((heavy.force - plain.force)[2:], 2.0 * acc[1:-1], atol=1e-3 * np.abs(2.0 * acc).max())


def test_nonuniform_strain_is_the_continuum():
    design = TABLE_1.replace(effects={"nonuniform_strain": {}})
    r = stiffness(design, [10.0, 100.0], [1e-4, 1e-2])
    assert r.slices == "continuum"
    assert_allclose(r.stiffness, stiffness(TABLE_1, [10.0, 100.0], [1e-4, 1e-2], slices="continuum").stiffness)


@pytest.mark.parametrize("design", [PAPER_B, TABLE_1])
def test_wave_stiffness_tends_to_eqs_17_18(design):
    mu = equivalent_modulus(design.material, 10.0, 1e-4)
    g = design.geometry
    k = wave_stiffness(design.mode, g.inner_radius, g.outer_radius, g.length, mu, 10.0, 1e-6)
    assert_allclose(k, thesis_factors(design)[0] * mu, rtol=1e-9)  # k² ∝ ρ = 1e-6: no waves


def _bvp_stiffness(mode, a, b, L, mu, f, rho):
    """Shear waves by collocation (scipy solve_bvp), real and imaginary parts as four states."""
    k2 = rho * (2 * np.pi * f) ** 2 / mu
    n = 0 if mode == "axial" else 1

    def rhs(r, y):
        u = y[0] + 1j * y[1]
        du = y[2] + 1j * y[3]
        d2u = -du / r + (n * n / r**2 - k2) * u
        return np.vstack([y[2], y[3], d2u.real, d2u.imag])

    end = 1.0 if mode == "axial" else b  # w(b) = d = 1, or v(b) = b φ with φ = 1
    bc = lambda ya, yb: np.array([ya[0], ya[1], yb[0] - end, yb[1]])
    r = np.linspace(a, b, 400)
    sol = solve_bvp(rhs, bc, r, np.vstack([(r - a) / (b - a) * end, 0 * r, 0 * r + end / (b - a), 0 * r]), tol=1e-10, max_nodes=100000)
    assert sol.success
    du_a = sol.sol(a)[2] + 1j * sol.sol(a)[3]
    return 2 * np.pi * a ** (n + 1) * L * mu * du_a


@pytest.mark.parametrize("design,f", [(PAPER_B, 400.0), (PAPER_B, 1500.0), (TABLE_1, 3000.0)])
def test_wave_stiffness_equals_numerical_boundary_value_solution(design, f):
    g = design.geometry
    mu = equivalent_modulus(design.material, f, 1e-4)
    exact = wave_stiffness(design.mode, g.inner_radius, g.outer_radius, g.length, mu, f, 1100.0)
    numeric = _bvp_stiffness(design.mode, g.inner_radius, g.outer_radius, g.length, mu, f, 1100.0)
    assert_allclose(exact, numeric, rtol=1e-6)
    assert abs(exact / (thesis_factors(design)[0] * mu) - 1) > 1e-3  # waves do matter here


def test_wave_effects_through_stiffness():
    design = PAPER_B.replace(effects={"wave_effects": {"density": 1100.0}})
    f = np.array([1.0, 100.0, 800.0])
    r = stiffness(design, f, 1e-4)
    plain = stiffness(PAPER_B, f, 1e-4)
    assert abs(r.stiffness[0, 0] / plain.stiffness[0, 0] - 1) < 1e-5
    assert r.magnitude[0, 2] > plain.magnitude[0, 2]  # towards the first resonance


def test_combinations_without_meaning_are_refused_with_a_message():
    waves = PAPER_B.replace(effects={"wave_effects": {"density": 1100.0}})
    with pytest.raises(ValueError, match="wave_effects"):
        stiffness(waves, 10.0, 1e-4, slices=3)
    with pytest.raises(ValueError, match="effects.inertia"):
        loop(PAPER_B.replace(effects={"inertia": {"mass": 1.0}}), 10.0, 1e-4)
    with pytest.raises(ValueError, match="rate_amplitude_coupling"):
        force_history(PAPER_B.replace(effects={"rate_amplitude_coupling": {"rate_exponent": 0.2}}), [0, 1e-4], 1e-3)


def test_loop_with_material_effects_matches_its_stiffness():
    design = PAPER_B.replace(effects={"viscous": {"viscosity": 500.0}, "strain_stiffening": {"stiffening": 20.0}, "rate_amplitude_coupling": {"rate_exponent": 0.2}})
    f, x = 30.0, 2e-3
    lp = loop(design, f, x, 1024)
    c = 2 * np.mean(lp.force * np.sin(lp.phase)) + 2j * np.mean(lp.force * np.cos(lp.phase))
    assert_allclose(c / x, stiffness(design, f, x).stiffness[0, 0], rtol=1e-9)


@pytest.mark.parametrize("mode", ["axial", "torsion"])
def test_standing_waves_without_density_are_the_static_closed_form(mode):
    """ρ = 0 (no rubber inertia) is eq 18 / eq 17 times µ_eq exactly (the Bessel solution's
    second-kind functions diverge at k = 0; a file may give ρ = 0), and the limit joins the wave
    solution continuously: at kb just above its switch (1e-6) the two differ by O((kb)²)."""
    from core.effects import wave_stiffness
    from core.shape import long_shape_factor

    a, b, length = 0.02, 0.035, 0.09
    mu = np.array([2.4e6 + 3.1e5j, 5.0e6 + 1.0e6j])
    f = np.array([10.0, 1000.0])
    got = wave_stiffness(mode, a, b, length, mu, f, 0.0)
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got, long_shape_factor(a, b, length, mode) * mu, rtol=1e-15)
    # densities putting |kb| on either side of the switch, at 10 Hz and µ* = mu[0]
    k_per_sqrt_rho = 2 * np.pi * 10.0 / np.sqrt(mu[0])
    for kb in (0.9e-6, 1.1e-6, 1e-3):
        rho = float((kb / (b * abs(k_per_sqrt_rho))) ** 2)
        k = wave_stiffness(mode, a, b, length, mu[0], 10.0, rho)
        static = long_shape_factor(a, b, length, mode) * mu[0]
        assert abs(k / static - 1) < max(kb**2, 1e-9)


def _wave_stiffness_digits(mode, a, b, length, mu, f, rho):
    """The standing waves' stiffness from their defining formulas (u = A J_n(kr) + B Y_n(kr),
    A and B from the two boundary conditions, K from the traction at r = a) in mpmath at
    40 digits more than J and Y's growth e^|Im kb| costs: a route that shares neither the
    Wronskian nor the Hankel functions of :func:`core.effects.wave_stiffness`."""
    mp = pytest.importorskip("mpmath")
    with mp.workdps(40 + int(abs((2 * np.pi * f * np.sqrt(rho / complex(mu)) * b).imag))):
        n = 0 if mode == "axial" else 1
        m = mp.mpc(complex(mu).real, complex(mu).imag)
        a, b, length = mp.mpf(a), mp.mpf(b), mp.mpf(length)
        k = 2 * mp.pi * mp.mpf(f) * mp.sqrt(mp.mpf(rho) / m)
        j, y = mp.besselj, mp.bessely
        det = j(n, k * a) * y(n, k * b) - j(n, k * b) * y(n, k * a)
        end = 1 if n == 0 else b  # w(b) = 1, or v(b) = b φ with φ = 1
        big_a, big_b = -end * y(n, k * a) / det, end * j(n, k * a) / det
        if n == 0:
            return complex(2 * mp.pi * a * length * m * -k * (big_a * j(1, k * a) + big_b * y(1, k * a)))
        dv = big_a * (k * j(0, k * a) - j(1, k * a) / a) + big_b * (k * y(0, k * a) - y(1, k * a) / a)
        return complex(2 * mp.pi * a * a * length * m * dv)


@pytest.mark.parametrize("mode", ["axial", "torsion"])
@pytest.mark.parametrize("f", [1e-3, 10.0, 3e3, 2.2e4, 1e5, 3e5])
def test_standing_waves_hold_their_digits_where_the_waves_decay(mode, f):
    """Up to 300 kHz (|Im ka| from 0 to 35, on either side of the switch to the Hankel functions
    at |Im ka| = 2), on the design's geometry and a thicker one: the stiffness to 1e-10 of the
    high-precision route's, finite. Inverting the two boundary conditions in double precision
    (the formulas themselves) lost 3.7e-7 of the stiffness at 100 kHz, and its sign axially and
    everything in torsion (NaN) at 1 MHz (the next test)."""
    design = PAPER_B if mode == "axial" else TABLE_1
    g = design.geometry
    for a, b in ((g.inner_radius, g.outer_radius), (0.01, 0.03)):
        mu = complex(equivalent_modulus(design.material, f, 1e-4))
        got = complex(wave_stiffness(mode, a, b, g.length, mu, f, 1100.0))
        assert np.isfinite(got)
        assert got == pytest.approx(_wave_stiffness_digits(mode, a, b, g.length, mu, f, 1100.0), rel=1e-10)


def test_standing_waves_at_a_megahertz_through_stiffness():
    """The public route (``stiffness``) with wave effects at 1 MHz: finite numbers, the
    transmitted stiffness far below the quasi-static one (the waves die out across the rubber)."""
    for design in (PAPER_B, TABLE_1):
        waves = design.replace(effects={"wave_effects": {"density": 1100.0}})
        r = stiffness(waves, [10.0, 1e6], 1e-4)
        assert np.all(np.isfinite(r.stiffness)) and np.all(np.isfinite(r.loss_factor))
        assert r.magnitude[0, 1] < 1e-6 * r.magnitude[0, 0]


def test_waves_that_die_out_across_the_rubber_are_refused_with_their_frequency():
    """A soft, wide bushing (µ 1.9 kPa, b 0.54 m) at 49 kHz: the stiffness the waves pass to the
    inner sleeve is below the least double, so it came out 0 and its loss factor 0/0 (NaN); the
    design file allows it, so the model says why it gives no number, naming the frequency."""
    design = PAPER_B.replace(inner_radius=0.0422, outer_radius=0.544, length=0.0984, shear_modulus=1927.5,
                             fractional_coefficient=2009.8, fractional_order=0.44, friction_stress_max=9029.5,
                             friction_strain_half=0.000426, effects={"wave_effects": {"density": 462.47}})
    assert np.all(np.isfinite(stiffness(design, [10.0, 1e3], 4.62e-3).loss_factor))
    with pytest.raises(ValueError, match="at 49000 Hz the shear waves die out across the rubber"):
        stiffness(design, [10.0, 4.9e4], 4.62e-3)
