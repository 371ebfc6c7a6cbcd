"""The element driven: harmonic drives against the stiffness (describing function), a random
history against force_history, trial and state, cost per step (docs/element.md)."""

import numpy as np
import pytest

from core import PAPER_B, TABLE_1, force_history, stiffness
from core.element import CHANNEL_MODES, CHANNELS, Element, coefficients

# 1000 steps a period, and the band's top at the drive frequency (the worst place in the band):
# the fractional term with the input held over a step is then within 0.2 % and 0.0032 rad of
# (iω)^α over the band for α = 0.2 (Element.held_error; a step that resolves the band's top).
# 3 periods, the last one analysed: the friction loop settles after the first reversal (what
# drift remains at ε̂/ε½ ≈ 0.25 is about 0.2 % of the friction modulus after two periods), the
# exponentials with rates near ω decay within a period, and the slow ones (rates far below ω)
# carry a nearly constant offset that the first harmonic over a whole period does not see.
STEPS, PERIODS = 1000, 3
STRAINS = (1e-4, 1e-3, 1e-2)  # ε̂ across the Fletcher–Gent range (ε½ = 4e-3)


def _harmonic(el, amplitudes, f):
    """The first harmonic of the last period's forces over the drive, per channel (complex K)."""
    return _harmonic_n(el, amplitudes, f, STEPS, PERIODS)


def _check(design, slices, f, strain, channels=CHANNELS):
    el = Element.from_design(design, slices, band=(min(0.1, f / 10), f), channels=channels)
    designs = [design.in_mode(CHANNEL_MODES[c]) for c in channels]
    amplitudes = np.array([d.drive(strain) for d in designs])
    k = _harmonic(el, amplitudes, f)
    for name, d, amp, kj in zip(channels, designs, amplitudes, k, strict=True):
        n = slices if name in el.coefficients.sliced_channels else 1
        k0 = stiffness(d, f, amp, slices=n).stiffness[0, 0]
        assert abs(abs(kj) / abs(k0) - 1) < 0.01, (name, f, strain)
        assert abs(kj.imag / kj.real - k0.imag / k0.real) < 0.005, (name, f, strain)


@pytest.mark.filterwarnings("error::core.element.ElementWarning")
@pytest.mark.parametrize("f", [1.0, 10.0, 100.0])
@pytest.mark.parametrize("strain", STRAINS)
def test_harmonic_drive_every_channel_matches_the_stiffness(f, strain):
    _check(PAPER_B, 1, f, strain)


@pytest.mark.filterwarnings("error::core.element.ElementWarning")
@pytest.mark.parametrize("f", [1.0, 100.0])
@pytest.mark.parametrize("strain", STRAINS)
def test_harmonic_drive_with_slices_matches_the_sliced_stiffness(f, strain):
    _check(PAPER_B, 3, f, strain, channels=("dz", "rz"))


@pytest.mark.filterwarnings("error::core.element.ElementWarning")
def test_harmonic_drive_with_strain_stiffening_and_viscosity():
    design = PAPER_B.replace(effects={"strain_stiffening": {"stiffening": 2000.0}, "viscous": {"viscosity": 500.0}})
    _check(design, 3, 10.0, 1e-2, channels=("dz", "dx"))


@pytest.mark.filterwarnings("ignore::core.element.ElementWarning")  # coarse on purpose: the effect shows
def test_fractional_response_is_what_the_element_gives():
    """The held input's effect in closed form (Element.fractional_response) against a simulation
    of a channel whose friction is negligible: K = S(µ + m R(ω)/2), R the discrete response."""
    design = TABLE_1.replace(friction_stress_max=1e-6)
    f, steps = 10.0, 400
    el = Element(coefficients(design, 1, (0.1, 10.0)), ("rz",))
    k = _harmonic_n(el, np.array([design.drive(1e-3)]), f, steps, periods=6)[0]
    r = el.fractional_response(f, 1.0 / (f * steps))
    m = design.material
    expected = design.shape_factor * (m.shear_modulus + m.fractional_coefficient * r / 2)
    exact = design.shape_factor * (m.shear_modulus + m.fractional_coefficient * (2j * np.pi * f) ** m.fractional_order / 2)
    assert abs(k / expected - 1) < 2e-4 < abs(k / exact - 1)  # the held input's effect, and nothing else
    mag, phase = el.held_error(1.0 / (f * steps))
    ratio = r / (2j * np.pi * f) ** m.fractional_order
    assert abs(abs(ratio) - 1) <= mag and abs(np.angle(ratio)) <= phase


def _harmonic_n(el, amplitudes, f, steps, periods):
    h = 1.0 / (f * steps)
    theta = 2 * np.pi * np.arange(1, steps * periods + 1) / steps
    forces = np.array([el.commit(amplitudes * np.sin(t), h) for t in theta])[-steps:]
    th = theta[-steps:, None]
    return (2 * np.mean(forces * np.sin(th), 0) + 2j * np.mean(forces * np.cos(th), 0)) / amplitudes


@pytest.mark.filterwarnings("error::core.element.ElementWarning")
def test_random_history_matches_force_history():
    rng = np.random.default_rng(7)
    dt, n = 1e-4, 10000  # 1 s; content 1–20 Hz, the band 0.5–25 Hz (h = T/400 at 25 Hz)
    t = dt * np.arange(1, n + 1)
    freqs = rng.uniform(1.0, 20.0, 12)
    x = sum(np.sin(2 * np.pi * fr * t + ph) / fr for fr, ph in zip(freqs, rng.uniform(0, 2 * np.pi, 12), strict=True))
    design = PAPER_B
    x = design.drive(3e-3) * x / np.max(np.abs(x))
    el = Element(coefficients(design, 1, (0.5, 25.0)), ("dz",))
    ours = np.array([el.commit([v], dt)[0] for v in x])
    ref = force_history(design, x, dt).force
    assert np.sqrt(np.mean((ours - ref) ** 2)) < 0.01 * np.sqrt(np.mean(ref**2))


def _state_equal(a, b):
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


@pytest.mark.filterwarnings("ignore::core.element.ElementWarning")  # a coarse step: the state is the point
def test_trial_leaves_the_state_and_restore_repeats_the_step_bitwise():
    el = Element.from_design(PAPER_B, 3)
    rng = np.random.default_rng(3)
    drive = np.array([PAPER_B.in_mode(CHANNEL_MODES[c]).drive(1e-3) for c in CHANNELS])
    for _ in range(50):
        el.commit(drive * rng.standard_normal(6), 1e-4)
    before = el.state()
    x = drive * rng.standard_normal(6)
    trial = el.trial(x, 2e-4)
    assert _state_equal(before, el.state())
    first = el.commit(x, 2e-4)
    assert np.array_equal(trial, first)
    after = el.state()
    el.commit(drive, 1e-4)  # a rejected step
    el.restore(before)
    assert np.array_equal(el.commit(x, 2e-4), first) and _state_equal(after, el.state())
    snapshot = el.state()
    snapshot["z"][:] = 0.0  # the state handed out is a copy
    assert not _state_equal(snapshot, el.state())
    with pytest.raises(ValueError, match="state"):
        el.restore({**before, "eps": np.zeros(2)})


def test_cost_per_step_does_not_grow_with_history():
    el = Element(coefficients(PAPER_B, 3, (0.5, 2000.0)), ("dz", "dx"))
    rng = np.random.default_rng(5)
    amp = np.array([PAPER_B.drive(2e-3), PAPER_B.in_mode("radial").drive(2e-3)])
    x = np.cumsum(rng.standard_normal((5000, 2)), axis=0) * amp / 30.0  # a random walk: reversals at every scale
    shapes, iterations = [], []
    for k, xk in enumerate(x, start=1):
        el.commit(xk, 1e-6)
        iterations.append(el.iterations)
        if k in (10, 5000):
            shapes.append({key: np.shape(v) for key, v in el.state().items()})
    assert shapes[0] == shapes[1]
    assert max(iterations[-1000:]) <= max(iterations[:1000]) + 2 and max(iterations) <= 12


@pytest.mark.filterwarnings("error::core.element.ElementWarning")
def test_harmonic_drive_of_another_design_and_order():
    from core import TABLE_1  # torsion bushing, α = 0.4

    _check(TABLE_1, 1, 10.0, 1e-3)


def test_a_series_solve_that_cannot_converge_raises(monkeypatch):
    from core import ConvergenceError
    from core.element import element

    monkeypatch.setattr(element, "MAX_ITER", 1)
    el = Element(coefficients(PAPER_B, 3, (0.1, 25.0)), ("dz",))
    with pytest.raises(ConvergenceError, match="channel dz did not converge in 1 iterations"):
        el.commit([PAPER_B.drive(1e-3)], 1e-4)
