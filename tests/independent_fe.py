"""A finite-element route to the shape factor that shares nothing with the shipped table but the
FE library (felupe, the `fe` extra) and the continuum: triquadratic 27-node hexahedra with a
discontinuous trilinear pressure and volume (felupe's mixed fields for that element, which do
not lock), a uniform mesh made in (x, r, θ) and mapped onto the true circles, no grading. The
table's own model (core.shape.fe_shape_factor) uses trilinear hexahedra with a constant pressure
per element on a mesh graded toward the free ends. Used by tests/test_compressibility.py."""

from __future__ import annotations

import functools

import numpy as np


@functools.cache
def mixed_q2_shape_factor(q: float, lam: float, mode: str, n_r: int, ratio: float) -> float:
    """S of a bushing a = 1, b = ``q``, L = ``lam``·(b − a) in ``mode`` (radial or conical) at
    K/µ = ``ratio``, with ``n_r`` elements across the wall (4 n_r around the half circumference,
    square-ish along the half length); half the length and half the circumference by symmetry,
    the axis along x, the inner sleeve moved along y (radial) or tilted about z (conical)."""
    import felupe as fem

    a, b, length = 1.0, q, lam * (q - 1.0)
    mu = 1.0e6  # a rubber's µ, keeping the reactions far above the solver's absolute floor
    n_x = max(2, round(n_r * lam / 2))
    grid = fem.Cube(a=(0.0, a, 0.0), b=(length / 2, b, np.pi), n=(n_x + 1, n_r + 1, 4 * n_r + 1))
    quadratic = fem.mesh.convert(grid, order=2, calc_midfaces=True, calc_midvolumes=True)
    x, r, theta = quadratic.points.T
    points = np.column_stack([x, r * np.cos(theta), r * np.sin(theta)])
    field = fem.FieldsMixed(fem.RegionTriQuadraticHexahedron(fem.Mesh(points, quadratic.cells, "hexahedron27")), n=3)
    inner, outer = np.isclose(r, a), np.isclose(r, b)
    free = ~inner & ~outer
    step = 1e-6 * (b - a)
    held = inner.sum()
    if mode == "radial":
        moved = np.column_stack([np.zeros(held), np.full(held, step), np.zeros(held)])
        mid = (0, 1, 1)  # the mid-plane x = 0: u_x = 0 (symmetric)
    else:
        angle = step / length
        moved = np.column_stack([-angle * points[inner, 1], angle * points[inner, 0], np.zeros(held)])
        mid = (1, 0, 0)  # the mid-plane x = 0: u_y = u_z = 0 (antisymmetric)
    boundaries = {
        "outer": fem.Boundary(field[0], mask=outer),
        "inner": fem.Boundary(field[0], mask=inner, value=moved.ravel()),
        "mid": fem.Boundary(field[0], mask=np.isclose(x, 0.0) & free, skip=mid),
        # the plane through the axis and the drive (θ = 0, π): u_z = 0
        "plane": fem.Boundary(field[0], mask=(np.abs(points[:, 2]) < 1e-12) & free, skip=(1, 1, 0)),
    }
    solid = fem.SolidBody(fem.ThreeFieldVariation(fem.NeoHooke(mu=mu, bulk=ratio * mu)), field)
    dof0, dof1 = fem.dof.partition(field, boundaries)
    result = fem.newtonraphson(items=[solid], x0=field, dof1=dof1, dof0=dof0,
                               ext0=fem.dof.apply(field, boundaries, dof0), verbose=0, tol=1e-6)
    if mode == "radial":
        return 4.0 * float(fem.tools.force(field, result.fun, boundaries["inner"])[1]) / (mu * step)
    moment = fem.tools.moment(field, result.fun, boundaries["inner"], centerpoint=np.zeros(3))
    return 4.0 * float(moment[2]) / (mu * angle)


def extrapolated(q: float, lam: float, mode: str, ratio: float, levels: tuple[int, int] = (2, 3)) -> float:
    """Richardson's extrapolation of two meshes with the element's order 2 in h (observed: the
    differences of 2 → 3 → 4 elements across the wall shrink as h^2.1)."""
    n1, n2 = levels
    s1, s2 = (mixed_q2_shape_factor(q, lam, mode, n, ratio) for n in levels)
    w = (1 / n2**2) / (1 / n1**2 - 1 / n2**2)
    return s2 - w * (s1 - s2)
