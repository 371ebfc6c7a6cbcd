"""Every mode, every route: the thesis' time-domain route against the analytic one across the
Fletcher–Gent knee, hysteresis loops against the stiffness and the energy they must carry, and
force histories against the steady loop and against closed forms of a path with reversals.

Independent numbers: the thesis' S and c written out (axial, torsion: tests/test_bushing.py),
a direct FE solve of the bushing (radial, conical: tests/test_shape.py, within the table's
0.5 %), Berg's eq 6 from its reversal points and the fractional derivative of a ramp in closed
form (eq 2: D^α (t − t₀)₊ = (t − t₀)₊^(1−α) / Γ(2 − α))."""

import itertools
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core import PAPER_B, force_history, loop, stiffness, strain_factor
from tests.test_bushing import thesis_factors
from tests.test_shape import TABLE_ACCURACY, energy_strain_factor, fe_paper_b

MODES = ("axial", "torsion", "radial", "conical")
KNEE = (0.03, 0.3, 1.0, 3.0, 30.0)  # ε̂/ε½: below, in and beyond the Fletcher–Gent knee
EXTENDED = {"viscous": {"viscosity": 500.0}, "strain_stiffening": {"stiffening": 20.0},
            "rate_amplitude_coupling": {"rate_exponent": 0.2}}


def amplitude_at(design, z: float) -> float:
    """The drive (m or rad) whose equivalent strain is z ε½."""
    return z * design.material.friction_strain_half / strain_factor(design.geometry, design.mode, design.shape)


def independent_factors(design):
    """(S, c, relative accuracy of S) by a route apart from the code's: the thesis' closed forms
    for the long axial and torsion bushing, a direct FE solve for radial and conical."""
    if design.mode in ("axial", "torsion"):
        s, c = thesis_factors(design)
        return s, c, 1e-12  # round-off
    s = fe_paper_b(design.mode)
    return s, energy_strain_factor(s, design.geometry), TABLE_ACCURACY


def first_harmonic(force, phase):
    """K x̂ with F ≈ Im(K x̂ e^{iθ}) over whole periods sampled evenly (a Fourier coefficient)."""
    return 2 * np.mean(force * np.sin(phase)) + 2j * np.mean(force * np.cos(phase))


# ---- the time-domain route ----------------------------------------------------------------


@pytest.mark.parametrize("effects", [{}, EXTENDED], ids=["model", "extended"])
@pytest.mark.parametrize("mode", MODES)
def test_the_time_domain_route_agrees_with_the_analytic_in_every_mode(mode, effects):
    """docs/model.md: the thesis' simulation and the closed-form steady state agree to 1e-3 (about
    1e-6 observed, 2e-5 at the smallest amplitude), in every direction, below, in and beyond the
    knee, from 1 to 100 Hz, with the material-level effects simulated too."""
    design = PAPER_B.in_mode(mode).replace(effects=effects)
    x = [amplitude_at(design, z) for z in KNEE]
    f = [1.0, 10.0, 100.0]
    td = stiffness(design, f, x, route="time-domain")
    an = stiffness(design, f, x)
    assert td.route == "time-domain" and an.route == "analytic"
    assert_allclose(td.stiffness, an.stiffness, rtol=1e-3)
    if not effects:  # the knee is there: softer with amplitude (strain stiffening turns it up)
        assert np.all(np.diff(td.magnitude[:, 1]) < 0)


# ---- hysteresis loops -----------------------------------------------------------------------


@pytest.mark.parametrize("z", [0.3, 3.0])
@pytest.mark.parametrize("mode", MODES)
def test_a_loop_carries_its_modes_stiffness_and_dissipation(mode, z):
    """The steady loop (closed-form branches) against the stiffness (the universal friction
    function, another algorithm): its first Fourier coefficient is K x̂; its area, the energy
    dissipated per cycle, is π x̂² Im K; the elastic branch is the line F = S µ x of an
    independent S; the simulated steady period (time-domain route) is the same loop."""
    design = PAPER_B.in_mode(mode)
    f, x = 5.0, amplitude_at(design, z)
    k = stiffness(design, f, x).stiffness[0, 0]
    lp = loop(design, f, x, 512)
    # even sampling of a periodic, piecewise smooth force whose reversals fall on samples with
    # zero slope in θ: the coefficient converges fast; 1e-9 is far above what is left
    assert_allclose(first_harmonic(lp.force, lp.phase) / x, k, rtol=1e-9)
    dense = loop(design, f, x, 4096)
    closed_x, closed_f = np.append(dense.displacement, dense.displacement[0]), np.append(dense.force, dense.force[0])
    area = -np.trapezoid(closed_x, closed_f)  # ∮ F dx = −∮ x dF
    assert_allclose(area, math.pi * x * x * k.imag, rtol=1e-5)  # trapezoids: O(1/N²)
    s, _, accuracy = independent_factors(design)
    assert_allclose(lp.force_elastic, s * design.material.shear_modulus * lp.displacement,
                    rtol=0, atol=accuracy * np.abs(lp.force_elastic).max())
    td = loop(design, f, x, 64, route="time-domain")
    scale = np.abs(lp.force).max()
    for part in ("force_elastic", "force_viscoelastic", "force_friction"):
        # the simulation's steady state to 2e-6 of µ_eq and GL's O(Δt) phase: 1e-3 of the peak
        assert_allclose(getattr(td, part), getattr(lp, part)[::8], rtol=0, atol=1e-3 * scale)


# ---- force histories ----------------------------------------------------------------------


@pytest.mark.parametrize("z", [0.3, 3.0])
@pytest.mark.parametrize("mode", MODES)
def test_a_harmonic_history_settles_on_the_analytic_stiffness_and_loop(mode, z):
    """A sine history from rest, 64 periods of 1024 samples: its last period is the steady
    loop, and its first harmonic the analytic stiffness of that mode."""
    design = PAPER_B.in_mode(mode)
    f, x, n_p, periods = 5.0, amplitude_at(design, z), 1024, 64
    t = np.arange(1, n_p * periods + 1) / (f * n_p)
    hist = force_history(design, x * np.sin(2 * np.pi * f * t), 1 / (f * n_p))
    last = hist.force[-n_p - 1 : -1]  # phases 0 … 2π(n_p − 1)/n_p
    phase = 2 * np.pi * np.arange(n_p) / n_p
    k = stiffness(design, f, x).stiffness[0, 0]
    # Grünwald–Letnikov lags by ωαΔt/2 = πα/n_p = 6e-4 rad on the viscoelastic part (about a
    # sixth of |K|: 1e-4 of |K|), and the fractional memory's transient after 64 periods is
    # smaller still: 3e-4
    assert_allclose(first_harmonic(last, phase) / x, k, rtol=3e-4)
    lp = loop(design, f, x, n_p)
    assert_allclose(last, lp.force, rtol=0, atol=3e-4 * np.abs(lp.force).max())
    assert_allclose(hist.force_inertia, 0.0)


def berg_path(eps, turns, smax, ehalf):
    """Berg's friction stress (eq 6) along a strain path from the virgin state, written out from
    its reversal points: ``turns`` are the samples where the strain reverses."""
    out = np.empty_like(eps)
    e_s, s_s = 0.0, 0.0
    bounds = [0, *turns, eps.size]
    for start, end in itertools.pairwise(bounds):
        seg = eps[start:end]
        s = 1.0 if seg[-1] > e_s else -1.0
        u = seg - e_s
        out[start:end] = s_s + u * (smax - s * s_s) / (ehalf * (1 - s * s_s / smax) + s * u)
        e_s, s_s = seg[-1], out[end - 1]
    return out


@pytest.mark.parametrize("mode", MODES)
def test_a_history_with_reversals_is_berg_and_the_fractional_derivative_in_closed_form(mode):
    """Up to 3 ε½, down to −1.8 ε½, up to 0.9 ε½ (equivalent strain), ramps of 50 ms: the
    elastic branch is S µ x, the friction branch S/(2c) times Berg's stress from its reversal
    points, the viscoelastic branch S m/2 times the fractional derivative of the ramps, each
    with S and c by an independent route."""
    design = PAPER_B.in_mode(mode)
    m = design.material
    s, c, accuracy = independent_factors(design)
    n_seg, t_seg = 4000, 0.05
    dt = t_seg / n_seg
    corners = np.array([0.0, 3.0, -1.8, 0.9]) * m.friction_strain_half / c  # drive at the turns
    t = dt * np.arange(3 * n_seg + 1)
    x = np.interp(t, t_seg * np.arange(4), corners)
    hist = force_history(design, x, dt)
    turns = [n_seg + 1, 2 * n_seg + 1]  # a segment ends on its turning sample
    assert_allclose(hist.time_s, t, rtol=1e-12)

    def check(part, expected, tol):
        assert_allclose(part, expected, rtol=0, atol=tol * np.abs(expected).max())

    check(hist.force_elastic, s * m.shear_modulus * x, accuracy)
    # S/(2c) ∝ √S and the stress at c x moves by at most the strain's change: 0.5 % for the FE
    friction = s / (2 * c) * berg_path(c * x, turns, m.friction_stress_max, m.friction_strain_half)
    check(hist.force_friction, friction, max(accuracy, 1e-9))
    slopes = np.diff(corners) / t_seg
    kicks = np.diff(np.concatenate(([0.0], slopes)))  # slope changes at 0, 50 and 100 ms
    alpha = m.fractional_order
    derivative = sum(dv * np.clip(t - t0, 0, None) ** (1 - alpha) for dv, t0 in zip(kicks, t_seg * np.arange(3)))
    derivative /= math.gamma(2 - alpha)
    # GL is first order: its error near a corner is ~αΔt/(2(t − t₀)) of the kick's term,
    # summed over the path under 1e-3 of the peak (Δt = 12.5 µs)
    check(hist.force_viscoelastic, s * m.fractional_coefficient / 2 * derivative, accuracy + 1e-3)
    assert_allclose(hist.force, hist.force_elastic + hist.force_viscoelastic + hist.force_friction, rtol=1e-12)
