"""Bushing dynamic stiffness, hysteresis loops and force histories (eqs 10–18).

======== ================== ======================================================
symbol   name here          meaning
======== ================== ======================================================
ε_eq     strain_factor · x  equivalent strain for the drive x (eq 14 torsion, eq 15 axial)
K        shape_factor · µ   stiffness from the equivalent modulus (eq 17 torsion, eq 18 axial)
φ, d     amplitude          peak angle (rad, torsion) or peak displacement (m, axial)
======== ================== ======================================================

The drive x(t) (angle or displacement) maps to the equivalent strain ε_eq = c·x, the material
turns that into a stress σ(t), and the moment or force is F = S·σ / (2c), where S is the shape
factor, so that F = S·µ·x for a purely elastic material.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Literal

import numpy as np

from . import material as mat
from .design import Design
from .effects import EFFECTS, branch_moduli, extended_modulus, inertia_correction, wave_stiffness
from .response import ComplexStiffness, loss_factor
from .shape import shape_factor, strain_factor
from .slices import continuum_node_count, continuum_nodes, slice_nodes, solve_series

UNITS = {
    "axial": {"amplitude": "m", "stiffness": "N/m", "force": "N", "drive": "displacement"},
    "torsion": {"amplitude": "rad", "stiffness": "N·m/rad", "force": "N·m", "drive": "angle"},
    "radial": {"amplitude": "m", "stiffness": "N/m", "force": "N", "drive": "displacement"},
    "conical": {"amplitude": "rad", "stiffness": "N·m/rad", "force": "N·m", "drive": "angle"},
}

Route = Literal["analytic", "time-domain"]
ROUTES = ("analytic", "time-domain")


def factors(design: Design) -> tuple[float, float]:
    """(S, c) of a design: its shape factor and strain factor."""
    return (shape_factor(design.geometry, design.mode, design.shape),
            strain_factor(design.geometry, design.mode, design.shape))


# --------------------------------------------------------------------------------------------
# Grids and results
# --------------------------------------------------------------------------------------------


def _grid(name: str, values) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name}: give one or more values")
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(f"{name}: every value must be a positive finite number")
    return arr


def _readonly(arr: np.ndarray) -> np.ndarray:
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class StiffnessResult(ComplexStiffness):
    """Dynamic stiffness on an amplitude × frequency grid.

    ``stiffness[i, j]`` is the complex K at ``amplitude[i]`` and ``frequency_hz[j]``, in
    ``units["stiffness"]`` (N/m axially, N·m/rad in torsion). Arrays are read-only (they may
    come from the cache).
    """

    design: Design
    frequency_hz: np.ndarray
    amplitude: np.ndarray
    stiffness: np.ndarray
    slices: int | str
    route: str

    @property
    def mode(self) -> str:
        return self.design.mode

    @property
    def units(self) -> dict[str, str]:
        return {"frequency_hz": "Hz", **UNITS[self.mode]}

    def table(self) -> dict[str, np.ndarray]:
        """Flat columns in docs/files.md's order, amplitude by amplitude, each a frequency sweep."""
        amp, freq = np.meshgrid(self.amplitude, self.frequency_hz, indexing="ij")
        k = self.stiffness.ravel()
        return {
            "frequency_hz": freq.ravel(),
            "amplitude": amp.ravel(),
            "stiffness_real": k.real,
            "stiffness_imag": k.imag,
            "magnitude": np.abs(k),
            "loss_factor": loss_factor(k),
        }


# --------------------------------------------------------------------------------------------
# Stiffness
# --------------------------------------------------------------------------------------------


def _modulus_time_domain(material, effects, frequency_hz, strain_amplitude):
    """Time-domain route, point by point (for checks and small grids), broadcast like the
    analytic :func:`core.material.equivalent_modulus`."""
    f, e = np.broadcast_arrays(np.asarray(frequency_hz, float), np.asarray(strain_amplitude, float))
    out = np.empty(f.shape, dtype=complex)
    for idx in np.ndindex(f.shape):
        out[idx] = _time_domain_point(material, effects, float(f[idx]), float(e[idx]))
    return out


@functools.lru_cache(maxsize=4096)
def _time_domain_point(material, effects: tuple, frequency_hz: float, strain_amplitude: float):
    return mat.equivalent_modulus_time_domain(
        material, frequency_hz, strain_amplitude, effects={k: dict(v) for k, v in effects}
    ).modulus


def modulus_function(design: Design, route: str = "analytic"):
    """µ_eq(frequency_hz, strain_amplitude) of the design's material with its material-level
    effects, by the chosen route, broadcast over both arguments."""
    if route == "analytic":
        effects = design.effect_parameters
        if any(EFFECTS[e].term is not None for e in effects):
            return functools.partial(extended_modulus, design.material, effects)
        return functools.partial(mat.equivalent_modulus, design.material)
    if route == "time-domain":
        # the time-domain route simulates the material-level effects itself
        return functools.partial(_modulus_time_domain, design.material,
                                 tuple((e, p) for e, p in design.effects if "@" not in e))
    raise ValueError(f"route: must be one of {', '.join(ROUTES)}, got {route!r}")


# more slices than this add nothing the continuum does not give, at far more cost
MAX_SLICES = 1000


def _check_slices(slices) -> int | str:
    if slices == "continuum":
        return slices
    if isinstance(slices, bool) or not isinstance(slices, (int, np.integer)) or not 1 <= slices <= MAX_SLICES:
        raise ValueError(f"slices: must be a whole number from 1 to {MAX_SLICES} or 'continuum' (the limit of "
                         f"many slices), got {slices!r}")
    return int(slices)


def slice_count(design: Design, slices: int | str = 1) -> int:
    """How many layers a stiffness evaluation with ``slices`` solves in series for ``design``
    (the continuum's quadrature nodes for ``"continuum"``): the work per point."""
    slices = _effective_slices(design, _check_slices(slices))
    return continuum_node_count(design.geometry, design.mode) if slices == "continuum" else int(slices)


def _check_series(design: Design, slices: int | str) -> None:
    """Slices, the continuum and standing waves are derived for the thesis' axial and torsion
    bushings (long shape factors): refuse them elsewhere rather than guess."""
    series = slices != 1 or "wave_effects" in design.effect_parameters
    if series and (design.mode not in ("axial", "torsion") or design.shape_kind != "long"):
        what = "slices, the continuum, nonuniform_strain and wave_effects"
        raise ValueError(f"{what} are derived for axial and torsion bushings with the long (closed-form) shape "
                         f"factors; this design is {design.mode} with the {design.shape_kind} shape")


def _effective_slices(design: Design, slices: int | str) -> int | str:
    """The continuum where one slice is asked of a design with the nonuniform_strain effect."""
    return "continuum" if slices == 1 and "nonuniform_strain" in design.effect_parameters else slices


MAX_STRAIN = 10.0  # equivalent strain amplitude: 1000 %, far past any rubber's breaking strain
# the smallest measured equivalent strain amplitude: below any test rig's resolution (for 15 mm of
# rubber, 15 pm); a measurement claiming less has its units wrong
MIN_MEASURED_STRAIN = 1e-9


def check_strain(design: Design, amplitude, what: str = "amplitude") -> None:
    """Refuse drive amplitudes whose equivalent strain is beyond :data:`MAX_STRAIN`: no rubber
    survives them, and the formulas' numbers stop being meaningful long before floats fail."""
    x = np.asarray(amplitude, dtype=float)
    c = strain_factor(design.geometry, design.mode, design.shape)
    if x.size and float(np.max(c * x)) > MAX_STRAIN:
        unit = UNITS[design.mode]["amplitude"]
        largest = MAX_STRAIN / c
        raise ValueError(f"{what}: at most {largest:.4g} {unit} for this bushing (an equivalent strain of "
                         f"{MAX_STRAIN:g}, {100 * MAX_STRAIN:g} %); got {float(np.max(x)):.4g} {unit}")


def check_measured_amplitude(design: Design, amplitude, what: str = "measured amplitude") -> None:
    """Measured amplitudes must be within what a test can drive and resolve for this bushing:
    equivalent strains from :data:`MIN_MEASURED_STRAIN` to :data:`MAX_STRAIN`."""
    check_strain(design, amplitude, what)
    x = np.asarray(amplitude, dtype=float)
    c = strain_factor(design.geometry, design.mode, design.shape)
    if x.size and float(np.min(c * x)) < MIN_MEASURED_STRAIN:
        unit = UNITS[design.mode]["amplitude"]
        raise ValueError(f"{what}: at least {MIN_MEASURED_STRAIN / c:.3g} {unit} for this bushing (an equivalent "
                         f"strain of {MIN_MEASURED_STRAIN:g}, below any test's resolution); got "
                         f"{float(np.min(x)):.3g} {unit}: are the units those of docs/files.md (m or rad)?")


def stiffness_points(design: Design, frequency_hz, amplitude, *, slices: int | str = 1,
                     route: Route = "analytic") -> np.ndarray:
    """Complex stiffness at paired points (frequency_hz[i], amplitude[i]), broadcast together:
    for measured data, which is no grid. Same model and options as :func:`stiffness`; no cache.
    """
    # broadcast, not expanded: on a grid (F,) × (A, 1) the friction term is evaluated per
    # amplitude and the fractional term per frequency, not at every point
    f, x = np.asarray(frequency_hz, float), np.asarray(amplitude, float)
    shape = np.broadcast_shapes(f.shape, x.shape)
    slices = _check_slices(slices)
    if route not in ROUTES:
        raise ValueError(f"route: must be one of {', '.join(ROUTES)}, got {route!r}")
    geo, mode = design.geometry, design.mode
    check_strain(design, x)
    effects = design.effect_parameters
    modulus = modulus_function(design, route)
    s, c = factors(design)
    slices = _effective_slices(design, slices)
    _check_series(design, slices)
    if "wave_effects" in effects:
        if slices != 1:
            raise ValueError(
                "effects.wave_effects: standing waves are computed for the single equivalent "
                "modulus; they cannot be combined with slices, the continuum or nonuniform_strain"
            )
        k = wave_stiffness(mode, geo.inner_radius, geo.outer_radius, geo.length,
                           modulus(f, c * x), f, effects["wave_effects"]["density"])
    elif slices == 1:
        k = s * modulus(f, c * x)  # eqs 16–18
    else:
        nodes = continuum_nodes(geo, mode) if slices == "continuum" else slice_nodes(geo, mode, slices)
        fp, xp = (np.broadcast_to(v, shape).ravel() for v in (f, x))
        k = solve_series(nodes, drive=xp, modulus=lambda eps: modulus(fp[:, None], eps),
                         strain_guess=c * xp).reshape(shape)
    if "inertia" in effects:
        k = inertia_correction(k, f, effects["inertia"]["mass"])
    k = np.broadcast_to(k, shape)
    if not np.all(np.isfinite(k)):
        raise ValueError("the stiffness is not finite at these points (check the design's effects)")
    return np.array(k)


@functools.lru_cache(maxsize=128)
def _stiffness_cached(design: Design, freq: tuple, amp: tuple, slices, route) -> StiffnessResult:
    f = np.array(freq)
    x = np.array(amp)
    slices = _effective_slices(design, slices)
    k = stiffness_points(design, f[None, :], x[:, None], slices=slices, route=route)
    return StiffnessResult(design, _readonly(f), _readonly(x), _readonly(np.array(k)), slices, route)


def stiffness(
    design: Design,
    frequency_hz,
    amplitude,
    *,
    slices: int | str = 1,
    route: Route = "analytic",
) -> StiffnessResult:
    """Dynamic stiffness K(ω, x̂) of the bushing on the grid amplitude × frequency.

    Parameters
    ----------
    design : the bushing (mode, geometry, material).
    frequency_hz : frequencies in Hz (one or more, > 0).
    amplitude : drive amplitudes, peak angle in rad (torsion) or peak displacement in m (axial).
    slices : 1 for the single equivalent modulus (eqs 14–18); N > 1 for N concentric slices of
        equal radial thickness in series (Paper A); ``"continuum"`` for the limit N → ∞.
        A design with the ``nonuniform_strain`` effect uses the continuum where 1 is asked.
    route : ``"analytic"`` (closed-form steady state, fast) or ``"time-domain"`` (the thesis'
        simulation of the strain history, point by point; slow, for checks).

    Returns a :class:`StiffnessResult`; repeated queries come from a bounded cache.
    Raises :class:`core.material.ConvergenceError` if an iteration does not converge.
    """
    f = _grid("frequency_hz", frequency_hz)
    x = _grid("amplitude", amplitude)
    slices = _check_slices(slices)
    if route not in ROUTES:
        raise ValueError(f"route: must be one of {', '.join(ROUTES)}, got {route!r}")
    return _stiffness_cached(design, tuple(f.tolist()), tuple(x.tolist()), slices, route)


def branch_stiffness(design: Design, frequency_hz, amplitude) -> dict[str, np.ndarray]:
    """K split by branch (single equivalent modulus, eqs 16–18), each on the amplitude ×
    frequency grid: ``elastic`` S·µ (with ``strain_stiffening``), ``viscoelastic``
    S·(m(iω)^α/2 + iωc/2) (with ``viscous``), ``friction`` S·µ_f(ε̂) (with
    ``rate_amplitude_coupling``). Their sum is :func:`stiffness` for a design without
    stiffness-level effects (inertia, waves, non-uniform strain), which are refused here.
    """
    _refuse_structural_effects(design, "the branch-by-branch stiffness")
    f = _grid("frequency_hz", frequency_hz)[None, :]
    x = _grid("amplitude", amplitude)[:, None]
    s, c = factors(design)
    eps = c * x
    return {name: s * modulus for name, modulus in
            branch_moduli(design.material, design.effect_parameters, f, eps).items()}


def cache_info():
    """Hits and misses of the stiffness cache (a functools.lru_cache, bounded)."""
    return _stiffness_cached.cache_info()


# --------------------------------------------------------------------------------------------
# Hysteresis loop and force histories
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class LoopResult:
    """One steady period of the hysteresis loop: drive x(θ) = x̂ sin θ, θ = 2πk/N, k < N.

    Forces in N (axial) or N·m (torsion), displacement in m or rad.
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
        return UNITS[self.design.mode]

    def table(self) -> dict[str, np.ndarray]:
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
    period (the same convergence rule as the time-domain modulus).
    """
    f = float(_grid("frequency_hz", frequency_hz)[0])
    xa = float(_grid("amplitude", amplitude)[0])
    check_strain(design, xa)
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 4:
        raise ValueError(f"points: must be a whole number ≥ 4, got {points!r}")
    _refuse_structural_effects(design, "the branch-by-branch hysteresis loop")
    theta = 2.0 * np.pi * np.arange(points) / points
    if route == "analytic":
        forces = loop_force(design, f, xa, theta)
    elif route == "time-domain":
        s, c = factors(design)
        scale = s / (2.0 * c)  # F = S σ / (2c)
        stresses = _time_domain_loop(design.material, design.effect_parameters, f, c * xa, points)
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
    s, c = factors(design)
    scale = s / (2.0 * c)  # F = S σ / (2c)
    eps_amp = c * amplitude
    theta = np.asarray(phase, dtype=float)
    eps = eps_amp * np.sin(theta)
    moduli = branch_moduli(m, effects, frequency_hz, eps_amp)
    el = 2.0 * m.shear_modulus * eps * (1.0 + effects.get("strain_stiffening", {}).get("stiffening", 0.0) * eps**2)
    fr = np.imag(2.0 * complex(moduli["viscoelastic"]) * eps_amp * np.exp(1j * theta))
    fric = steady_friction_loop(eps_amp, theta, m.friction_stress_max, m.friction_strain_half)
    base_friction = mat.friction_modulus(eps_amp, m.friction_stress_max, m.friction_strain_half)
    fric = fric * (complex(moduli["friction"]) / complex(base_friction)).real
    return scale * el, scale * fr, scale * fric


STRUCTURAL_EFFECTS = ("inertia", "nonuniform_strain", "wave_effects")


def material_model(design: Design) -> Design:
    """``design`` without its stiffness-level effects (:data:`STRUCTURAL_EFFECTS`): the material
    model with its material-level effects, for loops and branch-by-branch views."""
    kept = {eid: p for eid, p in design.effect_parameters.items() if eid not in STRUCTURAL_EFFECTS}
    return design if len(kept) == len(design.effects) else design.replace(effects=kept)


def _refuse_structural_effects(design: Design, what: str, allowed=()):
    for eid in STRUCTURAL_EFFECTS:
        if eid in design.effect_parameters and eid not in allowed:
            raise ValueError(
                f"effects.{eid}: {what} is computed from the material branches; it is not "
                f"available for a design with this effect (use the stiffness instead)"
            )


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
    """Force (moment) history for a sampled displacement (angle) history, branch by branch."""

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
    """Force (N) or moment (N·m) for any displacement (m) or angle (rad) history sampled every
    ``dt`` seconds, e.g. from a multibody simulation. O(N log N): the fractional memory is an
    FFT convolution (eq 3), the friction state changes only at reversals (eq 6).

    The history starts from rest in the virgin state at zero displacement; a first sample away
    from zero is reached by a step from zero. Material-level effects are simulated (except
    ``rate_amplitude_coupling``, defined for harmonic drives only); ``inertia`` adds M·d²x/dt²
    to the total force; ``nonuniform_strain`` and ``wave_effects`` are refused.
    """
    x = np.asarray(displacement, dtype=float)
    if x.ndim != 1 or x.size == 0 or not np.all(np.isfinite(x)):
        raise ValueError("displacement: give a one-dimensional array of finite numbers")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt: must be a positive finite number, got {dt!r}")
    _refuse_structural_effects(design, "the force history", allowed=("inertia",))
    effects = design.effect_parameters
    s, c = factors(design)
    scale = s / (2.0 * c)
    br = mat.branch_stresses(design.material, c * x, dt, effects)
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
