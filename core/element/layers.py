"""One layer's stress in a step, on Python floats (docs/element.md, "One channel", "A step").

In a step of length h with the strain held at its new value ε, a layer's stress is

    σ(ε) = a ε + b + 2µβε³ + σ_f(ε),

a = 2µ + m Σ_j g_j e^{−λ_j h} + c_v/h (Pa, one number per step length) and b = m Σ_j g_j
e^{−λ_j h} z_j − (a − 2µ) ε_n (Pa, per layer) from the elastic branch, the exponentials and the
viscosity; σ_f Berg's friction (eq 6). The friction memory is kept as two branch origins per
layer: the point (ε_s, σ_s) the stress rises from if the strain rises (row 0, s = +1) and the
one it falls from if the strain falls (row 1, s = −1). A rise keeps row 0 and makes the new
point row 1 (a fall reverses there), a fall the other way round; a strain that does not move
changes neither. This is Berg's reversal memory (the last reversal point, the direction, the
last point) in another form. On a branch, Berg's law is σ_s + u A/(B + s u), u = ε − ε_s,
A = σ_max − sσ_s (Pa), B = ε½(1 − sσ_s/σ_max) = (ε½/σ_max) A.

The element has 6 to a few dozen layers: plain float arithmetic (about 50 ns an operation) is
far cheaper here than NumPy calls (about 1 µs each whatever the size), so these functions take
and return floats, one layer at a time. Stresses in Pa, strains dimensionless.
"""

from __future__ import annotations

import math

from ..material import ConvergenceError

STIFFENING_MAX_ITER = 60


def friction(eps, eps_last, sigf, origin, sigma_max, ratio):
    """Berg's law (eq 6) at the strain ``eps`` on the branch its motion from ``eps_last`` takes
    (``origin``: the rows' origins (ε_s, σ_s) rising then falling, four floats; ``ratio`` =
    ε½/σ_max); the committed ``sigf`` where the strain has not moved."""
    if eps == eps_last:
        return sigf
    if eps > eps_last:
        es, ss, s = origin[0], origin[1], 1.0
    else:
        es, ss, s = origin[2], origin[3], -1.0
    A = sigma_max - s * ss
    u = eps - es
    return ss + u * A / (ratio * A + s * u)


def moved(origin, eps, eps_last, sigma_f):
    """The branch origins after committing the strain ``eps`` (friction stress ``sigma_f``) from
    ``eps_last``: a fall makes the new point the rising branch's origin, a rise the falling one's."""
    if eps < eps_last:
        return eps, sigma_f, origin[2], origin[3]
    if eps > eps_last:
        return origin[0], origin[1], eps, sigma_f
    return origin


def on_branch(tau, a, b, es, ss, s, sigma_max, ratio):
    """(ε, dσ/dε) where σ = a ε + b + σ_f(ε) on the branch from (``es``, ``ss``) in the direction
    ``s`` equals the target ``tau`` (Pa): with v = s(ε − ε_s) ≥ 0 a quadratic, solved in the form
    that loses no digits to cancellation."""
    A = sigma_max - s * ss
    B = ratio * A
    rho = s * (tau - (b + ss + a * es))
    rho = max(rho, 0.0)
    q = a * B + A - rho
    root = math.sqrt(q * q + 4.0 * a * B * rho)
    v = 2.0 * B * rho / (abs(q) + root) if q >= 0.0 else (root - q) * (0.5 / a)
    t = B + v
    return es + s * v, a + A * B / (t * t)


def stress(eps, a, b, sigma_f, k3):
    """σ = a ε + b + σ_f + k3 ε³ (Pa) at the strain ``eps`` with its friction stress ``sigma_f``
    (``k3`` = 2µβ, 0 without stiffening)."""
    sigma = a * eps + b + sigma_f
    return sigma + k3 * eps**3 if k3 else sigma


def strain(tau, a, b, kink, origin, sigma_max, eps_half, k3):
    """(ε, dσ/dε) of a layer at the target stress ``tau`` (Pa) in a step: σ is increasing in ε,
    so the branch follows from the target against ``kink``, the stress at the committed strain
    (:func:`stress`), and :func:`on_branch` solves on it. Strain stiffening (``k3`` = 2µβ)
    linearises the cubic at the last strain and solves the quadratic again until the strain
    stops changing."""
    es, ss, s = (origin[0], origin[1], 1.0) if tau > kink else (origin[2], origin[3], -1.0)
    ratio = eps_half / sigma_max
    if not k3:
        return on_branch(tau, a, b, es, ss, s, sigma_max, ratio)
    eps = on_branch(tau, a, b, es, ss, s, sigma_max, ratio)[0]
    last_change = math.inf
    for _ in range(STIFFENING_MAX_ITER):
        new, slope = on_branch(tau, a + 3.0 * k3 * eps * eps, b - 2.0 * k3 * eps**3, es, ss, s, sigma_max, ratio)
        change = abs(new - eps)
        eps = new
        # a few ulps of the strain or of ε½; or the change has stopped shrinking at the rounding
        # level (the linearised Newton iterates can only dither there)
        scale = abs(new) + eps_half
        if change <= 1e-14 * scale or (change >= last_change and change <= 1e-11 * scale):
            return eps, slope  # slope: its a includes 3k3ε² of the last pass
        last_change = change
    raise ConvergenceError("element: a layer's strain with strain stiffening did not converge in "
                           f"{STIFFENING_MAX_ITER} iterations (target stress {tau:.6g} Pa)")
