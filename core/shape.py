"""Shape factors of a bushing in every direction, and the energy-balance equivalent strain.

The stiffness separates into geometry and material, K_mode = S_mode · µ_eq(ω, ε_eq), with S_mode
the shape factor: m for the translations (axial, radial), m³ for the rotations (torsion about
the axis, conical: tilting about a diameter). Symbols: a inner, b outer radius, L length.

Closed forms (docs/model.md), for infinitely long bushings except torsion, which is exact at any
length (the free ends carry no traction in the exact solution):

* axial, long:   S = 2πL / ln(b/a)                                        (thesis eq 18)
* torsion:       S = 4π a² b² L / (b² − a²)                               (thesis eq 17)
* radial, long (plane strain, incompressible):
                 S = 4πL (a² + b²) / ((a² + b²) ln(b/a) − (b² − a²))
* conical: no closed form holds for real lengths; :func:`conical_reference` (the long radial
  stiffness per length, summed with the lever arm², S_radial,long · L²/12) is only the scale
  the finite-length table is divided by.

Finite lengths come from a finite-element model (:func:`fe_shape_factor`, the felupe library):
the rubber between rigid bonded tubes, the outer one held, the inner one moved rigidly by a small
displacement or rotation, the ends free; nearly incompressible (bulk modulus 5000 µ, Hu-Washizu
three-field hexahedra); a quarter of the bushing by its two planes of symmetry. Two meshes and
Richardson's extrapolation (the error falls as h²) give the converged value
(:func:`converged_shape_factor`). A table of the converged ratios to the closed forms over
(b/a, L/(b − a)), made by ``tools/shape_table.py`` and shipped as ``core/shape_table.json``, is
interpolated by bicubic splines in the logarithms (:func:`finite_shape_factor`).

The equivalent strain of any mode follows from the energy balance with a simple-shear specimen
(strain-energy density 2µε² at tensor shear strain ε): the bushing stores ½ S µ x̂², so

    ε_eq = x̂ · √(S / (4V)),     V = π (b² − a²) L,

which is the thesis' eq 15 with the long axial S and its eq 14 with the torsion S.
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .parameters import TRANSLATIONS, no_long_form
from .parameters import mode as checked_mode
from .parts import Geometry

TABLE_PATH = Path(__file__).with_name("shape_table.json")
BULK_RATIO = 5000.0  # K/µ of the FE model: rubber's is 1 000–5 000


class OutsideTable(ValueError):
    """A geometry outside the finite-length table."""


def _radii(a: float, b: float, L: float):
    if not (a > 0 and b > a and L > 0):
        raise ValueError(f"shape factor: needs 0 < a < b and L > 0, got a={a:g}, b={b:g}, L={L:g}")
    return float(a), float(b), float(L)


def long_shape_factor(a: float, b: float, L: float, mode: str) -> float:
    """The closed form of ``mode`` (torsion exact; axial and radial for a long bushing)."""
    checked_mode(mode)
    a, b, L = _radii(a, b, L)
    if mode == "axial":
        return 2.0 * math.pi * L / math.log(b / a)  # eq 18
    if mode == "torsion":
        return 4.0 * math.pi * a * a * b * b * L / (b * b - a * a)  # eq 17
    if mode == "radial":
        s = a * a + b * b
        return 4.0 * math.pi * L * s / (s * math.log(b / a) - (b * b - a * a))
    raise ValueError(no_long_form(mode))


def conical_reference(a: float, b: float, L: float) -> float:
    """The scale of the conical shape factor: the long radial stiffness per length with the
    lever arm² summed over the length, S_radial,long · L²/12 (m³). Not a stiffness formula."""
    return long_shape_factor(a, b, L, "radial") * L * L / 12.0


def reference_shape_factor(a: float, b: float, L: float, mode: str) -> float:
    """What the finite-length table's ratios are relative to."""
    return conical_reference(a, b, L) if mode == "conical" else long_shape_factor(a, b, L, mode)


def strain_factor_from_shape(S: float, a: float, b: float, L: float) -> float:
    """c in ε_eq = c · x̂ from the energy balance: √(S / (4V)), V = π(b² − a²)L."""
    return math.sqrt(S / (4.0 * math.pi * (b * b - a * a) * L))  # eqs 12–13


# ---- the finite-element model -------------------------------------------------------------

# components held at zero on the symmetry planes x = 0 (the mid-length) and z = 0 (through the
# axis, containing the load), per mode: the loads are symmetric or antisymmetric about each
_HELD = {
    "axial": ((0, 1, 1), (0, 0, 1)),
    "radial": ((1, 0, 0), (0, 0, 1)),
    "conical": ((0, 1, 1), (0, 0, 1)),
    "torsion": ((1, 0, 0), (1, 1, 0)),
}


def _axial_nodes(half_length: float, h: float, wall: float, n: int) -> np.ndarray:
    """Nodes from the mid-plane (0) to the free end: elements of size h within one wall
    thickness of the end, then growing by 1.25 toward the middle, at most 4h; at least n
    elements along a short bushing."""
    sizes, total = [], 0.0
    size = h = min(h, half_length / n)
    while total < half_length - 1e-12 * half_length:
        sizes.append(size)
        total += size
        if total >= wall:
            size = min(size * 1.25, 4 * h)
    sizes = np.array(sizes) * half_length / total
    return np.concatenate([[0.0], np.cumsum(sizes[::-1])])


def fe_shape_factor(a: float, b: float, L: float, mode: str, n_r: int = 6,
                    bulk_ratio: float = BULK_RATIO) -> tuple[float, int]:
    """S of ``mode`` from the felupe model with ``n_r`` elements across the wall (4 n_r around
    the half circumference, graded along the length) and a bulk modulus ``bulk_ratio`` times the
    shear modulus; the number of hexahedra of the quarter."""
    import felupe as fem  # the FE library (the `fe` extra): only here, for the table and its checks

    checked_mode(mode)
    a, b, L = _radii(a, b, L)
    h = (b - a) / n_r
    x_nodes = _axial_nodes(L / 2, h, b - a, n_r)
    rect = fem.mesh.Grid(x_nodes, np.linspace(a, b, n_r + 1))
    mesh = rect.revolve(n=4 * n_r + 1, phi=180, axis=0)
    field = fem.FieldsMixed(fem.RegionHexahedron(mesh), n=3)
    x = mesh.points
    r = np.hypot(x[:, 1], x[:, 2])
    inner, outer = np.isclose(r, a, rtol=1e-9), np.isclose(r, b, rtol=1e-9)
    p = x[inner]
    zero = np.zeros(len(p))
    step = 1e-6 * (b - a)  # small: the response is linear
    if mode == "axial":
        u = np.column_stack([zero + step, zero, zero])
    elif mode == "radial":
        u = np.column_stack([zero, zero + step, zero])
    elif mode == "torsion":  # about the axis x
        angle = step / b
        u = np.column_stack([zero, -angle * p[:, 2], angle * p[:, 1]])
    else:  # conical: about the diameter z, through the centre
        angle = step / L
        u = np.column_stack([-angle * p[:, 1], angle * p[:, 0], zero])
    held_mid, held_plane = _HELD[mode]
    free = ~inner & ~outer
    boundaries = {
        "outer": fem.Boundary(field[0], mask=outer),
        "inner": fem.Boundary(field[0], mask=inner, value=u.ravel()),
        "mid": fem.Boundary(field[0], mask=np.isclose(x[:, 0], 0.0) & free, skip=tuple(1 - k for k in held_mid)),
        "plane": fem.Boundary(field[0], mask=np.isclose(x[:, 2], 0.0) & free,
                              skip=tuple(1 - k for k in held_plane)),
    }
    # µ of a rubber (1 MPa), so that the reaction forces are far above felupe's absolute floor
    # (1e-3) in its relative convergence test; S = reaction / (µ · step)
    mu = 1e6 / max(a, 1e-300) ** 2
    solid = fem.SolidBody(fem.ThreeFieldVariation(fem.NeoHooke(mu=mu, bulk=bulk_ratio * mu)), field)
    dof0, dof1 = fem.dof.partition(field, boundaries)
    ext0 = fem.dof.apply(field, boundaries, dof0)
    # the problem is linear (a step of 1e-6 of the wall): Newton converges in one or two
    # iterations to the round-off floor of the nearly incompressible system (about 1e-8)
    res = fem.newtonraphson(items=[solid], x0=field, dof1=dof1, dof0=dof0, ext0=ext0, verbose=0, tol=1e-6)
    # the quarter's reaction on the inner tube, times 4 (the other quarters mirror it)
    if mode in TRANSLATIONS:
        force = fem.tools.force(field, res.fun, boundaries["inner"])
        return 4.0 * float(force[0] if mode == "axial" else force[1]) / (mu * step), mesh.ncells
    moment = fem.tools.moment(field, res.fun, boundaries["inner"], centerpoint=np.zeros(3))
    return 4.0 * float(moment[0] if mode == "torsion" else moment[2]) / (mu * angle), mesh.ncells


@dataclass(frozen=True)
class Converged:
    value: float  # Richardson's extrapolation of the two meshes
    coarse: float
    fine: float
    cells: int  # of the finer quarter model

    @property
    def error(self) -> float:
        """The estimated relative error of the finer mesh (its distance to the extrapolation)."""
        return abs(self.fine - self.value) / abs(self.value)


def converged_shape_factor(a: float, b: float, L: float, mode: str, levels: tuple[int, int] = (6, 8),
                           bulk_ratio: float = BULK_RATIO) -> Converged:
    """S from two meshes (``levels`` elements across the wall) and Richardson's extrapolation
    with the observed order 2 (checked on three meshes in the tests), at K/µ ``bulk_ratio``."""
    n1, n2 = levels
    s1, _ = fe_shape_factor(a, b, L, mode, n1, bulk_ratio)
    s2, cells = fe_shape_factor(a, b, L, mode, n2, bulk_ratio)
    w = (1 / n2**2) / (1 / n1**2 - 1 / n2**2)
    return Converged(s2 - w * (s1 - s2), s1, s2, cells)


# ---- the table ------------------------------------------------------------------------------


@dataclass(frozen=True)
class ShapeTable:
    radius_ratio: np.ndarray  # b/a
    length_ratio: np.ndarray  # L/(b − a)
    ratios: dict  # mode → array (radius_ratio × length_ratio) of S_FE / S_reference
    splines: dict = field(default_factory=dict)  # mode → bicubic spline of ln(ratio) in the logarithms
    slopes: dict = field(default_factory=dict)  # mode → bicubic spline of the series law's slope g

    def ratio(self, mode: str, radius_ratio: float, length_ratio: float) -> float:
        lo_r, hi_r = self.radius_ratio[[0, -1]]
        lo_l, hi_l = self.length_ratio[[0, -1]]
        if not (lo_r <= radius_ratio <= hi_r and lo_l <= length_ratio <= hi_l):
            raise OutsideTable(
                f"the finite-length shape factors cover b/a {lo_r:g}–{hi_r:g} and L/(b − a) {lo_l:g}–{hi_l:g}; "
                f"this bushing has b/a {radius_ratio:.3g} and L/(b − a) {length_ratio:.3g} (use shape 'thesis', the long-bushing "
                f"closed forms, for axial or torsion)")
        # the spline interpolates ln(ratio): its exp stays positive and smooth
        return math.exp(float(self.splines[mode](math.log(radius_ratio), math.log(length_ratio))[0, 0]))

    def slope(self, mode: str, radius_ratio: float, length_ratio: float) -> float:
        """The series law's slope g at (b/a, L/(b − a)) inside the table (:meth:`ratio`'s range)."""
        self.ratio(mode, radius_ratio, length_ratio)  # the range check and its message
        return float(self.slopes[mode](math.log(radius_ratio), math.log(length_ratio))[0, 0])

    def compressible_factor(self, mode: str, radius_ratio: float, length_ratio: float, x):
        """S(x)/S(x₀) of the table's FE model at µ/K = ``x`` (real, or complex for a complex
        shear modulus), x₀ = 1/:data:`BULK_RATIO`: 1/(1 + g·(x − x₀))."""
        return 1.0 / (1.0 + self.slope(mode, radius_ratio, length_ratio) * (x - 1.0 / BULK_RATIO))


@functools.cache
def table() -> ShapeTable:
    """The shipped table, read and its splines built once per process."""
    from scipy.interpolate import RectBivariateSpline

    data = json.loads(TABLE_PATH.read_text(encoding="utf-8"))
    q, lam = np.array(data["radius_ratio"]), np.array(data["length_ratio"])
    ratios = {m: np.array(v) for m, v in data["ratios"].items()}
    splines = {m: RectBivariateSpline(np.log(q), np.log(lam), np.log(r), kx=3, ky=3, s=0) for m, r in ratios.items()}
    slopes = {m: RectBivariateSpline(np.log(q), np.log(lam), np.array(g), kx=3, ky=3, s=0)
              for m, g in data.get("compressibility", {}).get("slopes", {}).items()}
    return ShapeTable(q, lam, ratios, splines, slopes)


def finite_shape_factor(a: float, b: float, L: float, mode: str) -> float:
    """S of a bushing of real length: the table's converged FE ratio times the reference
    (torsion: its exact formula, which the FE reproduces)."""
    checked_mode(mode)
    a, b, L = _radii(a, b, L)
    if mode == "torsion":
        return long_shape_factor(a, b, L, "torsion")
    return reference_shape_factor(a, b, L, mode) * table().ratio(mode, b / a, L / (b - a))


def shape_factor(geometry: Geometry, mode: str, shape: str | None = None) -> float:
    """The shape factor S of a bushing in ``mode``, with K = S·µ_eq.

    The closed forms of :mod:`core.shape` for ``shape="long"`` (torsion S = 4π a² b² L /
    (b² − a²), eq 17; axial S = 2π L / ln(b/a), eq 18; radial, plane strain), the finite-length
    FE table for ``"finite"``.

    Parameters
    ----------
    geometry : Geometry
        The bonded radii a, b and the length L, in m.
    mode : str
        The direction: one of :data:`core.parameters.MODES`.
    shape : {'long', 'finite'} or None, default None
        Which shape factor; ``None``: the mode's default (:data:`core.parameters.DEFAULT_SHAPE`:
        long for axial and torsion, finite for radial and conical).

    Returns
    -------
    float
        S in m (axial, radial) or m³/rad (torsion, conical).

    Raises
    ------
    ValueError
        If ``"long"`` is asked of the conical mode (no closed form), the geometry lies outside
        the finite-length table (:class:`OutsideTable`), or ``mode`` is unknown.
    """
    a, b, L = geometry.inner_radius, geometry.outer_radius, geometry.length
    if (shape or checked_mode(mode).default_shape) == "finite":
        return finite_shape_factor(a, b, L, mode)
    return long_shape_factor(a, b, L, mode)


def long_radial_compressible(a: float, b: float, L: float, x):
    """The long radial shape factor (plane strain) of a compressible rubber, µ/K = ``x`` (real,
    or complex by the correspondence principle):

        S = 8πL (1 − ν) / ((3 − 4ν) ln(b/a) − (b² − a²) / ((3 − 4ν)(b² + a²))),

    with Poisson's ratio ν = (3 − 2x) / (2(3 + x)): the exact solution of Navier's equations for
    the inner tube displaced across the axis (the displacement's first circular harmonic; four
    constants from the bonded tubes). At x = 0 it is the incompressible closed form; for a thin
    wall t = b − a it tends to πa(λ + 3µ)/t per length (compression λ + 2µ and shear µ of the
    layer)."""
    a, b, L = _radii(a, b, L)
    nu = (3.0 - 2.0 * x) / (2.0 * (3.0 + x))
    k = 3.0 - 4.0 * nu
    return 8.0 * math.pi * L * (1.0 - nu) / (k * math.log(b / a) - (b * b - a * a) / (k * (b * b + a * a)))


def pure_shear(mode: str, shape: str | None = None) -> bool:
    """Whether ``mode`` with ``shape`` (None: the mode's default) shears the rubber without
    squeezing it, so that its bulk modulus does not matter: torsion, and the long axial bushing."""
    kind = shape or checked_mode(mode).default_shape
    return mode == "torsion" or (mode == "axial" and kind == "long")


def bulk_factor(geometry: Geometry, mode: str, shape: str | None, x):
    """How much a bulk modulus K changes the shape factor: S(µ/K = x) / S, with S the shape
    factor of :func:`shape_factor` (K/µ = :data:`BULK_RATIO` for the finite-length table, the
    incompressible closed forms for ``long``). ``x`` is µ/K, real or complex (µ* complex: the
    correspondence principle, K* = µ*·S(µ*/K)); an array broadcasts.

    Torsion and the long axial bushing are pure shear (factor 1 at any K). The finite-length
    table's entries follow the series law 1/S(x) = (1 + g·(x − x₀))/S(x₀), a shear spring in
    series with a bulk spring (its slope g from a second FE solve); the long radial bushing has
    the plane-strain closed form :func:`long_radial_compressible`."""
    a, b, L = _radii(geometry.inner_radius, geometry.outer_radius, geometry.length)
    kind = shape or checked_mode(mode).default_shape
    if pure_shear(mode, kind):
        return np.ones_like(np.asarray(x) * 1.0)
    if kind == "long":  # radial
        return long_radial_compressible(a, b, L, x) / long_shape_factor(a, b, L, "radial")
    return table().compressible_factor(mode, b / a, L / (b - a), np.asarray(x))


def bulk_tangent(geometry: Geometry, mode: str, shape: str | None, x):
    """d(x·φ(x))/dx with φ = :func:`bulk_factor`: (1/S)·∂(µ·S(µ/K))/∂µ at fixed K, the
    stiffness' derivative in the shear modulus, by which the shear (deviatoric) part of the
    strain energy is µ·∂K/∂µ·x̂²/2 (dimensionless; ``x`` = µ/K, real or complex, broadcast).

    The finite-length table's series law: (1 − g x₀)/(1 + g(x − x₀))²; the long radial closed
    form: its derivative in x; 1 for pure shear."""
    a, b, L = _radii(geometry.inner_radius, geometry.outer_radius, geometry.length)
    kind = shape or checked_mode(mode).default_shape
    x = np.asarray(x)
    if pure_shear(mode, kind):
        return np.ones_like(x * 1.0)
    if kind == "long":  # radial: S + x dS/dx of the plane-strain solution
        nu = (3.0 - 2.0 * x) / (2.0 * (3.0 + x))
        dnu = -4.5 / (3.0 + x) ** 2
        k, ln, r = 3.0 - 4.0 * nu, math.log(b / a), (b * b - a * a) / (b * b + a * a)
        den = k * ln - r / k
        dden = -4.0 * dnu * (ln + r / k**2)
        s, ds = (1.0 - nu) / den, (-dnu * den - (1.0 - nu) * dden) / den**2
        return 8.0 * math.pi * L * (s + x * ds) / long_shape_factor(a, b, L, "radial")
    g = table().slope(mode, b / a, L / (b - a))
    return (1.0 - g / BULK_RATIO) / (1.0 + g * (x - 1.0 / BULK_RATIO)) ** 2


def strain_factor(geometry: Geometry, mode: str, shape: str | None = None) -> float:
    """The strain factor c of a bushing in ``mode``, with ε_eq = c·x̂.

    From the energy balance, c = √(S / (4V)), V = π(b² − a²)L: with the long shape factors,
    torsion c = a b / (b² − a²) (eq 14) and axial c = 1 / sqrt(2 (b² − a²) ln(b/a)) (eq 15).

    Parameters
    ----------
    geometry : Geometry
        The bonded radii a, b and the length L, in m.
    mode : str
        The direction: one of :data:`core.parameters.MODES`.
    shape : {'long', 'finite'} or None, default None
        Which shape factor, as for :func:`shape_factor`.

    Returns
    -------
    float
        c in 1/m (axial, radial) or 1/rad (torsion, conical).

    Raises
    ------
    ValueError
        As :func:`shape_factor`.
    """
    a, b, L = geometry.inner_radius, geometry.outer_radius, geometry.length
    kind = shape or checked_mode(mode).default_shape
    if mode == "torsion" and kind == "long":
        return a * b / (b * b - a * a)  # eq 14, the same number without round-off
    if mode == "axial" and kind == "long":
        return 1.0 / np.sqrt(2.0 * (b * b - a * a) * np.log(b / a))  # eq 15
    return strain_factor_from_shape(shape_factor(geometry, mode, shape), a, b, L)
