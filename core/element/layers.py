"""One layer's stress in a step, vectorised over layers (docs/element.md, "One channel", "A step").

In a step of length h with the strain held at its new value ε, a layer's stress is

    σ(ε) = a ε + b + 2µβε³ + σ_f(ε),

a and b from the elastic branch, the exponentials and the viscosity (:func:`linear_part`), σ_f
Berg's friction (eq 6) from the layer's reversal memory. Every function takes and returns
arrays over layers; stresses in Pa, strains dimensionless.
"""

from __future__ import annotations

import numpy as np

from ..material import ConvergenceError

STIFFENING_MAX_ITER = 60


def linear_part(mu, m, viscosity, h, wh, z, eps):
    """(a, b) of σ = a ε + b + …: a = 2µ + m Σ_j g_j e^{−λ_j h} + c_v/h (Pa) and
    b = m Σ_j g_j e^{−λ_j h} z_j − (a − 2µ) ε_n (Pa), with ``wh`` = g_j e^{−λ_j h}, ``z`` the
    exponentials' states (layers × terms) and ``eps`` the committed strains ε_n."""
    k = m * float(np.sum(wh)) + viscosity / h
    return 2.0 * mu + k, m * (z @ wh) - k * eps


def branch(d, eps_last, sigf, eps_s, sig_s, direction):
    """The friction branch of a motion in direction ``d`` (+1, −1, 0 for none) from the committed
    point: (ε_s, σ_s, s), the reversal point and direction. Against the last direction the layer
    reverses at its committed point (ε, σ_f); from the virgin state (s = 0) it takes ``d``."""
    rev = d * direction < 0
    return (np.where(rev, eps_last, eps_s), np.where(rev, sigf, sig_s), np.where(d != 0, d, direction))


def friction(eps, es, ss, s, sigma_max, eps_half):
    """Berg's law (eq 6) on the branch (ε_s, σ_s, s): σ_s + u(σ_max − sσ_s)/(ε½(1 − sσ_s/σ_max) + su)."""
    u = eps - es
    return ss + u * (sigma_max - s * ss) / (eps_half * (1.0 - s * ss / sigma_max) + s * u)


def forward(eps, state, a, b, mu, beta, sigma_max, eps_half):
    """The stress at the strains ``eps``, with (σ_f, ε_s, σ_s, s) to commit. ``state`` is
    (ε_n, σ_f, ε_s, σ_s, s) of the committed step."""
    eps_last, sigf = state[0], state[1]
    d = np.sign(eps - eps_last)
    es, ss, s = branch(d, *state)
    sf = np.where(d == 0, sigf, friction(eps, es, ss, s, sigma_max, eps_half))
    sigma = a * eps + b + sf
    if beta:
        sigma = sigma + 2.0 * mu * beta * eps**3
    return sigma, (sf, es, ss, s)


def _on_branch(tau, a, b, es, ss, s, sigma_max, eps_half):
    """The strain where a ε + b + σ_f(ε) = τ on the branch (ε_s, σ_s, s) (a quadratic in
    v = s(ε − ε_s) ≥ 0, solved without cancellation), and σ_f's slope there."""
    A = sigma_max - s * ss
    B = eps_half * (1.0 - s * ss / sigma_max)
    rho = np.maximum(s * (tau - b - ss - a * es), 0.0)
    q = a * B + A - rho
    root = np.sqrt(q * q + 4.0 * a * rho * B)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(q >= 0.0, 2.0 * rho * B / (q + root), (root - q) / (2.0 * a))
    return es + s * v, A * B / (B + v) ** 2


def inverse(tau, state, a, b, mu, beta, sigma_max, eps_half):
    """The strains where each layer's stress is ``tau``, and dσ/dε there (Pa): σ is increasing,
    the branch follows from τ against the stress at the committed strain, and on a branch the
    strain solves a quadratic (exact without stiffening; with it the cubic is linearised at the
    last strain and the quadratic solved again until the strain stops changing)."""
    eps_last, sigf = state[0], state[1]
    kink = a * eps_last + b + sigf
    if beta:
        kink = kink + 2.0 * mu * beta * eps_last**3
    d = np.sign(tau - kink)
    es, ss, s = branch(d, *state)
    eps, slope = _on_branch(tau, a, b, es, ss, s, sigma_max, eps_half)
    if beta:
        k3 = 2.0 * mu * beta
        for _ in range(STIFFENING_MAX_ITER):
            k1 = 3.0 * k3 * eps * eps
            new, slope = _on_branch(tau, a + k1, b - 2.0 * k3 * eps**3, es, ss, s, sigma_max, eps_half)
            done = np.all(np.abs(new - eps) <= 1e-14 * np.abs(new) + 1e-300)  # a few ulps
            eps = new
            if done:
                break
        else:
            raise ConvergenceError("element: a layer's strain with strain stiffening did not converge in "
                                   f"{STIFFENING_MAX_ITER} iterations")
        slope = slope + 3.0 * k3 * eps * eps
    eps = np.where(d == 0, eps_last, eps)
    return eps, a + slope
