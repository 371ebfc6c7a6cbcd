"""Sliced bushing (Paper A) and its continuum limit: amplitude-dependent rubber layers in series.

The rubber between a and b is a stack of layers in series: the same moment T (torsion) or
force F (axial) passes through every layer, and the layer angles (displacements) add up to the
drive x̂. A layer k is described by two numbers:

* p_k, its stress per unit load: the stress amplitude in the layer is τ_k = p_k |T|, and its
  (tensor) strain amplitude ε̂_k follows from the material, τ_k = 2 |µ(ε̂_k)| ε̂_k;
* q_k, its compliance weight: the layer's complex angle (displacement) is T q_k / µ(ε̂_k).

So x̂ = |T| · |Σ_k q_k / µ_k| and K = T / x = 1 / Σ_k (q_k / µ_k).

Slices of equal radial thickness r_{k−1} < r_k (eqs 14–18 per slice, strain factor c_k and shape
factor S_k) have p_k = 2 c_k / S_k and q_k = 1 / S_k; one slice is eqs 17/18. The continuum limit
comes from equilibrium at each radius: τ = T / (2π r² L) in torsion, τ = F / (2π r L) axially,
the local strain from the local modulus, and the drive from integrating the local strain over r
(dθ = 2ε dr / r, dw = 2ε dr); Gauss–Legendre quadrature in ln r turns that into nodes with
p = 1/(2π r² L), q = w / (2π r³ L) (torsion) and p = 1/(2π r L), q = w / (2π r L) (axial).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from .material import ConvergenceError
from .parts import Geometry
from .shape import shape_factor, strain_factor


@dataclass(frozen=True)
class SeriesNodes:
    """Layers in series: stress per unit load ``p`` (1/m² or 1/m³) and compliance weight ``q``."""

    p: np.ndarray
    q: np.ndarray


def slice_nodes(geometry: Geometry, mode: str, n: int) -> SeriesNodes:
    """N slices of equal radial thickness, each a small bushing (eqs 14–18)."""
    r = np.linspace(geometry.inner_radius, geometry.outer_radius, n + 1)
    p, q = [], []
    for r0, r1 in pairwise(r):
        g = Geometry(float(r0), float(r1), geometry.length)
        s = shape_factor(g, mode)
        p.append(2.0 * strain_factor(g, mode) / s)
        q.append(1.0 / s)
    return SeriesNodes(np.array(p), np.array(q))


def continuum_node_count(geometry: Geometry, mode: str) -> int:
    """Enough Gauss–Legendre nodes for ~1e-13 relative: 8 plus 4 per decade of the strain
    ratio across the rubber ((b/a)² in torsion, b/a axially), checked against 128 nodes in
    the tests."""
    ratio = geometry.outer_radius / geometry.inner_radius
    decades = np.log10(ratio ** (2 if mode == "torsion" else 1))
    return int(min(64, 8 + 4 * max(1, int(np.ceil(decades)))))


@functools.lru_cache(maxsize=64)
def _unit_nodes(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes and weights of ``n`` points on (0, 1), read-only: computed once per
    count (an eigenvalue problem, 0.3 ms: an eighth of a continuum evaluation of 150 points)."""
    t, w = np.polynomial.legendre.leggauss(n)
    t, w = (t + 1.0) / 2.0, w / 2.0
    t.flags.writeable = w.flags.writeable = False
    return t, w


def continuum_nodes(geometry: Geometry, mode: str, n: int | None = None) -> SeriesNodes:
    """Gauss–Legendre nodes in t = ln(r/a) / ln(b/a) for the continuum limit N → ∞."""
    a, b, L = geometry.inner_radius, geometry.outer_radius, geometry.length
    t, w = _unit_nodes(n or continuum_node_count(geometry, mode))
    log_ratio = np.log(b / a)
    r = a * np.exp(t * log_ratio)
    wr = w * log_ratio * r  # dr = r ln(b/a) dt
    # the stress per load at each radius: with a uniform modulus the strain then falls as 1/r²
    # in torsion (eq 10) and as 1/r axially (eq 11)
    if mode == "torsion":
        return SeriesNodes(1.0 / (2.0 * np.pi * r * r * L), wr / (2.0 * np.pi * r**3 * L))
    return SeriesNodes(1.0 / (2.0 * np.pi * r * L), wr / (2.0 * np.pi * r * L))


def solve_series(
    nodes: SeriesNodes,
    drive,
    modulus,
    strain_guess,
    *,
    tol: float = 1e-11,
    max_iter: int = 100,
) -> np.ndarray:
    """Complex stiffness of layers in series, each at its own strain amplitude.

    Parameters
    ----------
    nodes : the layers (:func:`slice_nodes` or :func:`continuum_nodes`).
    drive : (G,) drive amplitudes x̂ (rad or m), one per problem.
    modulus : callable mapping strain amplitudes of shape (G, N) to complex µ(ε̂) in Pa (each
        row at its problem's frequency).
    strain_guess : (G,) a typical strain amplitude per problem, to start from.

    Newton's method in u_k = ln ε̂_k and λ = ln |T| on the equations
    ln(2|µ_k|) + u_k − ln p_k − λ = 0 (the load is continuous: Paper A's moment continuity) and
    λ + ln |Σ q_k/µ_k| − ln x̂ = 0 (the layers' angles add up to the drive); the Jacobian is
    diagonal plus one row, solved in closed form. Converged when every residual, a relative
    error of the load, is below ``tol``; otherwise :class:`ConvergenceError`, never a number.
    """
    drive = np.asarray(drive, dtype=float)
    p, q = nodes.p[None, :], nodes.q[None, :]
    log_drive = np.log(drive)
    h = 1e-7  # step in ln ε̂ for dµ/du

    # start: every layer at the single equivalent modulus, the strains spread as elastically
    mu0 = modulus(np.broadcast_to(np.asarray(strain_guess, float)[:, None], (drive.size, p.shape[1])))
    load = drive / np.abs(np.sum(q / mu0, axis=1))
    u = np.log(p * load[:, None] / (2.0 * np.abs(mu0)))
    lam = np.log(load)

    for _ in range(max_iter):
        mu = modulus(np.exp(u))
        dmu = (modulus(np.exp(u + h)) - mu) / h
        total = np.sum(q / mu, axis=1)
        e_layer = np.log(2.0 * np.abs(mu)) + u - np.log(p) - lam[:, None]
        e_drive = lam + np.log(np.abs(total)) - log_drive
        worst = np.maximum(np.max(np.abs(e_layer), axis=1), np.abs(e_drive))
        if np.all(worst <= tol):
            return 1.0 / total
        slope = 1.0 + np.real(dmu / mu)  # d ln τ_k / d u_k
        d_drive = np.real(-(q * dmu / mu**2) * np.conj(total)[:, None]) / np.abs(total[:, None]) ** 2
        if np.any(slope <= 0):
            raise ConvergenceError(
                "stress amplitude does not grow with strain amplitude in a layer; "
                "the series problem has no unique solution"
            )
        d_lam = (-e_drive + np.sum(d_drive * e_layer / slope, axis=1)) / (
            1.0 + np.sum(d_drive / slope, axis=1)
        )
        du = (d_lam[:, None] - e_layer) / slope
        # damp long steps (ln scale): at most a factor e per iteration
        damp = 1.0 / np.maximum(1.0, np.maximum(np.max(np.abs(du), axis=1), np.abs(d_lam)))
        u = u + damp[:, None] * du
        lam = lam + damp * d_lam
    bad = np.flatnonzero(worst > tol)
    raise ConvergenceError(
        f"sliced-bushing iteration did not reach load continuity {tol:.0e} in {max_iter} steps "
        f"for {bad.size} of {drive.size} points (first at drive {drive[bad[0]]:g}, "
        f"residual {worst[bad[0]]:.1e})"
    )
