"""The separable material model (eqs 1–7): elastic, fractional and Berg friction branches.

Two routes lead to the equivalent complex shear modulus µ_eq(ω, ε̂) = σ̂ / (2 ε̂) (eq 16):

* the **time-domain route**, the thesis' own: drive the branches with ε(t) = ε̂ sin ωt, step the
  strain history (Grünwald–Letnikov for the fractional branch, Berg's smooth friction with
  reversal updates) until the steady state is reached, and take the first harmonic;
* the **analytic steady-state route**: µ_eq = µ + m (iω)^α / 2 + µ_f(ε̂), where the friction
  modulus µ_f comes from the closed-form steady loop (:func:`friction_modulus_universal`).

Conventions: ε is the tensor shear strain (γ = 2ε), σ = 2µε for the elastic branch; complex
amplitudes follow ε(t) = Im(ε̂ e^{iωt}), so Im µ_eq ≥ 0 means dissipation. All SI.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.signal import oaconvolve

from .memo import remembered as _remembered
from .parts import Material

REFERENCE_FREQUENCY_HZ = 10.0  # rate_amplitude_coupling: µ_f · (f / 10 Hz)^γ

# --------------------------------------------------------------------------------------------
# Analytic steady-state route
# --------------------------------------------------------------------------------------------

def friction_reversal_ratio(z):
    """Steady turning-point friction stress in units of σ_fmax, for amplitude z = ε̂/ε½.

    x solves x² + (1 + z) x − z = 0 (docs/model.md); written without cancellation as
    x = 2z / ((1 + z) + sqrt((1 + z)² + 4z)).
    """
    z = np.asarray(z, dtype=float)
    return 2.0 * z / ((1.0 + z) + np.sqrt((1.0 + z) ** 2 + 4.0 * z))


def _log1p_remainder(q):
    """R(q) = ln(1 + q)/q − 1 + q/2 = q²/3 − q³/4 + …, accurate for all q ≥ 0
    (a series below q = 0.05, where the direct form cancels). Arrays wholly on one side of
    0.05 (a fit's points mostly are) take their one form without the masks: the same numbers."""
    q = np.asarray(q, dtype=float)
    small = q < 0.05
    if not small.any():
        return _log1p_direct(q)
    if small.all():
        return _log1p_series(q)
    out = np.empty_like(q)
    out[small] = _log1p_series(q[small])
    out[~small] = _log1p_direct(q[~small])
    return out


def _log1p_series(qs):
    series = np.zeros_like(qs)
    for k in range(17, 2, -1):  # Horner: Σ_{k≥3} (−1)^(k+1) q^(k−2) / k, error < 1e-18
        series *= qs
        series += (-1.0) ** (k + 1) / k
    return series * qs * qs


def _log1p_direct(ql):
    return np.log1p(ql) / ql - 1.0 + 0.5 * ql


def _universal(z):
    """g(z) computed: :func:`friction_modulus_universal` without its cache."""
    z = np.asarray(z, dtype=float)
    x = friction_reversal_ratio(z)
    c = 1.0 + x
    cz = c + z
    s = np.sqrt(c * (c + 2.0 * z)) / cz
    real = c * c / (cz * cz * s * (1.0 + s))
    h = x * (x + z) - c * _log1p_remainder(2.0 * z / c)
    positive = z > 0  # at z = 0, Im g = 0 (the limit), not 0/0
    imag = np.where(positive, (2.0 / np.pi) * h / np.where(positive, z, 1.0), 0.0)
    return real + 1j * imag


def friction_modulus_universal(z):
    """Universal friction modulus g(z), with µ_f(ε̂) = (σ_fmax/ε½) · g(ε̂/ε½) (docs/model.md).

    The steady symmetric Berg loop between ±ε̂ has the rising branch (ε in units of ε½,
    σ in units of σ_fmax)  σ = 1 − (1 + x)² / ((1 + x) + z + ε), and the falling branch by
    symmetry. Its first Fourier coefficient over ε = z sin θ, divided by 2z, integrates in
    closed form (half-period integrals of 1/(A + z sin θ), A = 1 + x + z):

        Re g = (1 + x)² / ((1 + x + z)² s (1 + s)),  s = sqrt((1 + x)(1 + x + 2z)) / (1 + x + z)
        Im g = 2 / (π z) · [x (x + z) − (1 + x) R(q)],  q = 2z / (1 + x)

    with R from :func:`_log1p_remainder`. Limits: g → 1/2 as z → 0 (µ_f → σ_fmax/(2ε½));
    Im g → 2/(π z) as z → ∞ (the Coulomb square loop). Im g ≥ 0.

    Parameters: z, array-like, dimensionless amplitude ε̂/ε½ > 0. Returns complex array.

    The last values are remembered (:func:`_remembered`): a fit's finite-difference Jacobian
    changes one parameter at a time, and z = ε̂/ε½ only when ε½ changes.
    """
    return _remembered("universal", _universal, z)


def friction_modulus(strain_amplitude, friction_stress_max: float, friction_strain_half: float):
    """Friction modulus µ_f(ε̂) in Pa for the tensor strain amplitude ε̂ (docs/model.md, route 2).
    ``friction_strain_half`` may be one value per design, shaped (n, 1, …) against ε̂."""
    eps = np.asarray(strain_amplitude, dtype=float)
    universal = _by_row(lambda half: friction_modulus_universal(eps / half), friction_strain_half, eps.shape)
    if universal is None:
        universal = friction_modulus_universal(eps / friction_strain_half)
    return friction_stress_max / friction_strain_half * universal


FEW_VALUES = 8  # a parameter of this few distinct values (per design) is computed value by value


def _by_row(compute, values, shape):
    """``compute(v)`` for each of the few distinct values v of a parameter given one value per
    design (shaped (n, 1, …) against arguments of ``shape``), stacked to (n, …) in the designs'
    order: each value's numbers computed once, and remembered (a finite-difference Jacobian's
    columns share all but one value of each parameter). None where ``values`` is not so shaped or
    has more than :data:`FEW_VALUES` distinct values (Monte Carlo samples)."""
    values = np.asarray(values)
    if values.ndim == 0 or values.size != values.shape[0] or values.ndim <= len(shape):
        return None
    listed = values.ravel().tolist()
    distinct = dict.fromkeys(listed)
    if len(distinct) > FEW_VALUES:
        return None
    out = np.broadcast_shapes(values.shape[1:], shape)
    rows = {v: np.broadcast_to(compute(v), out) for v in distinct}
    if len(listed) == 1:
        return rows[listed[0]][None]
    return np.stack([rows[v] for v in listed])


def fractional_modulus(frequency_hz, fractional_coefficient: float, fractional_order: float):
    """Fractional-branch modulus m (iω)^α / 2 in Pa (eq 5 over 2, since σ = 2µε)."""
    return fractional_coefficient * _fractional_power(frequency_hz, fractional_order) / 2.0  # eqs 2, 5


def _fractional_power(frequency_hz, fractional_order):
    """(iω)^α, remembered for a scalar α (:func:`_remembered`): a fit's finite-difference
    Jacobian changes α in one column of its five or more."""
    if np.ndim(fractional_order) == 0:
        return _remembered(("power", float(fractional_order)),
                           functools.partial(_power, float(fractional_order)), frequency_hz)
    rows = _by_row(functools.partial(_fractional_power, frequency_hz), fractional_order, np.shape(frequency_hz))
    return _power(fractional_order, np.asarray(frequency_hz, dtype=float)) if rows is None else rows


def _power(fractional_order, frequency_hz):
    omega = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)
    return (1j * omega) ** fractional_order


def equivalent_modulus(material: Material, frequency_hz, strain_amplitude):
    """µ_eq(ω, ε̂) = µ + m (iω)^α / 2 + µ_f(ε̂) in Pa, broadcast over the two arrays (eq 16).

    The analytic steady-state route: the friction modulus µ_f from the closed-form steady loop
    (:func:`friction_modulus`).

    Parameters
    ----------
    material : Material
        The five parameters (µ in Pa, m in Pa·s^α, α dimensionless, σ_fmax in Pa, ε½
        dimensionless), or any object with these five fields as arrays that broadcast with the
        two arguments (e.g. one value per Monte Carlo sample, shaped (n, 1, …), as
        :mod:`core.whatif.tolerance` gives): the result then has a row per sample.
    frequency_hz : float or array_like
        Frequencies in Hz.
    strain_amplitude : float or array_like
        Equivalent (tensor) shear strain amplitudes ε̂, dimensionless, positive.

    Returns
    -------
    numpy.ndarray
        Complex µ_eq in Pa, the arguments broadcast together; Im µ_eq ≥ 0 (dissipation).
    """
    parts = branch_moduli(material, frequency_hz, strain_amplitude)
    return parts["elastic"] + parts["viscoelastic"] + parts["friction"]  # eq 16


def branch_moduli(material: Material, frequency_hz, strain_amplitude) -> dict:
    """The three terms of µ_eq (eq 16) in Pa, by branch: ``elastic`` µ, ``viscoelastic``
    m (iω)^α / 2 and ``friction`` µ_f(ε̂), unbroadcast (µ stays a scalar, or an array of samples).
    :func:`equivalent_modulus` is their sum; :func:`core.effects.branch_moduli` adds the
    material-level effects' terms to them."""
    return {  # the linear part µ + m(iω)^α/2 is eqs 8–9's µ(ω), the friction part eq 6's
        "elastic": material.shear_modulus,
        "viscoelastic": fractional_modulus(frequency_hz, material.fractional_coefficient,
                                           material.fractional_order),
        "friction": friction_modulus(strain_amplitude, material.friction_stress_max,
                                     material.friction_strain_half),
    }


# --------------------------------------------------------------------------------------------
# Time-domain route: the branches along a sampled strain path
# --------------------------------------------------------------------------------------------


def grunwald_weights(n: int, order: float) -> np.ndarray:
    """Grünwald–Letnikov weights w_0 … w_{n−1} (eq 3) by the recursion
    w_0 = 1, w_j = w_{j−1} (j − 1 − α)/j, which never overflows (the Gamma ratio does)."""
    j = np.arange(1, n, dtype=float)
    return np.concatenate(([1.0], np.cumprod((j - 1.0 - order) / j)))


def fractional_stress(strain, dt: float, fractional_coefficient: float, fractional_order: float):
    """σ_fr(t_n) ≈ m Δt^(−α) Σ_{j=0..n} w_j ε_{n−j} (eq 3), an FFT convolution: O(N log N).

    The history is taken to start from rest at ε = 0 before the first sample. The sum is
    first-order accurate at t_n and second-order accurate at the shifted time t_n − αΔt/2.
    """
    strain = np.asarray(strain, dtype=float)
    w = grunwald_weights(strain.size, fractional_order)
    return fractional_coefficient * dt ** (-fractional_order) * oaconvolve(w, strain)[: strain.size]


def friction_stress(strain, friction_stress_max: float, friction_strain_half: float):
    """Berg's smooth friction stress (eq 6) along a sampled strain path.

        σ_f = σ_fs + (ε − ε_s)(σ_fmax − s σ_fs) / (ε½ (1 − s σ_fs/σ_fmax) + s (ε − ε_s))

    with s = sign(dε/dt) and (ε_s, σ_fs) the last reversal point, updated whenever the strain
    rate changes sign. The path starts from the virgin state (ε_s = 0, σ_fs = 0) at ε = 0, so a
    path that starts elsewhere is reached by monotone loading from zero. Rate independent.
    The state changes only at reversals: a scalar recurrence runs once per reversal to find
    the reversal states, then eq 6 is evaluated for all samples at once.
    """
    eps = np.asarray(strain, dtype=float)
    smax, ehalf = float(friction_stress_max), float(friction_strain_half)
    path = np.concatenate(([0.0], eps))
    step = np.sign(np.diff(path))
    # a sample that does not move keeps the direction it had (no reversal)
    moving = step != 0
    if not moving.any():
        return np.zeros_like(eps)
    idx = np.where(moving, np.arange(step.size), 0)
    np.maximum.accumulate(idx, out=idx)
    direction = step[idx]
    first = int(np.argmax(moving))
    direction[:first] = step[first]
    # segments of monotone motion; the last sample of each is the next reversal point
    change = np.flatnonzero(direction[1:] != direction[:-1]) + 1  # index into eps
    starts = np.concatenate(([0], change))
    ends = np.concatenate((change, [eps.size]))
    seg_dir = direction[starts]
    # the reversal states, one scalar step per segment (plain floats: cheap per reversal)
    eps_s = np.empty(starts.size)
    sig_s = np.empty(starts.size)
    e0, s0 = 0.0, 0.0
    for k, (s, e1) in enumerate(zip(seg_dir.tolist(), eps[ends - 1].tolist())):
        eps_s[k], sig_s[k] = e0, s0
        u = e1 - e0
        s0 = s0 + u * (smax - s * s0) / (ehalf * (1.0 - s * s0 / smax) + s * u)
        e0 = e1
    # eq 6 for every sample at once, with its segment's reversal state
    seg = np.repeat(np.arange(starts.size), ends - starts)
    s, es, ss = seg_dir[seg], eps_s[seg], sig_s[seg]
    u = eps - es
    return ss + u * (smax - s * ss) / (ehalf * (1.0 - s * ss / smax) + s * u)


def elastic_stress(material: Material, strain, effects: Mapping | None = None):
    """Elastic-branch stress in Pa at the (tensor shear) strain ``strain``: σ_el = 2µε (eq 1), or
    2µε(1 + βε²) with the ``strain_stiffening`` effect (docs/model.md). Arrays too."""
    strain = np.asarray(strain, dtype=float)
    elastic = 2.0 * material.shear_modulus * strain  # eq 1
    if effects and "strain_stiffening" in effects:
        elastic = elastic * (1.0 + effects["strain_stiffening"]["stiffening"] * strain**2)
    return elastic


@dataclass(frozen=True)
class BranchStresses:
    """Stress histories along one strain path, in Pa: the elastic branch (with
    ``strain_stiffening``), the viscoelastic branch (fractional, with ``viscous``) and the
    friction branch (with ``rate_amplitude_coupling``)."""

    elastic: np.ndarray
    fractional: np.ndarray
    friction: np.ndarray

    @property
    def total(self) -> np.ndarray:
        return self.elastic + self.fractional + self.friction  # eq 7


def branch_stresses(
    material: Material,
    strain,
    dt: float,
    effects: Mapping | None = None,
    frequency_hz: float | None = None,
) -> BranchStresses:
    """Stress of each branch for the sampled strain history ``strain`` (step ``dt`` in s).

    ``effects`` (id → parameters, docs/model.md) adds the material-level extensions in the time
    domain: σ_el = 2µε(1 + βε²) (``strain_stiffening``), σ += c dε/dt (``viscous``, central
    differences), σ_f · (f / 10 Hz)^γ (``rate_amplitude_coupling``, which needs the drive
    frequency ``frequency_hz``: it is defined for harmonic drives only).
    """
    strain = np.asarray(strain, dtype=float)
    effects = effects or {}
    elastic = elastic_stress(material, strain, effects)
    visco = fractional_stress(strain, dt, material.fractional_coefficient, material.fractional_order)
    if "viscous" in effects:
        visco = visco + effects["viscous"]["viscosity"] * np.gradient(
            np.concatenate(([0.0], strain)), dt
        )[1:]
    friction = friction_stress(strain, material.friction_stress_max, material.friction_strain_half)
    if "rate_amplitude_coupling" in effects:
        if frequency_hz is None:
            raise ValueError(
                "effects.rate_amplitude_coupling: defined for harmonic drives only (it scales "
                "friction by the drive frequency), not for an arbitrary history"
            )
        gamma = effects["rate_amplitude_coupling"]["rate_exponent"]
        friction = friction * (frequency_hz / REFERENCE_FREQUENCY_HZ) ** gamma
    return BranchStresses(elastic, visco, friction)


class ConvergenceError(RuntimeError):
    """An iteration stopped before meeting its tolerance; no number is returned.

    Raised by the time-domain route (:func:`equivalent_modulus_time_domain`) and by the slices
    and the continuum (:func:`core.slices.solve_series`); the message says what did not
    converge and how far it was.
    """


@dataclass(frozen=True)
class TimeDomainModulus:
    """µ_eq from the time-domain route, with how it was reached.

    Attributes
    ----------
    modulus : complex
        µ_eq in Pa.
    periods : int
        The periods simulated.
    samples_per_period : int
        The time steps per period.
    change : float
        The estimated relative change of µ_eq still to come (:func:`_remaining_change`),
        dimensionless.
    """

    modulus: complex
    periods: int
    samples_per_period: int
    change: float


def _remaining_change(h1: complex, h2: complex, h3: complex) -> float:
    """Relative change still to come after the last period, from the last three periods'
    harmonics h1 (last), h2, h3, assuming the approach to steady state is at worst geometric
    with the observed ratio r = |h1 − h2| / |h2 − h3|: remaining ≈ |h1 − h2| r / (1 − r).
    A change at round-off level counts as converged; a ratio ≥ 1 gives no estimate (inf)."""
    d1, d2 = abs(h1 - h2), abs(h2 - h3)
    scale = abs(h1)
    if d1 <= 1e-13 * scale:
        return d1 / scale
    r = d1 / d2 if d2 > 0 else np.inf
    if r >= 0.999:
        return np.inf
    return float(max(d1 * r / (1.0 - r), d1) / scale)


def _first_harmonic(signal, theta, weight_shift=0.0):
    """Complex first harmonic c such that signal ≈ Im(c e^{iθ}) over whole periods."""
    # signal ≈ a sin θ + b cos θ  ⇒  c = a + i b
    a = 2.0 * np.mean(signal * np.sin(theta - weight_shift))
    b = 2.0 * np.mean(signal * np.cos(theta - weight_shift))
    return a + 1j * b


def _period_modulus(br: BranchStresses, theta, n_p: int, k: int, shift: float, strain_amplitude):
    """µ_eq from the first harmonic of the k-th last period of the branch stresses."""
    sl = slice(theta.size - k * n_p, theta.size - (k - 1) * n_p)
    th = theta[sl]
    stress_amp = (
        _first_harmonic(br.elastic[sl], th)
        + _first_harmonic(br.fractional[sl], th, shift)  # GL: 2nd order at t − αΔt/2
        + _first_harmonic(br.friction[sl], th)
    )
    return stress_amp / (2.0 * strain_amplitude)


def samples_per_period_for(material: Material, strain_amplitude: float) -> int:
    """Samples per period resolving the friction knee (width ~ sqrt(2 ε½/ε̂) in phase)."""
    z = strain_amplitude / material.friction_strain_half
    knee = np.sqrt(2.0 / max(z, 1e-12))
    need = 2.0 * np.pi / min(knee / 40.0, 2.0 * np.pi / 1024)
    return int(4 * 2 ** int(np.ceil(np.log2(need / 4))))


def equivalent_modulus_time_domain(
    material: Material,
    frequency_hz: float,
    strain_amplitude: float,
    *,
    samples_per_period: int | None = None,
    periods: int = 8,
    max_periods: int = 1024,
    rtol: float = 2e-6,
    effects: Mapping | None = None,
) -> TimeDomainModulus:
    """µ_eq(ω, ε̂) by simulating the strain-driven model (the thesis' route, eq 16).

    ε(t) = ε̂ sin ωt is applied from rest. The fractional memory decays slowly (algebraically)
    and, at small amplitude, so does the friction loop's drift from the virgin state, so the
    number of periods doubles until the change still to come is below ``rtol`` (relative to
    |µ_eq|), or :class:`ConvergenceError` is raised. The GL sum is assigned to its second-order time
    t_n − αΔt/2 (a phase shift ωαΔt/2 of its harmonic). Convergence is judged on the last three
    periods (:func:`_remaining_change`).

    Parameters
    ----------
    material : Material
        The five parameters of the model, SI (µ and σ_fmax in Pa, m in Pa·s^α).
    frequency_hz : float
        The drive frequency in Hz, positive.
    strain_amplitude : float
        The tensor shear strain amplitude ε̂, dimensionless, positive.
    samples_per_period : int or None, default None
        Time steps per period; None: enough to resolve the friction knee
        (:func:`samples_per_period_for`).
    periods : int, default 8
        The periods simulated first.
    max_periods : int, default 1024
        The most periods simulated before :class:`ConvergenceError`.
    rtol : float, default 2e-6
        The relative change of µ_eq still to come that counts as converged, dimensionless.
    effects : mapping of str to mapping, or None, default None
        Material-level effects, id → parameters (docs/model.md), in SI units: ``viscous``'s
        viscosity in Pa·s, ``strain_stiffening``'s β and ``rate_amplitude_coupling``'s γ
        dimensionless.

    Returns
    -------
    TimeDomainModulus
        ``modulus``, µ_eq in Pa, with the periods and samples it took and the change still to
        come (dimensionless).

    Raises
    ------
    ValueError
        If the frequency or the strain amplitude is not positive.
    ConvergenceError
        If the change still to come is above ``rtol`` after ``max_periods``.
    """
    if not (frequency_hz > 0 and strain_amplitude > 0):
        raise ValueError("frequency and strain amplitude must be positive")
    n_p = samples_per_period or samples_per_period_for(material, strain_amplitude)
    omega = 2.0 * np.pi * frequency_hz
    dt = 1.0 / (frequency_hz * n_p)
    shift = omega * material.fractional_order * dt / 2.0
    total = periods
    while True:
        n = total * n_p
        theta = 2.0 * np.pi * np.arange(1, n + 1) / n_p
        strain = strain_amplitude * np.sin(theta)
        br = branch_stresses(material, strain, dt, effects, frequency_hz)
        h1, h2, h3 = (
            _period_modulus(br, theta, n_p, k, shift, strain_amplitude) for k in (1, 2, 3)
        )
        change = _remaining_change(h1, h2, h3)
        if change <= rtol:
            return TimeDomainModulus(complex(h1), total, n_p, float(change))
        if total * 2 > max_periods:
            raise ConvergenceError(
                f"time-domain steady state not reached at {frequency_hz:g} Hz, strain amplitude "
                f"{strain_amplitude:g} after {total} periods (estimated remaining change "
                f"{change:.2e} > {rtol:.1e})"
            )
        total *= 2
