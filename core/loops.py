"""Hysteresis loops and force histories of a bushing, branch by branch (eqs 1–7, 14–18).

The drive x(t) (angle or displacement) maps to the equivalent strain ε_eq = c·x
(:meth:`Design.strain`), the material turns that into a stress σ(t) (:mod:`core.material`), and
the moment or force is F = S·σ / (2c) (:func:`force_per_stress`), where S is the shape factor, so
that F = S·µ·x for a purely elastic material. A compressible rubber (a bulk modulus in a
direction that squeezes it) is a shear layer in series with an elastic bulk spring
(:mod:`core.compressible`): its loop is that series' steady period, the rubber's strain no
longer c·x.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import material as mat
from .bushing import (
    ROUTES,
    Route,
    check_strain,
    material_model,
    modulus_function,
    positive_values,
    refuse_structural_effects,
)
from .compressible import (
    history_point,
    in_series,
    series_at,
    series_history_strain,
    steady_series_strain,
)
from .design import Design
from .effects import branch_moduli
from .parameters import MODE


def force_per_stress(design: Design) -> float:
    """S / (2c): the force (N) or moment (N·m) per unit stress (Pa) of the material's branches,
    F = S·σ / (2c), so that F = S·µ·x for a purely elastic material (σ = 2µε, ε = c·x)."""
    return design.shape_factor / (2.0 * design.strain_factor)


@dataclass(frozen=True, eq=False)
class LoopResult:
    """One steady period of the hysteresis loop: drive x(θ) = x̂ sin θ, θ = 2πk/N, k < N.

    Attributes
    ----------
    design : Design
        The bushing the loop is of.
    frequency_hz : float
        The drive frequency in Hz.
    amplitude : float
        The drive amplitude x̂: peak displacement in m (axial, radial) or peak angle in rad
        (torsion, conical).
    phase : numpy.ndarray
        The drive phases θ = 2πk/N, shape (N,), in rad.
    displacement : numpy.ndarray
        The drive x̂ sin θ, shape (N,), in m or rad.
    force_elastic : numpy.ndarray
        The elastic branch's force, shape (N,), in N (axial, radial) or moment in N·m (torsion,
        conical).
    force_viscoelastic : numpy.ndarray
        The viscoelastic (fractional, and any viscous) branch's force, in N or N·m.
    force_friction : numpy.ndarray
        The friction branch's force, in N or N·m.
    force : numpy.ndarray
        The total force, the sum of the three branches, in N or N·m.
    units : dict of str to str
        The unit of each quantity: ``amplitude`` m or rad, ``stiffness`` N/m or N·m/rad,
        ``force`` N or N·m, and ``drive`` (displacement or angle).
    """

    design: Design
    frequency_hz: float
    amplitude: float
    phase: np.ndarray
    displacement: np.ndarray
    force_elastic: np.ndarray
    force_viscoelastic: np.ndarray
    force_friction: np.ndarray

    @property
    def force(self) -> np.ndarray:
        return self.force_elastic + self.force_viscoelastic + self.force_friction

    @property
    def units(self) -> dict[str, str]:
        return MODE[self.design.mode].units

    def table(self) -> dict[str, np.ndarray]:
        """The loop's columns: the drive, the total force and each branch's.

        Returns
        -------
        dict of str to numpy.ndarray
            ``displacement`` in m or rad; ``force``, ``force_elastic``, ``force_viscoelastic``
            and ``force_friction`` in N or N·m; N values each.
        """
        return {
            "displacement": self.displacement,
            "force": self.force,
            "force_elastic": self.force_elastic,
            "force_viscoelastic": self.force_viscoelastic,
            "force_friction": self.force_friction,
        }


def steady_friction_loop(strain_amplitude: float, phase, friction_stress_max, friction_strain_half):
    """Steady Berg friction stress along ε = ε̂ sin θ, in closed form (docs/model.md, route 2).

    Rising branch (cos θ ≥ 0): σ = σ_fmax [1 − ε½ (1 + x)² / (ε½ (1 + x) + ε̂ + ε)];
    falling branch: σ(ε) = −σ_rising(−ε); x from :func:`core.material.friction_reversal_ratio`.
    """
    phase = np.asarray(phase, dtype=float)
    eps = strain_amplitude * np.sin(phase)
    x = mat.friction_reversal_ratio(strain_amplitude / friction_strain_half)
    h = friction_strain_half
    rising = np.cos(phase) >= 0.0
    e = np.where(rising, eps, -eps)
    branch = friction_stress_max * (1.0 - h * (1.0 + x) ** 2 / (h * (1.0 + x) + strain_amplitude + e))
    return np.where(rising, branch, -branch)


def loop_model(design: Design) -> Design:
    """The design whose :func:`loop` a view draws for ``design``: its material model
    (:func:`core.bushing.material_model`: stiffness-level effects have no branches), keeping the
    bulk modulus where it acts as a spring in series (:func:`core.compressible.in_series`), whose
    loop :func:`loop` follows."""
    model = material_model(design)
    return model.replace(bulk_modulus=design.material.bulk_modulus) if in_series(design) else model


def loop(
    design: Design,
    frequency_hz: float,
    amplitude: float,
    points: int = 256,
    *,
    route: Route = "analytic",
) -> LoopResult:
    """One steady period of force (moment) against displacement (angle), branch by branch.

    ``route="analytic"`` builds the steady loop in closed form (elastic line, the fractional
    ellipse Im(m(iω)^α ε̂ e^{iθ}), the Berg loop of :func:`steady_friction_loop`);
    ``route="time-domain"`` simulates from rest until the steady state and returns the last
    period (the same convergence rule as the time-domain modulus). The force is F = S·σ / (2c)
    of the material's stresses (:func:`force_per_stress`, eqs 14–18). A design whose bulk
    modulus squeezes the rubber (radial, conical, finite axial) is a shear layer in series with
    a bulk spring (:func:`core.compressible.series_at`; the long radial closed form's matched at
    this frequency and amplitude): the steady period of that series
    (:func:`core.compressible.steady_series_strain`), the branches at the rubber's own strain,
    by the analytic route only.

    Parameters
    ----------
    design : Design
        The bushing; stiffness-level effects (inertia, non-uniform strain, standing waves) are
        refused: a loop shows the material's branches.
    frequency_hz : float
        The drive frequency in Hz, positive.
    amplitude : float
        The drive amplitude x̂, positive: peak displacement in m (axial, radial) or peak angle
        in rad (torsion, conical).
    points : int, default 256
        Samples per period, at least 4.
    route : {'analytic', 'time-domain'}, default 'analytic'
        The closed-form steady loop, or the simulated one.

    Returns
    -------
    LoopResult
        The drive in m or rad and the forces in N or N·m (moments), at the phases θ = 2πk/N.

    Raises
    ------
    ValueError
        If the frequency or amplitude is not positive, the amplitude is beyond the equivalent
        strain :data:`core.bushing.MAX_STRAIN`, ``points`` or ``route`` is not allowed (the
        time-domain route with a bulk spring), or the design has a stiffness-level effect.
    ConvergenceError
        If the time-domain route or the series solve does not reach its steady state.
    """
    f = float(positive_values("frequency_hz", frequency_hz)[0])
    xa = float(positive_values("amplitude", amplitude)[0])
    check_strain(design, xa)
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 4:
        raise ValueError(f"points: must be a whole number ≥ 4, got {points!r}")
    refuse_structural_effects(design, "the branch-by-branch hysteresis loop")
    theta = 2.0 * np.pi * np.arange(points) / points
    series = series_at(design, modulus_function(design), f, xa, "the hysteresis loop")
    if series is not None:
        if route != "analytic":
            raise ValueError(f"route: the loop through a bulk spring in series is solved in its steady state "
                             f"(route 'analytic'), got {route!r}")
        _, *stresses = steady_series_strain(design, series, f, xa, points)
        scale = series.shape_factor / (2.0 * series.strain_factor)
        forces = tuple(scale * part for part in stresses)
    elif route == "analytic":
        forces = loop_force(design, f, xa, theta)
    elif route == "time-domain":
        scale = force_per_stress(design)
        stresses = _time_domain_loop(design.material, design.effect_parameters, f, design.strain(xa), points)
        forces = tuple(scale * part for part in stresses)
    else:
        raise ValueError(f"route: must be one of {', '.join(ROUTES)}, got {route!r}")
    return LoopResult(design, f, xa, theta, xa * np.sin(theta), *forces)


def loop_force(design: Design, frequency_hz: float, amplitude: float, phase):
    """Steady force (moment) branches at the drive phases θ, x = x̂ sin θ, in closed form:
    (elastic, viscoelastic, friction), each in N or N·m. The viscoelastic branch is linear:
    Im(2 µ_ve ε̂ e^{iθ}) with its branch modulus µ_ve (:func:`core.effects.branch_moduli`: the
    fractional term and any viscous one). The friction branch is the steady Berg loop scaled as
    its branch modulus is by the effects (µ_f → µ_f (f/10 Hz)^γ). The elastic branch is the
    waveform 2µε(1 + βε²) with strain stiffening (its first harmonic is the elastic branch
    modulus µ(1 + ¾βε̂²); the third harmonic the closed form leaves out is drawn here)."""
    m = design.material
    effects = design.effect_parameters
    scale = force_per_stress(design)
    eps_amp = design.strain(amplitude)
    theta = np.asarray(phase, dtype=float)
    eps = eps_amp * np.sin(theta)
    moduli = branch_moduli(m, effects, frequency_hz, eps_amp)
    el = mat.elastic_stress(m, eps, effects)
    fr = np.imag(2.0 * complex(moduli["viscoelastic"]) * eps_amp * np.exp(1j * theta))
    fric = steady_friction_loop(eps_amp, theta, m.friction_stress_max, m.friction_strain_half)
    base_friction = mat.friction_modulus(eps_amp, m.friction_stress_max, m.friction_strain_half)
    fric = fric * (complex(moduli["friction"]) / complex(base_friction)).real
    return scale * el, scale * fr, scale * fric



SERIES_SAMPLES = 2048  # the phases of the series' steady period a measured loop's phases are read from


def steady_loop_force(design: Design, frequency_hz: float, amplitude: float, phase):
    """Steady force (moment) branches at any drive phases θ, x = x̂ sin θ, of the model a
    measured loop is compared with: (elastic, viscoelastic, friction), each in N or N·m.
    :func:`loop_force` in closed form; where a bulk modulus acts as a spring in series
    (:func:`core.compressible.series_at`, as :func:`loop`), the series' steady period
    (:func:`core.compressible.steady_series_strain`) on :data:`SERIES_SAMPLES` phases, read at
    ``phase`` by periodic linear interpolation (within about 10⁻⁶ of the force's range)."""
    series = series_at(design, modulus_function(design), frequency_hz, amplitude, "the loop's force at measured phases")
    if series is None:
        return loop_force(design, frequency_hz, amplitude, phase)
    _, *stresses = steady_series_strain(design, series, frequency_hz, amplitude, SERIES_SAMPLES)
    scale = series.shape_factor / (2.0 * series.strain_factor)
    grid = 2.0 * np.pi * np.arange(SERIES_SAMPLES) / SERIES_SAMPLES
    theta = np.mod(np.asarray(phase, dtype=float), 2.0 * np.pi)
    return tuple(scale * np.interp(theta, grid, part, period=2.0 * np.pi) for part in stresses)


def _time_domain_loop(material, effects, frequency_hz, eps_amp, points):
    """Last period of the simulated stresses, on the loop's phase grid θ = 2πk/points."""
    td = mat.equivalent_modulus_time_domain(material, frequency_hz, eps_amp, effects=effects)
    n_p = max(td.samples_per_period, points)
    n_p = int(points * -(-n_p // points))  # a multiple of points
    n = td.periods * n_p
    theta = 2.0 * np.pi * np.arange(1, n + 1) / n_p
    br = mat.branch_stresses(
        material, eps_amp * np.sin(theta), 1.0 / (frequency_hz * n_p), effects, frequency_hz
    )
    # last period, starting at θ ≡ 0: samples n − n_p … n − 1 are θ = 2π(k + 1)/n_p; take
    # the sample with k + 1 ≡ 0 first
    last = slice(n - n_p - 1, n - 1)
    step = n_p // points
    return (br.elastic[last][::step], br.fractional[last][::step], br.friction[last][::step])


@dataclass(frozen=True, eq=False)
class HistoryResult:
    """Force (moment) history for a sampled displacement (angle) history, branch by branch.

    Attributes
    ----------
    design : Design
        The bushing the history is of.
    time_s : numpy.ndarray
        The sample times, shape (N,), in s, from 0.
    displacement : numpy.ndarray
        The drive, shape (N,): displacement in m (axial, radial) or angle in rad (torsion,
        conical).
    force_elastic : numpy.ndarray
        The elastic branch's force, shape (N,), in N (axial, radial) or moment in N·m (torsion,
        conical).
    force_viscoelastic : numpy.ndarray
        The viscoelastic (fractional, and any viscous) branch's force, in N or N·m.
    force_friction : numpy.ndarray
        The friction branch's force, in N or N·m.
    force_inertia : numpy.ndarray
        M·d²x/dt² of the ``inertia`` effect (zero without it), in N or N·m.
    force : numpy.ndarray
        The total force, the sum of the four parts, in N or N·m.
    """

    design: Design
    time_s: np.ndarray
    displacement: np.ndarray
    force_elastic: np.ndarray
    force_viscoelastic: np.ndarray
    force_friction: np.ndarray
    force_inertia: np.ndarray  # M·d²x/dt² of the ``inertia`` effect, zero without it

    @property
    def force(self) -> np.ndarray:
        return self.force_elastic + self.force_viscoelastic + self.force_friction + self.force_inertia


def force_history(design: Design, displacement, dt: float) -> HistoryResult:
    """Force (N) or moment (N·m) for any displacement (m) or angle (rad) history.

    For a history sampled every ``dt`` seconds, e.g. from a multibody simulation. O(N log N):
    the fractional memory is an FFT convolution (eq 3), the friction state changes only at
    reversals (eq 6). A bulk modulus that squeezes the rubber (radial, conical, a finite axial
    bushing) is a bulk spring in series (:mod:`core.compressible`): the rubber's strain along the
    whole history solves ε + κσ[ε] = c x (:func:`core.compressible.series_history_strain`, a few
    Newton steps of such residuals), and F = S σ/(2c) of the series' shear layer; the long radial
    closed form's series is matched at the history's dominant frequency and peak drive
    (:func:`core.compressible.history_point`).

    Parameters
    ----------
    design : Design
        The bushing. Material-level effects are simulated (except ``rate_amplitude_coupling``,
        defined for harmonic drives only); ``inertia`` adds M·d²x/dt² to the total force;
        ``nonuniform_strain`` and ``wave_effects`` are refused.
    displacement : array_like
        The drive history, one-dimensional: displacement in m (axial, radial) or angle in rad
        (torsion, conical).
    dt : float
        The sampling interval in s, positive.

    Returns
    -------
    HistoryResult
        The force (N) or moment (N·m) at each sample, branch by branch.

    Raises
    ------
    ValueError
        If ``displacement`` is not a one-dimensional array of finite numbers, ``dt`` is not a
        positive finite number, the design has a refused effect, or it has
        ``rate_amplitude_coupling``.
    ConvergenceError
        If the series with a bulk spring (:func:`core.compressible.series_history_strain`) does
        not converge.

    Notes
    -----
    The history starts from rest in the virgin state at zero displacement; a first sample away
    from zero is reached by a step from zero.
    """
    x = np.asarray(displacement, dtype=float)
    if x.ndim != 1 or x.size == 0 or not np.all(np.isfinite(x)):
        raise ValueError("displacement: give a one-dimensional array of finite numbers")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt: must be a positive finite number, got {dt!r}")
    refuse_structural_effects(design, "the force history", allowed=("inertia",))
    effects = design.effect_parameters
    series = None
    if in_series(design) and np.any(x):  # the long radial closed form's matched at the history's own point
        series = series_at(design, modulus_function(design), *history_point(x, dt), "the force history")
    if series is None:
        scale, strain = force_per_stress(design), design.strain(x)
    else:  # the rubber's strain through the bulk spring in series, the whole history at once
        scale, strain = series.shape_factor / (2.0 * series.strain_factor), series_history_strain(design, series, x, dt)
    br = mat.branch_stresses(design.material, strain, dt, effects)
    inertial = np.zeros_like(x)
    if "inertia" in effects:  # from rest at zero: x_{-1} = x_{-2} = 0
        padded = np.concatenate(([0.0, 0.0], x))
        inertial = effects["inertia"]["mass"] * np.diff(padded, 2) / dt**2
    return HistoryResult(
        design,
        dt * np.arange(x.size),
        x,
        scale * br.elastic,
        scale * br.fractional,
        scale * br.friction,
        inertial,
    )
