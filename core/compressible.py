"""A compressible rubber as a shear layer in series with an elastic bulk spring (docs/model.md,
"Compressibility"), for the outputs that follow the rubber's strain along a drive: the
hysteresis loop (:mod:`core.loops`) and the time-domain element (:mod:`core.element`); and the
stiffness at the rubber's own strain amplitude (:class:`BulkCorrection`).

The finite-length table's series law 1/S(x) = (1 + g(x − x₀))/S(x₀), x = µ/K,
x₀ = 1/:data:`core.shape.BULK_RATIO`, gives the stiffness

    1/K = (1 − g x₀)/(S₀ µ) + g/(S₀ K),

exactly a shear layer of shape factor S₀/(1 − g x₀) (strain factor √(S/(4V)) by the energy
balance, :func:`core.shape.strain_factor_from_shape`) in series with the compliance
C_b = g/(S₀ K) (m/N, or rad/(N·m)). By the correspondence principle the same holds with the
complex, amplitude-dependent µ* of the rubber: the force is the same through both, the drive is
the sum of their displacements, x = ε/c + C_b F, so the rubber's own strain is not c·x.

The long radial bushing's plane-strain closed form (:func:`core.shape.long_radial_compressible`)
has no such global form: its stiffness of a thin wall tends to πaL(K + 7µ/3)/t, the bulk and the
shear moduli side by side, not in series. The series law through its tangent at x = 0,
1/S(x) = (1 + g x)/S(0) with g = (ln q + 3r)/(ln q − r), q = b/a, r = (q² − 1)/(q² + 1)
(:func:`long_radial_slope`), is off the closed form by up to 4.7 % at K/µ 50 (b/a → 1), 0.93 %
at 250 and 0.33 % at 700. So the long radial direction gets a series matched at its operating
point instead (:func:`long_radial_series`): three real numbers (S', c', C_b) chosen so that at the
complex µ* of that point the series' stiffness S'µ*/(1 + C_b S'µ*) is the closed form's
S₀µ*φ(µ*/K) and the rubber's strain c'x̂/|1 + C_b S'µ*| is the energy rule's c·x̂·|√ψ(µ*/K)|
(both are rational in x, so they take a complex µ*/K); as the loss vanishes the pair tends to the
closed form's tangent at x. The loop and a fit to a measured loop match it at their own (f, x̂)
(:func:`series_at`, the stiffness's µ*), the force history at its peak drive and dominant
frequency (:func:`history_point`), the element at :data:`REFERENCE_FREQUENCY` and
:data:`REFERENCE_STRAIN`.

The stiffness's first harmonic needs only the rubber's strain amplitude, and that follows from
the energy balance for any closed form K = S·µ·φ(µ/K): the shear (deviatoric) energy is
µ·∂K/∂µ·x̂²/2 at fixed drive (the strain field is stationary), so ε̂ = c·x̂·|√ψ(µ*/K)| with
ψ(x) = d(xφ)/dx (:func:`core.shape.bulk_tangent`). For the table's series law this is the
series' own ε̂ = c'x̂/|1 + C_b S'µ*|, c' the shear layer's strain factor (the force F = S'µ*x_r
through both, x = x_r + C_b F), and K = S·µ*·φ(µ*/K) = S'µ*/(1 + C_b S'µ*); the long radial
closed form gets its rubber's amplitude by the same rule (:meth:`BulkCorrection.rubber_modulus`
solves it with µ* = µ_eq(f, ε̂)).

:func:`steady_series_strain` solves one steady period of the series for a harmonic drive: the
shear strain ε(θ) at every sample with ε + κσ[ε] = c x̂ sin θ, κ = C_b S/2 (1/Pa), σ[ε] the
rubber's three branches (the fractional one over the whole period, harmonic by harmonic; Berg's
friction on the steady symmetric loop between ±ε̂, ε̂ = max ε), by Newton's method with the
linear systems solved by GMRES. :func:`series_history_strain` solves the same balance for any
sampled drive history, ε + κσ[ε] = c x (the force history, :func:`core.loops.force_history`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .design import Design
from .effects import branch_moduli
from .material import ConvergenceError, elastic_stress, friction_modulus, friction_reversal_ratio
from .shape import (
    BULK_RATIO,
    bulk_factor,
    bulk_tangent,
    pure_shear,
    strain_factor_from_shape,
    table,
)

LONG_RADIAL_REFUSAL = (
    "material.bulk_modulus: the long {mode} closed form of a compressible rubber (plane strain) has no "
    "global series form (a shear layer in series with a bulk spring is up to 4.7 % off it at K/µ 50, 0.9 % at 250): "
    "{what} needs the operating point (frequency and amplitude) its series is matched at")
# the element's operating point for the long radial closed form with a bulk modulus (docs/element.md)
REFERENCE_FREQUENCY = 10.0  # Hz
REFERENCE_STRAIN = 1e-3  # the drive's equivalent strain c·x̂
LOSS_FLOOR = 1e-6  # |Im µ*|/|µ*| below which the matched pair is the closed form's tangent
RUBBER_TOLERANCE = 1e-13  # on ln ε̂ of the rubber's strain amplitude (relative)
MAX_RUBBER_ITERATIONS = 60
SAMPLES = 2048  # at least this many samples a period inside the steady solve
TOLERANCE = 1e-12  # relative to the drive's strain c·x̂, on the series balance
MAX_NEWTON = 60


@dataclass(frozen=True)
class BulkSeries:
    """A compressible direction as a shear layer in series with a bulk spring.

    Attributes
    ----------
    shape_factor : float
        The shear layer's S, m (translations) or m³/rad (rotations).
    strain_factor : float
        The shear layer's c = √(S/(4V)), 1/m or 1/rad.
    compliance : float
        The bulk spring's C_b, m/N or rad/(N·m).
    """

    shape_factor: float
    strain_factor: float
    compliance: float

    @property
    def kappa(self) -> float:
        """κ = C_b S/2 (1/Pa): the bulk spring's strain per unit of the rubber's stress,
        ε + κσ = c·x."""
        return 0.5 * self.compliance * self.shape_factor


def long_radial_slope(radius_ratio: float) -> float:
    """g of the long radial closed form's tangent series law, 1/S(x) ≈ (1 + g x)/S(0):
    (ln q + 3r)/(ln q − r), q = b/a, r = (q² − 1)/(q² + 1) (dimensionless)."""
    q = float(radius_ratio)
    ln, r = math.log(q), (q * q - 1.0) / (q * q + 1.0)
    return (ln + 3.0 * r) / (ln - r)


def in_series(design: Design) -> bool:
    """Whether ``design``'s bulk modulus acts as a spring in series (:func:`series_at`): K is given
    and the direction squeezes the rubber (the finite-length table's directions and the long
    radial closed form, whose series is matched at an operating point)."""
    return design.material.bulk_modulus is not None and not pure_shear(design.mode, design.shape_kind)


def bulk_series(design: Design, what: str = "the time-domain element") -> BulkSeries | None:
    """The series form of ``design`` in its own mode, or None where the bulk modulus is absent
    or does not act (pure shear: torsion, the long axial bushing). ValueError for the long
    radial closed form (:data:`LONG_RADIAL_REFUSAL`, naming ``what``): its series depends on the
    operating point (:func:`series_at`)."""
    bulk = design.material.bulk_modulus
    if bulk is None or pure_shear(design.mode, design.shape_kind):
        return None
    if design.shape_kind == "long":
        raise ValueError(LONG_RADIAL_REFUSAL.format(mode=design.mode, what=what))
    geo = design.geometry
    a, b, L = geo.inner_radius, geo.outer_radius, geo.length
    s0 = design.shape_factor
    g = table().slope(design.mode, b / a, L / (b - a))
    s = s0 / (1.0 - g / BULK_RATIO)
    return BulkSeries(s, strain_factor_from_shape(s, a, b, L), g / (s0 * bulk))


def long_radial_series(design: Design, modulus: complex) -> BulkSeries:
    """The series matched to the long radial closed form at the rubber's complex modulus
    ``modulus`` µ* (Pa) (see the module's docstring): with A = 1/(S₀µ*φ(µ*/K)) the closed form's
    compliance, C_b = Im(µ*A)/Im(µ*), S' = 1/Re(µ*(A − C_b)) (so that µ*(A − C_b) is real and
    1/(S'µ*) + C_b = A), and c' = S'·c·|√ψ(µ*/K)|·|µ*A| (so that the series' rubber strain
    c'x̂/|1 + C_b S'µ*| = c'x̂/(S'|µ*A|) is the energy rule's c·x̂·|√ψ|). Where |Im µ*| < :data:`LOSS_FLOOR`·|µ*|, the
    closed form's tangent at the real µ: S' = S₀φ²/ψ, C_b = (φ − ψ)/(S₀φ²µ), its limit."""
    mu = complex(modulus)
    x = mu / design.material.bulk_modulus
    geo = design.geometry
    s0, c = design.shape_factor, design.strain_factor
    phi = complex(bulk_factor(geo, design.mode, "long", x))
    psi = complex(bulk_tangent(geo, design.mode, "long", x))
    a = 1.0 / (s0 * mu * phi)
    if abs(mu.imag) >= LOSS_FLOOR * abs(mu):
        compliance = (mu * a).imag / mu.imag
    else:
        compliance = ((phi - psi) / (s0 * phi * phi * mu)).real
    s = 1.0 / (mu * (a - compliance)).real
    return BulkSeries(s, s * c * math.sqrt(abs(psi)) * abs(mu * a), compliance)


def series_at(design: Design, modulus, frequency_hz: float, amplitude: float,
              what: str = "the hysteresis loop") -> BulkSeries | None:
    """The series (:class:`BulkSeries`) ``design`` follows at the drive frequency (Hz) and
    amplitude x̂ (m or rad): :func:`bulk_series` where that is the table's, and for the long radial
    closed form :func:`long_radial_series` at the µ* the stiffness takes there (µ*(f, ε̂) at the
    rubber's own strain amplitude, :meth:`BulkCorrection.rubber_modulus`); None where the bulk
    modulus is absent or does not act. ``modulus`` is µ_eq(f, ε̂) in Pa
    (:func:`core.bushing.modulus_function`)."""
    if not in_series(design) or design.shape_kind != "long":
        return bulk_series(design, what)
    bulk = BulkCorrection(design.geometry, design.mode, design.shape_kind, design.material.bulk_modulus)
    _, mu = bulk.rubber_modulus(modulus, frequency_hz, design.strain(amplitude))
    return long_radial_series(design, complex(np.asarray(mu).ravel()[0]))


def history_point(displacement, dt: float) -> tuple[float, float]:
    """The operating point a sampled drive history's long radial series is matched at
    (:func:`series_at`): its dominant frequency, that of the largest bin of its discrete Fourier
    transform past zero (Hz; 1/(2 dt) for a single sample), and its peak |x| (m or rad). For a
    whole number of periods of a harmonic drive, its frequency and amplitude."""
    x = np.asarray(displacement, dtype=float)
    spectrum = np.abs(np.fft.rfft(x))[1:]
    frequency = (int(np.argmax(spectrum)) + 1) / (x.size * dt) if spectrum.size else 0.5 / dt
    return frequency, float(np.max(np.abs(x)))


# ---- the stiffness at the rubber's own strain amplitude ------------------------------------


@dataclass(frozen=True, eq=False)
class BulkCorrection:
    """How an elastic bulk modulus changes K = S·µ* of a design (:func:`core.bushing.bulk_correction`),
    by the correspondence principle, at the rubber's own strain amplitude.

    Attributes
    ----------
    geometry, mode, shape
        The design's (:func:`core.shape.bulk_factor`'s arguments).
    bulk_modulus : float or numpy.ndarray
        K in Pa, broadcast against µ* (e.g. one value per sample shaped (n, 1, …)).
    """

    geometry: object
    mode: str
    shape: str
    bulk_modulus: object

    def factor(self, mu):
        """S(µ*/K)/S (dimensionless) at the complex equivalent modulus µ* (Pa)."""
        return bulk_factor(self.geometry, self.mode, self.shape, mu / self.bulk_modulus)

    def strain_ratio(self, mu):
        """ε̂/(c x̂) = |√ψ|, ψ = d(xφ)/dx at x = µ*/K (:func:`core.shape.bulk_tangent`): the
        rubber's strain amplitude against the drive's c·x̂ (dimensionless)."""
        return np.sqrt(np.abs(bulk_tangent(self.geometry, self.mode, self.shape, mu / self.bulk_modulus)))

    def rubber_modulus(self, modulus, frequency_hz, strain):
        """The rubber's strain amplitude ε̂ and µ*(f, ε̂) where ε̂ = ``strain``·|√ψ(µ*(f, ε̂)/K)|
        (docs/model.md, "Compressibility"), ``strain`` = c·x̂ the drive's equivalent strain;
        ``modulus`` is µ*(frequency_hz, strain_amplitude) in Pa, broadcast.

        Solved for ln ε̂ at every point at once by the secant method, started from the fixed-point
        step and kept inside the bracket the signs of the residual h = ln ε̂ − ln(c x̂) − ln|√ψ|
        have shown (bisection where a step leaves it); a point stays where it is once
        |h| ≤ :data:`RUBBER_TOLERANCE`, so a point's value does not depend on the others solved
        with it. Where µ* does not depend on the amplitude the first step is the solution.

        Returns
        -------
        tuple of numpy.ndarray
            (ε̂, µ*): the strain amplitude (dimensionless) and the complex modulus in Pa, shaped as
            the arguments broadcast together.

        Raises
        ------
        ConvergenceError
            If some point has not converged in :data:`MAX_RUBBER_ITERATIONS` steps.
        """
        drive = np.log(np.asarray(strain, dtype=float))

        def residual(t):
            mu = modulus(frequency_hz, np.exp(t))
            return t - drive - np.log(self.strain_ratio(mu)), mu

        h, mu = residual(drive)
        shape = np.broadcast_shapes(np.shape(h), np.shape(mu))
        t = np.array(np.broadcast_to(drive, shape))
        h, mu = np.array(np.broadcast_to(h, shape)), np.array(np.broadcast_to(mu, shape))
        lo, hi = np.full(shape, -np.inf), np.full(shape, np.inf)
        t_old = h_old = None
        for _ in range(MAX_RUBBER_ITERATIONS):
            done = (np.abs(h) <= RUBBER_TOLERANCE) | ~np.isfinite(h)  # not finite: the caller says so
            if done.all():
                return np.exp(t), mu
            lo, hi = np.where(h < 0, np.maximum(lo, t), lo), np.where(h > 0, np.minimum(hi, t), hi)
            slope = np.ones(shape)
            if t_old is not None:
                moved = t != t_old
                slope = np.divide(h - h_old, t - t_old, out=slope, where=moved)
                slope = np.where(np.isfinite(slope) & (slope > 0), slope, 1.0)
            step = t - h / slope
            inside = (step > lo) & (step < hi)
            both = np.isfinite(lo) & np.isfinite(hi)
            step = np.where(inside, step, np.where(both, 0.5 * (lo + hi), np.where(np.isfinite(hi), hi - 1.0, lo + 1.0)))
            t_new = np.where(done, t, step)
            h_new, mu_new = residual(t_new)
            t_old, h_old = t, h
            t = t_new
            h = np.where(done, h, np.broadcast_to(h_new, shape))
            mu = np.where(done, mu, np.broadcast_to(mu_new, shape))
        raise ConvergenceError(f"the rubber's strain amplitude through the bulk spring did not converge in "
                               f"{MAX_RUBBER_ITERATIONS} steps (residual {float(np.nanmax(np.abs(h))):.2e})")


# ---- one steady period of the series ------------------------------------------------------


def _grid(points: int) -> int:
    """A sample count M that ``points`` divides, a multiple of 4 (odd harmonics only, the
    Nyquist frequency's among the even ones), at least :data:`SAMPLES`."""
    k = -(-SAMPLES // points)
    while (points * k) % 4:
        k += 1
    return points * k


def _friction(eps, top, sigma_max, half):
    """Berg's steady loop (:func:`core.loops.steady_friction_loop`'s branches) at the strains
    ``eps`` with turning points ±ε̂ at the samples ``top`` (the maximum) and ``top`` + M/2: the
    stress, its slope in ε and its derivative in ε̂ (Pa)."""
    n = eps.size
    amp = eps[top]
    x = float(friction_reversal_ratio(amp / half))
    dx = (1.0 - x) / (2.0 * x + 1.0 + amp / half) / half  # dx/dε̂ from x² + (1 + z)x − z = 0
    rising = ((np.arange(n) - top) % n) >= n // 2  # from the minimum (top + M/2) up to the top
    rising[top] = True
    s = np.where(rising, 1.0, -1.0)
    e = s * eps  # the falling branch is −σ_rising(−ε)
    w = half * (1.0 + x)
    d = w + amp + e
    # 1 − w(1 + x)/d without the cancellation at small strains: ε̂ − ε½x(1 + x) = ε̂x by x's equation
    stress = s * sigma_max * (amp * x + e) / d
    slope = sigma_max * w * (1.0 + x) / d**2
    by_amp = s * sigma_max * (-2.0 * half * (1.0 + x) * dx / d + w * (1.0 + x) * (half * dx + 1.0) / d**2)
    return stress, slope, by_amp


def steady_series_strain(design: Design, series: BulkSeries, frequency_hz: float, amplitude: float, points: int):
    """One steady period of the shear strain and the rubber's stresses for the drive
    x = x̂ sin θ through ``series`` (see the module's docstring).

    Returns
    -------
    tuple of numpy.ndarray
        (ε, σ_elastic, σ_viscoelastic, σ_friction) at θ = 2πk/``points``, k < ``points``:
        the strain (dimensionless) and the branches' stresses in Pa.

    Raises
    ------
    ConvergenceError
        If Newton's method does not meet :data:`TOLERANCE`, or the strain is not one rise and
        one fall a period.
    """
    from scipy.sparse.linalg import LinearOperator, gmres

    m = design.material
    effects = design.effect_parameters
    n = _grid(points)
    theta = 2.0 * np.pi * np.arange(n) / n
    drive = series.strain_factor * amplitude
    kappa = series.kappa
    harmonics = np.arange(n // 2 + 1)
    odd = harmonics % 2 == 1
    h = np.zeros(n // 2 + 1, dtype=complex)  # 2µ_ve at each odd harmonic (the branch is linear)
    h[odd] = 2.0 * branch_moduli(m, effects, frequency_hz * harmonics[odd], drive)["viscoelastic"]
    base = complex(friction_modulus(drive, m.friction_stress_max, m.friction_strain_half))
    scale = (complex(branch_moduli(m, effects, frequency_hz, drive)["friction"]) / base).real  # (f/10 Hz)^γ
    smax, half = m.friction_stress_max * scale, m.friction_strain_half
    beta = effects.get("strain_stiffening", {}).get("stiffening", 0.0)

    def odd_part(v):
        spec = np.fft.rfft(v)
        spec[~odd] = 0.0
        return spec

    def stresses(eps):
        top = int(np.argmax(eps))
        fr, slope, by_amp = _friction(eps, top, smax, half)
        ve = np.fft.irfft(h * odd_part(eps), n)
        return elastic_stress(m, eps, effects), ve, fr, (top, slope, by_amp)

    # the start: the linear series with the equivalent modulus at the drive's strain
    mu_eq = complex(sum(branch_moduli(m, effects, frequency_hz, drive).values()))
    eps = np.imag(drive * np.exp(1j * theta) / (1.0 + 2.0 * kappa * mu_eq))
    target = drive * np.sin(theta)
    for it in range(MAX_NEWTON):
        el, ve, fr, (top, slope, by_amp) = stresses(eps)
        residual = eps + kappa * (el + ve + fr) - target
        worst = float(np.max(np.abs(residual)))
        if worst <= TOLERANCE * drive:
            break
        local = kappa * (2.0 * m.shear_modulus * (1.0 + 3.0 * beta * eps**2) + slope)
        mean = float(np.mean(local))

        def jacobian(v, local=local, top=top, by_amp=by_amp):
            amp = 0.5 * (v[top] - v[(top + n // 2) % n])  # ε̂ moves with the top and the bottom
            return v + local * v + kappa * (np.fft.irfft(h * odd_part(v), n) + by_amp * amp)

        def preconditioner(v, mean=mean):
            return np.fft.irfft(np.fft.rfft(v) / (1.0 + mean + kappa * h), n)

        step, _ = gmres(LinearOperator((n, n), jacobian), -residual, rtol=1e-12, atol=0.0, restart=60,
                           maxiter=20, M=LinearOperator((n, n), preconditioner))
        eps = eps + np.fft.irfft(odd_part(step), n)  # the steady loop is odd: ε(θ + π) = −ε(θ)
    else:
        raise ConvergenceError(f"the steady loop through the bulk spring did not converge in {MAX_NEWTON} Newton "
                               f"iterations (residual {worst / drive:.2e} of the drive's strain)")
    rise = np.diff(np.roll(eps, -top - n // 2)[: n // 2 + 1])  # from the minimum to the top
    if np.any(rise < -1e-9 * drive):
        raise ConvergenceError("the steady loop through the bulk spring: the rubber's strain does not rise and fall "
                               "once a period")
    every = n // points
    return tuple(v[::every].copy() for v in (eps, el, ve, fr))


# ---- any sampled history through the series ----------------------------------------------


def series_history_strain(design: Design, series: BulkSeries, displacement, dt: float) -> np.ndarray:
    """The rubber's shear strain at every sample of the drive history ``displacement`` (m or rad,
    every ``dt`` s) through ``series``: ε + κσ[ε] = c x at once over the whole history, σ[ε] the
    material's branches along it (:func:`core.material.branch_stresses`: the fractional memory
    from rest, friction's reversals), by Newton's method with Krylov steps (finite differences of
    σ[ε] along each direction, so friction's reversal memory is followed as it is), to
    :data:`TOLERANCE` of the largest c|x|. Each residual is O(N log N); the steps are preconditioned
    by the linear part at rest, 1 + κ(2µ + σ_fmax/ε½ + m D^α), the fractional derivative by its
    Grünwald–Letnikov symbol in the frequency domain (the history padded to twice its length).

    Returns
    -------
    numpy.ndarray
        ε at each sample (dimensionless).

    Raises
    ------
    ConvergenceError
        If Newton's method does not meet the tolerance in :data:`MAX_NEWTON` iterations.
    """
    from scipy.optimize import NoConvergence, newton_krylov
    from scipy.sparse.linalg import LinearOperator

    from .material import branch_stresses

    m = design.material
    effects = design.effect_parameters
    target = series.strain_factor * np.asarray(displacement, dtype=float)
    scale = float(np.max(np.abs(target)))
    if scale == 0.0:
        return np.zeros_like(target)
    kappa = series.kappa

    def residual(eps):
        br = branch_stresses(m, eps, dt, effects)
        return eps + kappa * (br.elastic + br.fractional + br.friction) - target

    # the linear part at rest, 1 + κ(2µ + σ_fmax/ε½ + m D^α), in the frequency domain: the
    # Grünwald–Letnikov symbol dt^(−α)(1 − e^(−iω dt))^α on a grid padded to 2N (no wrap-around)
    n = target.size
    size = 2 * n
    z = np.exp(-2j * np.pi * np.arange(size // 2 + 1) / size)
    symbol = 1.0 + kappa * (2.0 * m.shear_modulus + m.friction_stress_max / m.friction_strain_half
                            + m.fractional_coefficient * dt ** -m.fractional_order * (1.0 - z) ** m.fractional_order)

    def precondition(v):
        return np.fft.irfft(np.fft.rfft(v, size) / symbol, size)[:n]

    start = precondition(target)
    try:
        return newton_krylov(residual, start, f_tol=TOLERANCE * scale, maxiter=MAX_NEWTON,
                             inner_M=LinearOperator((n, n), precondition), inner_inner_m=5)
    except NoConvergence as exc:
        worst = float(np.max(np.abs(residual(np.asarray(exc.args[0]))))) if exc.args else float("nan")
        raise ConvergenceError(f"the force history through the bulk spring did not converge in {MAX_NEWTON} Newton "
                               f"iterations (residual {worst / scale:.2e} of the drive's largest strain)") from None
