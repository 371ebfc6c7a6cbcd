"""The material model: both routes, the limits and identities of docs/model.md, the branches."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from scipy import integrate, special

from core import PAPER_B, TABLE_1, ConvergenceError, strain_factor
from core.loops import steady_friction_loop
from core.material import (
    equivalent_modulus,
    equivalent_modulus_time_domain,
    fractional_stress,
    friction_modulus,
    friction_modulus_universal,
    friction_reversal_ratio,
    friction_stress,
    grunwald_weights,
)

PAPER_B_AMPLITUDES_M = [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.25e-3, 0.35e-3, 1e-3]
PAPER_B_FREQUENCIES = [1.0, 3.0, 10.0, 30.0, 100.0]


# --- the two routes ----------------------------------------------------------------------


@pytest.mark.parametrize("amplitude", PAPER_B_AMPLITUDES_M)
def test_routes_agree_on_paper_b(amplitude):
    """docs/model.md: analytic and time-domain routes agree to better than 1e-3 (we hold 1e-4)."""
    eps = strain_factor(PAPER_B.geometry, "axial") * amplitude
    for f in PAPER_B_FREQUENCIES:
        td = equivalent_modulus_time_domain(PAPER_B.material, f, eps)
        an = equivalent_modulus(PAPER_B.material, f, eps)
        assert abs(td.modulus / an - 1) < 1e-4, (f, amplitude, td)


@pytest.mark.parametrize("angle", [1.74e-6, 1.74e-4, 1.74e-2, 1.74e-1])
def test_routes_agree_on_table_1(angle):
    eps = strain_factor(TABLE_1.geometry, "torsion") * angle
    for f in (10.0, 100.0):
        td = equivalent_modulus_time_domain(TABLE_1.material, f, eps)
        an = equivalent_modulus(TABLE_1.material, f, eps)
        assert abs(td.modulus / an - 1) < 1e-4


def test_time_domain_refuses_to_return_unconverged():
    eps = strain_factor(PAPER_B.geometry, "axial") * 1e-5
    with pytest.raises(ConvergenceError, match="steady state not reached"):
        equivalent_modulus_time_domain(PAPER_B.material, 10.0, eps, max_periods=8)


# --- friction modulus: closed form, limits, identities ----------------------------------


def _berg_loop_harmonic(z):
    """First harmonic of the steady Berg loop by adaptive quadrature, σ_fmax = ε½ = 1."""
    x = friction_reversal_ratio(z)

    def rising(e):  # Berg's eq 6 from the reversal (−z, −x), s = +1
        return -x + (e + z) * (1 + x) / ((1 + x) + (e + z))

    # the integrands scale with z: the absolute tolerance too (1e-13 of the real part's size;
    # the imaginary part, O(z²) at small z, cancels and cannot be held to a relative one)
    opts = {"epsabs": 1e-13 * z, "epsrel": 1e-10, "limit": 200}
    re = integrate.quad(lambda t: rising(z * np.sin(t)) * np.sin(t), -np.pi / 2, np.pi / 2, **opts)[0]
    im = integrate.quad(lambda t: rising(z * np.sin(t)) * np.cos(t), -np.pi / 2, np.pi / 2, **opts)[0]
    return (re + 1j * im) / (np.pi * z)


def reference_modulus(material, frequency_hz, strain_amplitude):
    """µ_eq(ω, ε̂) of eq 16 by a route independent of core.material's closed forms, broadcast:
    µ (eq 1) + m (iω)^α / 2 (eq 5, written out here) + µ_f from the quadrature of Berg's steady
    loop (eq 6, :func:`_berg_loop_harmonic`); agrees with the closed form to about 1e-10. For
    the tests of everything built on µ_eq (bushings, loops, fits)."""
    f, eps = np.broadcast_arrays(np.asarray(frequency_hz, float), np.asarray(strain_amplitude, float))
    smax, ehalf = material.friction_stress_max, material.friction_strain_half
    friction = np.vectorize(lambda e: smax / ehalf * _berg_loop_harmonic(e / ehalf), otypes=[complex])
    omega = 2 * np.pi * f
    return (material.shear_modulus + material.fractional_coefficient * (1j * omega) ** material.fractional_order / 2
            + friction(eps))


@pytest.mark.parametrize("z", [1e-3, 0.03, 0.3, 1.0, 3.0, 30.0, 300.0])
def test_closed_form_equals_quadrature_of_the_loop(z):
    assert_allclose(friction_modulus_universal(z), _berg_loop_harmonic(z), rtol=1e-9)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.one_of(st.just(0.0), st.floats(1e-7, 1e4)), min_size=1, max_size=40))
def test_an_array_of_amplitudes_gives_each_its_own_value(z):
    """g(z) over an array, whatever mix of small (the series' side of R(q)), large and zero
    amplitudes it holds, is each amplitude's value alone (each alone takes one form whole):
    the array's masks and its shortcuts when all amplitudes lie on one side change no number."""
    alone = np.array([friction_modulus_universal(np.array([v]))[0] for v in z])
    assert_allclose(friction_modulus_universal(np.array(z)), alone, rtol=1e-14, atol=0)
    assert friction_modulus_universal(np.array([0.0]))[0] == 0.5  # the z → 0 limit, not 0/0


def test_turning_point_is_the_fixed_point_of_berg_friction():
    """Simulated Berg friction driven ±ε̂ settles on the turning stress x σ_fmax."""
    for z in (0.5, 2.0, 20.0):
        n_p, periods = 400, 40
        theta = 2 * np.pi * np.arange(1, n_p * periods + 1) / n_p
        sig = friction_stress(z * np.sin(theta), 1.0, 1.0)
        peak = sig[n_p * (periods - 1) + n_p // 4 - 1]  # θ = π/2 of the last period
        assert_allclose(peak, friction_reversal_ratio(z), rtol=1e-6)


def test_small_amplitude_limit():
    """µ_f → σ_fmax / (2 ε½) as ε̂ → 0: the initial slope of the virgin curve."""
    mu = friction_modulus(1e-12, 2.0e4, 4e-3)
    assert_allclose(mu.real, 2.0e4 / (2 * 4e-3), rtol=1e-8)
    assert abs(mu.imag) < 1e-6 * mu.real


def test_large_amplitude_is_the_coulomb_square_loop():
    """A square loop of height ±σ_fmax dissipates 4 σ_fmax ε̂ per cycle: Im µ_f → 2σ_fmax/(π ε̂)."""
    z = 1e8
    g = friction_modulus_universal(z)
    assert_allclose(g.imag * np.pi * z / 2, 1.0, rtol=1e-3)
    assert g.real < 1e-3 * g.imag


@settings(max_examples=60, deadline=None)
@given(st.floats(1e-6, 1e5))
def test_loop_area_is_dissipated_energy(z):
    """Area of the steady loop ∮σ dε = 2π ε̂² Im µ_f (docs/model.md), by trapezoids on the loop."""
    theta = np.linspace(0, 2 * np.pi, 200001)
    sig = steady_friction_loop(z, theta, 1.0, 1.0)
    area = -np.trapezoid(z * np.sin(theta), sig)  # ∮ σ dε = −∮ ε dσ
    expected = 2 * np.pi * z**2 * friction_modulus(z, 1.0, 1.0).imag
    assert_allclose(area, expected, rtol=2e-5, atol=1e-14)


@settings(max_examples=60, deadline=None)
@given(st.floats(1e-9, 1e6))
def test_dissipation_is_never_negative(z):
    g = friction_modulus_universal(z)
    assert g.imag >= 0 and g.real > 0


@settings(max_examples=40, deadline=None)
@given(
    smax=st.floats(1e2, 1e6),
    ehalf=st.floats(1e-5, 1e-1),
    z=st.floats(1e-3, 1e3),
)
def test_friction_scaling_by_simulation(smax, ehalf, z):
    """The loop in units of σ_fmax and ε½ is universal: simulate it at both scales."""
    theta = 2 * np.pi * np.arange(1, 4 * 64 + 1) / 64
    scaled = friction_stress(z * ehalf * np.sin(theta), smax, ehalf)
    unit = friction_stress(z * np.sin(theta), 1.0, 1.0)
    assert_allclose(scaled, smax * unit, rtol=1e-9, atol=1e-12 * smax)


def test_virgin_curve_builds_half_the_stress_at_eps_half():
    eps = np.linspace(0, 3e-3, 301)
    sig = friction_stress(eps, 1.92e4, 1e-3)
    assert_allclose(sig[100], 1.92e4 / 2, rtol=1e-12)  # ε = ε½
    assert np.all(np.abs(sig) < 1.92e4)


def test_friction_is_rate_independent():
    """Travelling the same path slower (samples repeated, i.e. pauses) changes nothing."""
    rng = np.random.default_rng(1)
    path = np.cumsum(rng.normal(size=400)) * 1e-4
    slow = np.repeat(path, 3)
    assert_allclose(friction_stress(slow, 1e4, 1e-3)[2::3], friction_stress(path, 1e4, 1e-3))


def test_reversal_then_return_retraces_nothing_outside_the_bounds():
    """After any path the stress stays within ±σ_fmax and moving on in one direction
    approaches ±σ_fmax."""
    rng = np.random.default_rng(2)
    path = np.concatenate([np.cumsum(rng.normal(size=1000)) * 1e-3, np.linspace(0, 1, 100) + 1])
    sig = friction_stress(path, 5e3, 2e-3)
    assert np.all(np.abs(sig) < 5e3)
    assert sig[-1] > 0.99 * 5e3


# --- fractional branch -------------------------------------------------------------------


def test_grunwald_weights_equal_binomials_and_never_overflow():
    alpha = 0.37
    w = grunwald_weights(200, alpha)
    j = np.arange(200)
    assert_allclose(w, (-1.0) ** j * special.binom(alpha, j), rtol=1e-12, atol=1e-300)
    big = grunwald_weights(1_000_000, alpha)
    assert np.all(np.isfinite(big)) and abs(big[-1]) < abs(big[-2])
    assert_allclose(grunwald_weights(5, 1.0), [1, -1, 0, 0, 0])


@pytest.mark.parametrize("alpha", [0.2, 0.5, 0.9])
def test_grunwald_letnikov_derivative_of_a_power(alpha):
    """D^α t = t^(1−α) / Γ(2 − α) (Riemann–Liouville from 0); GL is first-order in Δt."""
    dt = 1e-4
    t = dt * np.arange(1, 10001)
    gl = fractional_stress(t, dt, 1.0, alpha)
    exact = t ** (1 - alpha) / special.gamma(2 - alpha)
    assert_allclose(gl[-1], exact[-1], rtol=5e-4)


def test_fractional_steady_state_is_m_i_omega_alpha():
    """Eq 5: the fractional branch's steady harmonic response is m (iω)^α."""
    m, alpha, f = 6e5, 0.2, 7.0
    n_p, periods = 2048, 64
    dt = 1 / (f * n_p)
    theta = 2 * np.pi * np.arange(1, n_p * periods + 1) / n_p
    sig = fractional_stress(np.sin(theta), dt, m, alpha)[-n_p:]
    th = theta[-n_p:] - 2 * np.pi * f * alpha * dt / 2  # GL is 2nd order at t − αΔt/2
    c = 2 * np.mean(sig * np.sin(th)) + 2j * np.mean(sig * np.cos(th))
    assert_allclose(c, m * (2j * np.pi * f) ** alpha, rtol=1e-4)
