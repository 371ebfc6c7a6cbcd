"""Bushing dynamic stiffness on a frequency × amplitude grid (eqs 14–18); the hysteresis loops
and force histories are in :mod:`core.loops`.

======== ================== ======================================================
symbol   name here          meaning
======== ================== ======================================================
ε_eq     strain_factor · x  equivalent strain for the drive x (eq 14 torsion, eq 15 axial)
K        shape_factor · µ   stiffness from the equivalent modulus (eq 17 torsion, eq 18 axial)
φ, d     amplitude          peak angle (rad, torsion) or peak displacement (m, axial)
======== ================== ======================================================

The drive amplitude x̂ maps to the equivalent strain amplitude ε_eq = c·x̂ (:meth:`Design.strain`),
the material gives µ_eq(ω, ε_eq) (eq 16) and K = S·µ_eq (:func:`equivalent_stiffness`); slices,
the continuum (:mod:`core.slices`) and the stiffness-level effects (:mod:`core.effects`) refine it.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Literal

import numpy as np

from . import material as mat
from .compressible import BulkCorrection
from .design import Design
from .effects import EFFECTS, branch_moduli, extended_modulus, inertia_correction, wave_stiffness
from .parameters import MODE, THESIS_MODES
from .response import ComplexStiffness, loss_factor
from .shape import bulk_factor, pure_shear, shape_factor, strain_factor  # noqa: F401 (re-exported)
from .slices import continuum_node_count, continuum_nodes, slice_nodes, solve_series

Route = Literal["analytic", "time-domain"]
ROUTES = ("analytic", "time-domain")


def factors(design: Design) -> tuple[float, float]:
    """(S, c) of a design: its shape factor and strain factor (:attr:`Design.shape_factor`,
    :attr:`Design.strain_factor`)."""
    return design.shape_factor, design.strain_factor


# --------------------------------------------------------------------------------------------
# Grids and results
# --------------------------------------------------------------------------------------------


def positive_values(name: str, values) -> np.ndarray:
    """``values`` as a 1-d float array of one or more positive finite numbers, or ValueError
    naming ``name``."""
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
    """Dynamic stiffness on an amplitude × frequency grid, as :func:`stiffness` gives it.

    ``stiffness[i, j]`` is the complex K at ``amplitude[i]`` and ``frequency_hz[j]``, in
    ``units["stiffness"]``. Arrays are read-only (they may come from the cache).

    Attributes
    ----------
    design : Design
        The bushing the stiffness is of.
    frequency_hz : numpy.ndarray
        The frequencies, shape (F,), in Hz.
    amplitude : numpy.ndarray
        The drive amplitudes, shape (A,): peak displacement in m (axial, radial) or peak angle
        in rad (torsion, conical).
    stiffness : numpy.ndarray
        Complex dynamic stiffness K, shape (A, F), in N/m (axial, radial) or N·m/rad (torsion,
        conical).
    slices : int or {'continuum'}
        How the rubber was solved: 1 for the single equivalent modulus (eqs 17, 18), N for N
        slices in series, ``"continuum"`` for the limit.
    route : {'analytic', 'time-domain'}
        How the equivalent modulus was computed.
    mode : str
        The design's mode.
    units : dict of str to str
        The unit of each quantity: ``frequency_hz`` Hz, ``amplitude`` m or rad, ``stiffness``
        N/m or N·m/rad, ``force`` N or N·m, and ``drive`` (what the amplitude is: displacement
        or angle).
    magnitude : numpy.ndarray
        |K|, shape (A, F), in N/m or N·m/rad.
    loss_factor : numpy.ndarray
        Im K / Re K, shape (A, F), dimensionless.
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
        return {"frequency_hz": "Hz", **MODE[self.mode].units}

    def table(self) -> dict[str, np.ndarray]:
        """Flat columns in docs/files.md's order, amplitude by amplitude, each a frequency sweep.

        Returns
        -------
        dict of str to numpy.ndarray
            A·F values each: ``frequency_hz`` in Hz, ``amplitude`` in m or rad,
            ``stiffness_real``, ``stiffness_imag`` and ``magnitude`` in N/m or N·m/rad,
            ``loss_factor`` dimensionless.
        """
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
    if series and (design.mode not in THESIS_MODES or design.shape_kind != "long"):
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
    if x.size and float(np.max(design.strain(x))) > MAX_STRAIN:
        unit = MODE[design.mode].amplitude.si
        largest = design.drive(MAX_STRAIN)
        raise ValueError(f"{what}: at most {largest:.4g} {unit} for this bushing (an equivalent strain of "
                         f"{MAX_STRAIN:g}, {100 * MAX_STRAIN:g} %); got {float(np.max(x)):.4g} {unit}")


def check_measured_amplitude(design: Design, amplitude, what: str = "measured amplitude") -> None:
    """Measured amplitudes must be within what a test can drive and resolve for this bushing:
    equivalent strains from :data:`MIN_MEASURED_STRAIN` to :data:`MAX_STRAIN`."""
    check_strain(design, amplitude, what)
    x = np.asarray(amplitude, dtype=float)
    if x.size and float(np.min(design.strain(x))) < MIN_MEASURED_STRAIN:
        unit = MODE[design.mode].amplitude.si
        smallest = design.drive(MIN_MEASURED_STRAIN)
        raise ValueError(f"{what}: at least {smallest:.3g} {unit} for this bushing (an equivalent "
                         f"strain of {MIN_MEASURED_STRAIN:g}, below any test's resolution); got "
                         f"{float(np.min(x)):.3g} {unit}: are the units those of docs/files.md (m or rad)?")


def equivalent_stiffness(modulus, s, c, frequency_hz, amplitude, bulk=None):
    """K = S·µ_eq(f, ε_eq) at ε_eq = c·x̂: the single equivalent modulus (eqs 14–18), broadcast
    over every argument. ``modulus`` is µ_eq(frequency_hz, strain_amplitude) in Pa (e.g.
    :func:`modulus_function`'s, or :func:`core.material.equivalent_modulus` of a material);
    ``s`` the shape factor (m or m³/rad) and ``c`` the strain factor (1/m or 1/rad). S, c and the
    parameters inside ``modulus`` may be arrays, e.g. one value per Monte Carlo sample shaped
    (n, 1, …) against the points; the drive ``amplitude`` is in m or rad.

    ``bulk``: a compressible rubber's :class:`core.compressible.BulkCorrection`
    (:func:`bulk_correction`), or None. Then K = S·µ*·S(µ*/K)/S with µ* = µ_eq(f, ε̂) at the
    rubber's own strain amplitude ε̂ = c·x̂·|√ψ(µ*/K)|, solved point by point
    (:meth:`~core.compressible.BulkCorrection.rubber_modulus`, docs/model.md "Compressibility"):
    the bulk spring takes its share of the drive."""
    if bulk is None:
        return s * modulus(frequency_hz, c * amplitude)  # eqs 14, 15 inside; eqs 17, 18
    _, mu = bulk.rubber_modulus(modulus, frequency_hz, c * amplitude)
    return s * mu * bulk.factor(mu)


def bulk_correction(design: Design, bulk_modulus=None) -> BulkCorrection | None:
    """A compressible rubber's correction of K = S·µ_eq, by the correspondence principle
    (:class:`core.compressible.BulkCorrection`): the factor S(µ*/K)/S
    (:func:`core.shape.bulk_factor`) of the complex µ* (the loss, friction's tangent included)
    against the elastic bulk modulus K, with µ* at the rubber's own strain amplitude; None for
    a design without ``bulk_modulus`` (nearly incompressible, K = 5000 µ: S as it is) or in a
    direction of pure shear (:func:`core.shape.pure_shear`). ``bulk_modulus`` (Pa, may be an
    array broadcast against µ_eq) replaces the design's."""
    bulk = design.material.bulk_modulus if bulk_modulus is None else bulk_modulus
    if bulk is None or pure_shear(design.mode, design.shape_kind):
        return None  # nothing to correct: K absent, or a direction that only shears the rubber
    return BulkCorrection(design.geometry, design.mode, design.shape_kind, bulk)


def stiffness_points(design: Design, frequency_hz, amplitude, *, slices: int | str = 1,
                     route: Route = "analytic", bulk_modulus: float | None = None) -> np.ndarray:
    """Complex stiffness at paired points (frequency_hz[i], amplitude[i]), broadcast together.

    For measured data, which is no grid: the same model and options as :func:`stiffness`
    (eqs 14–18 for one slice), without its cache.

    Parameters
    ----------
    design : Design
        The bushing (mode, geometry, material, effects).
    frequency_hz : float or array_like
        Frequencies in Hz.
    amplitude : float or array_like
        Drive amplitudes, broadcast with ``frequency_hz``: peak displacement in m (axial,
        radial) or peak angle in rad (torsion, conical).
    slices : int or {'continuum'}, default 1
        As for :func:`stiffness`.
    route : {'analytic', 'time-domain'}, default 'analytic'
        As for :func:`stiffness`.
    bulk_modulus : float or None, default None
        Replaces the design's bulk modulus, in Pa (:func:`bulk_correction`); ``math.inf`` gives
        the incompressible limit, which no design file takes.

    Returns
    -------
    numpy.ndarray
        Complex K, shaped as ``frequency_hz`` and ``amplitude`` broadcast together, in N/m
        (axial, radial) or N·m/rad (torsion, conical).

    Raises
    ------
    ValueError
        If ``slices`` or ``route`` is none of those allowed, an amplitude is beyond the
        equivalent strain :data:`MAX_STRAIN`, slices, the continuum or standing waves are asked
        of a design they are not derived for, or the stiffness is not finite.
    ConvergenceError
        If the iteration of the slices, the continuum or the time-domain route does not
        converge.
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
                           modulus(f, design.strain(x)), f, effects["wave_effects"]["density"])
    elif slices == 1:
        k = equivalent_stiffness(modulus, s, c, f, x, bulk_correction(design, bulk_modulus))
    else:
        nodes = continuum_nodes(geo, mode) if slices == "continuum" else slice_nodes(geo, mode, slices)
        fp, xp = (np.broadcast_to(v, shape).ravel() for v in (f, x))
        k = solve_series(nodes, drive=xp, modulus=lambda eps: modulus(fp[:, None], eps),
                         strain_guess=design.strain(xp)).reshape(shape)
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
    design : Design
        The bushing (mode, geometry, material, effects).
    frequency_hz : float or array_like
        Frequencies in Hz, one or more, each positive.
    amplitude : float or array_like
        Drive amplitudes, one or more, each positive: peak displacement in m (axial, radial) or
        peak angle in rad (torsion, conical).
    slices : int or {'continuum'}, default 1
        1 for the single equivalent modulus (eqs 14–18); N > 1 for N concentric slices of
        equal radial thickness in series (Paper A); ``"continuum"`` for the limit N → ∞.
        A design with the ``nonuniform_strain`` effect uses the continuum where 1 is asked.
    route : {'analytic', 'time-domain'}, default 'analytic'
        ``"analytic"``: the closed-form steady state, fast; ``"time-domain"``: the thesis'
        simulation of the strain history, point by point (slow, for checks).

    Returns
    -------
    StiffnessResult
        Complex K on the amplitude × frequency grid, in N/m or N·m/rad; repeated queries come
        from a bounded cache.

    Raises
    ------
    ValueError
        If a frequency or amplitude is not a positive finite number, ``slices`` or ``route`` is
        none of those allowed, or :func:`stiffness_points` refuses the design or an amplitude.
    ConvergenceError
        If the iteration of the slices, the continuum or the time-domain route does not
        converge.
    """
    f = positive_values("frequency_hz", frequency_hz)
    x = positive_values("amplitude", amplitude)
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
    refuse_structural_effects(design, "the branch-by-branch stiffness")
    f = positive_values("frequency_hz", frequency_hz)[None, :]
    x = positive_values("amplitude", amplitude)[:, None]
    s, eps, bulk = design.shape_factor, design.strain(x), bulk_correction(design)
    if bulk is not None:  # a compressible rubber: the branches at its own strain amplitude
        eps, _ = bulk.rubber_modulus(modulus_function(design), f, eps)
    moduli = branch_moduli(design.material, design.effect_parameters, f, eps)
    # and the whole µ_eq's factor on each branch
    factor = 1.0 if bulk is None else bulk.factor(sum(moduli.values()))
    return {name: s * modulus * factor for name, modulus in moduli.items()}  # eqs 17, 18 branch by branch


def cache_info():
    """Hits and misses of the stiffness cache (a functools.lru_cache, bounded)."""
    return _stiffness_cached.cache_info()


# --------------------------------------------------------------------------------------------
# Material model and structural effects
# --------------------------------------------------------------------------------------------


STRUCTURAL_EFFECTS = ("inertia", "nonuniform_strain", "wave_effects")


def material_model(design: Design) -> Design:
    """``design`` without its stiffness-level effects (:data:`STRUCTURAL_EFFECTS`) and without a
    bulk modulus (the bulk spring in series is no branch of the material): the material model
    with its material-level effects, for loops and branch-by-branch views."""
    kept = {eid: p for eid, p in design.effect_parameters.items() if eid not in STRUCTURAL_EFFECTS}
    if design.material.bulk_modulus is not None:
        design = design.replace(bulk_modulus=None)
    return design if len(kept) == len(design.effects) else design.replace(effects=kept)


def refuse_structural_effects(design: Design, what: str, allowed=()) -> None:
    """ValueError if ``design`` has a stiffness-level effect (:data:`STRUCTURAL_EFFECTS`) other
    than those ``allowed``: ``what`` is computed from the material branches."""
    for eid in STRUCTURAL_EFFECTS:
        if eid in design.effect_parameters and eid not in allowed:
            raise ValueError(
                f"effects.{eid}: {what} is computed from the material branches; it is not "
                f"available for a design with this effect (use the stiffness instead)"
            )
