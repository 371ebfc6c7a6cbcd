"""One layer's stress in a step, vectorised over layers (docs/element.md, "One channel", "A step").

In a step of length h with the strain held at its new value ε, a layer's stress is

    σ(ε) = a ε + b + 2µβε³ + σ_f(ε),

a and b from the elastic branch, the exponentials and the viscosity (:func:`linear_part`), σ_f
Berg's friction (eq 6). The friction memory is kept as two branch origins per layer: the
point (ε_s, σ_s) the stress rises from if the strain rises (row 0, s = +1) and the one it falls
from if the strain falls (row 1, s = −1). A rise keeps row 0 and makes the new point row 1 (a
fall reverses there), a fall the other way round; a strain that does not move changes neither.
This is Berg's reversal memory (the last reversal point, the direction, the last point) in
another form. Arrays over layers; stresses in Pa, strains dimensionless.
"""

from __future__ import annotations

import numpy as np

from ..material import ConvergenceError

STIFFENING_MAX_ITER = 60
SIGN = np.array([[1.0], [-1.0]])  # s of the rising and the falling branch


def linear_part(mu, m, viscosity, h, wh, z, eps):
    """(a, b) of σ = a ε + b + …: a = 2µ + m Σ_j g_j e^{−λ_j h} + c_v/h (Pa, one number) and
    b = m Σ_j g_j e^{−λ_j h} z_j − (a − 2µ) ε_n (Pa per layer), with ``wh`` = g_j e^{−λ_j h},
    ``z`` the exponentials' states (layers × terms) and ``eps`` the committed strains ε_n."""
    k = m * float(np.sum(wh)) + viscosity / h
    return 2.0 * mu + k, m * (z @ wh) - k * eps


def branch_shape(origin_sig, sigma_max, eps_half):
    """(A, B) of Berg's law on each branch: A = σ_max − sσ_s (Pa), B = ε½(1 − sσ_s/σ_max) = (ε½/σ_max) A."""
    A = sigma_max - SIGN * origin_sig
    return A, (eps_half / sigma_max) * A


def friction(eps, eps_last, sigf, origin_eps, origin_sig, A, B):
    """Berg's law (eq 6) at the strains ``eps`` on the branch their motion from ``eps_last``
    takes: σ_s + u A/(B + s u), u = ε − ε_s; the committed ``sigf`` where the strain has not moved."""
    up = eps > eps_last
    es = np.where(up, origin_eps[0], origin_eps[1])
    u = eps - es
    s = np.where(up, 1.0, -1.0)
    sf = np.where(up, origin_sig[0], origin_sig[1]) + u * np.where(up, A[0], A[1]) / (np.where(up, B[0], B[1]) + s * u)
    return np.where(eps == eps_last, sigf, sf)


def moved(eps, eps_last, sf, origin_eps, origin_sig):
    """The branch origins after committing the strains ``eps`` (friction stress ``sf``): a fall
    (s(ε − ε_n) < 0 for s = +1) makes the new point the rising branch's origin, a rise the
    falling branch's."""
    reversed_here = SIGN * (eps - eps_last) < 0.0
    return np.where(reversed_here, eps, origin_eps), np.where(reversed_here, sf, origin_sig)


class Inverse:
    """The strains where each layer's stress is a target τ, for one step: σ is increasing, so
    the branch follows from τ against the stress at the committed strain, and on a branch the
    strain solves a quadratic in v = s(ε − ε_s) ≥ 0 (exact without stiffening; with it the
    cubic is linearised at the last strain and the quadratic solved again until the strain stops
    changing). Both branches are solved at once (rows), then the right one taken."""

    def __init__(self, a, b, eps_last, sigf, origin_eps, origin_sig, A, B, mu, beta):
        self.b, self.es, self.ss, self.A, self.B = b, origin_eps, origin_sig, A, B
        self.k3 = 2.0 * mu * beta
        self.kink = a * eps_last + b + sigf + (self.k3 * eps_last**3 if beta else 0.0)
        self.eps_last = eps_last
        self._set(a, b)

    def _set(self, a, b):
        self.a = a
        self.C = b + self.ss + a * self.es
        self.aBA = a * self.B + self.A
        self.fourAB = 4.0 * a * self.B
        self.inv2a = 0.5 / a

    def _solve(self, tau):
        rho = np.maximum(SIGN * (tau - self.C), 0.0)
        q = self.aBA - rho
        root = np.sqrt(q * q + self.fourAB * rho)
        v = np.where(q >= 0.0, 2.0 * self.B * rho / (np.abs(q) + root), (root - q) * self.inv2a)
        return self.es + SIGN * v, self.A * self.B / (self.B + v) ** 2

    def __call__(self, tau):
        """(ε, dσ/dε) at the targets ``tau`` (Pa), strains dimensionless, slope in Pa."""
        up = tau > self.kink
        eps2, slope2 = self._solve(tau)
        eps = np.where(up, eps2[0], eps2[1])
        if self.k3:
            a0, b0 = self.a, self.b
            for _ in range(STIFFENING_MAX_ITER):
                self._set(a0 + 3.0 * self.k3 * eps * eps, b0 - 2.0 * self.k3 * eps**3)
                eps2, slope2 = self._solve(tau)
                new = np.where(up, eps2[0], eps2[1])
                # a few ulps, or 1e-14 of ε½ at a strain near zero (B ≈ ε½ on the branch)
                done = np.all(np.abs(new - eps) <= 1e-14 * (np.abs(new) + self.B[0]))
                eps = new
                if done:
                    break
            else:
                raise ConvergenceError("element: a layer's strain with strain stiffening did not converge in "
                                       f"{STIFFENING_MAX_ITER} iterations")
            slope = self.a + np.where(up, slope2[0], slope2[1])  # a here includes 3k3ε² of the last pass
            self._set(a0, b0)
            return eps, slope
        return eps, self.a + np.where(up, slope2[0], slope2[1])
