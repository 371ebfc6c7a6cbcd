"""The stateful time-domain element: six uncoupled channels, one step at a time, O(1) per step
(docs/element.md).

:class:`Element` holds every layer of every channel in flat arrays (layers × exponentials for
the fractional memory), so a step is a fixed number of array operations whatever the channels,
slices and history. A channel of one layer without a bulk spring needs no solve: its strain is
c·x. A channel of layers in series (slices, or a bulk spring) solves for its force F by
Newton's method on Σ_k ε_k(p_k F)/c_k + C_b F = x, each layer's strain ε_k(τ) exact on its
friction branch (:class:`core.element.layers.Inverse`), safeguarded by a bracket on F (bisection
where a friction kink throws Newton outside it), to 1e−13 relative.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..design import Design
from ..material import ConvergenceError
from . import layers
from .coefficients import CHANNELS, OUTPUTS, Coefficients, coefficients
from .prony import CHECK_POINTS_PER_DECADE, DEFAULT_BAND

STATE_VERSION = 1
TOLERANCE = 1e-13  # relative, on the channel's drive balance
MAX_ITER = 100
LAST_STEP = 1e-8  # relative residual below which the last Newton step is taken without evaluating
_STATE_KEYS = ("eps", "sigf", "z", "origin_eps", "origin_sig", "x", "force", "tangent", "slope")
_H_CACHE = 64  # step lengths remembered (e^{−λh} per h)
HELD_LIMIT = (0.01, 0.01)  # relative magnitude, phase (rad): the fractional term's error that warns


def bracketed(new, step, lo, hi):
    """Newton's next force ``new`` (``step`` from the last) kept inside the bracket (lo, hi) of
    each channel: bisection where both ends are known, else 2|step| away from the known end."""
    outside = (new <= lo) | (new >= hi)
    if not outside.any():
        return new
    lo_known, hi_known = np.isfinite(lo), np.isfinite(hi)
    safe = np.where(lo_known & hi_known, 0.5 * (np.where(lo_known, lo, 0.0) + np.where(hi_known, hi, 0.0)),
                    np.where(lo_known, lo + 2.0 * np.abs(step), hi - 2.0 * np.abs(step)))
    return np.where(outside, safe, new)


class ElementWarning(UserWarning):
    """A step too long for the band: with the input held over it, the fractional term is more than
    :data:`HELD_LIMIT` off (iω)^α somewhere in the band (:meth:`Element.held_error`)."""


class Element:
    """The bushing as a time-domain element (docs/element.md).

    Parameters
    ----------
    coefficients : Coefficients
        From :func:`core.element.coefficients`.
    channels : sequence of str or None, default None
        Which channels (``dx`` … ``rz``), in this order in inputs and outputs; None: all six.

    The inputs are displacements (m) and angles (rad) in the channels' order; the outputs are
    forces (N) and moments (N·m). :meth:`trial` leaves the state unchanged, :meth:`commit`
    advances it; :meth:`state` and :meth:`restore` read and set it (plain arrays, copies).
    A step whose held input puts the fractional term more than :data:`HELD_LIMIT` off
    (iω)^α somewhere in the band (:meth:`held_error`) gives an :class:`ElementWarning`, once
    per step length.
    """

    def __init__(self, coefficients: Coefficients, channels=None):
        names = CHANNELS if channels is None else tuple(channels)
        unknown = [n for n in names if n not in CHANNELS]
        if unknown or not names or len(set(names)) != len(names):
            raise ValueError(f"channels: give distinct names among {', '.join(CHANNELS)}, got {channels!r}")
        co = self.coefficients = coefficients
        self.channels = names
        self.outputs = tuple(OUTPUTS[CHANNELS.index(n)] for n in names)
        self.band = co.band
        self.error_bound = (co.magnitude_error, co.phase_error)
        chs = [co.channels[n] for n in names]
        compliance = np.array([ch.compliance for ch in chs])
        counts = np.array([len(ch.S) for ch in chs])
        series = (counts > 1) | (compliance > 0)
        self._direct_ch = np.flatnonzero(~series)  # one layer, no bulk spring: ε = c·x
        self._series_ch = np.flatnonzero(series)
        # the layers, the direct channels' first (one each, in channel order), then the series'
        ordered = [chs[i] for i in self._direct_ch] + [chs[i] for i in self._series_ch]
        S = np.concatenate([ch.S for ch in ordered])
        c = np.concatenate([ch.c for ch in ordered])
        self._nd = self._direct_ch.size
        self._p = 2.0 * c / S  # stress (Pa) per unit force
        self._c = c
        self._inv_c = 1.0 / c
        self._counts = counts[self._series_ch]
        local = np.repeat(np.arange(self._series_ch.size), self._counts)
        self._sum = (local[None, :] == np.arange(self._series_ch.size)[:, None]).astype(float)
        self._to_layers = self._sum * self._p[self._nd:]  # F (channels) @ this: the layers' stresses τ = p F
        self._drive = self._sum * self._inv_c[self._nd:]  # this @ ε: Σ ε_k/c_k per channel
        self._drive_slope = self._sum * (self._p * self._inv_c)[self._nd:]  # this @ (1/σ'): dx/dF
        self._compliance = compliance[self._series_ch]
        self._any_compliance = bool(np.any(self._compliance > 0))
        self._rates = np.array(co.rate)
        self._weights = np.array(co.weight)
        self._mat = (co.mu, co.beta, co.sigma_f_max, co.eps_half)
        self._h_cache: dict[float, np.ndarray] = {}
        self._warned: set[float] = set()
        self.iterations = 0  # Newton iterations of the last step's series solve
        n_layers, n_terms = S.size, self._rates.size
        self._s = {"eps": np.zeros(n_layers), "sigf": np.zeros(n_layers), "z": np.zeros((n_layers, n_terms)),
                   "origin_eps": np.zeros((2, n_layers)), "origin_sig": np.zeros((2, n_layers)),
                   "x": np.zeros(len(chs)), "force": np.zeros(len(chs)), "tangent": self._initial_tangent(),
                   "slope": np.full(n_layers, 2.0 * co.mu + co.sigma_f_max / co.eps_half)}

    @classmethod
    def from_design(cls, design: Design, slices: int = 1, band=DEFAULT_BAND, channels=None) -> Element:
        """The element of ``design`` (:func:`core.element.coefficients`), fresh from rest."""
        return cls(coefficients(design, slices, band), channels)

    def channel(self, name: str) -> Element:
        """A fresh element of the one channel ``name`` (its input and output are length-1 arrays)."""
        return Element(self.coefficients, (name,))

    def fractional_response(self, frequency_hz, h: float):
        """What the element's fractional term gives for a harmonic drive sampled every ``h`` s
        and held over each step, per unit of (iω)^α's coefficient: at the step ends,
        Σ_j g_j d_j (1 − e^{−iωh}) / (1 − d_j e^{−iωh}), d_j = e^{−λ_j h} (complex; α = 1: the
        mean rate over the step, (1 − e^{−iωh})/h). Compare with (iω)^α."""
        w = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)
        e = np.exp(-1j * w * h)
        if not self._rates.size:
            return (1.0 - e) / h
        d = np.exp(-self._rates * h)
        return (d * self._weights * (1.0 - e[..., None]) / (1.0 - d * e[..., None])).sum(axis=-1)

    def held_error(self, h: float) -> tuple[float, float]:
        """The fractional term's largest relative magnitude error and phase error (rad) inside
        the band with the input held over steps of ``h`` s: :meth:`fractional_response` against
        (iω)^α, the fit's own error included."""
        f1, f2 = self.band
        f = np.geomspace(f1, f2, max(int(CHECK_POINTS_PER_DECADE * np.log10(f2 / f1) / 5), 50))
        r = self.fractional_response(f, h) / (2j * np.pi * f) ** self.coefficients.alpha
        return float(np.max(np.abs(np.abs(r) - 1.0))), float(np.max(np.abs(np.angle(r))))

    # ---- state --------------------------------------------------------------------------

    def state(self) -> dict:
        """A copy of the state: plain float arrays and the format's ``version``."""
        out = {k: v.copy() for k, v in self._s.items()}
        out["version"] = STATE_VERSION
        return out

    def restore(self, state: dict) -> None:
        """Set the state to ``state`` (from :meth:`state`, of an element of the same coefficients
        and channels), copying it; ValueError if it does not fit."""
        if not isinstance(state, dict) or state.get("version") != STATE_VERSION:
            raise ValueError(f"state: not an element state of version {STATE_VERSION}")
        new = {}
        for k in _STATE_KEYS:
            v = np.array(state.get(k), dtype=float)
            if v.shape != self._s[k].shape or not np.all(np.isfinite(v)):
                raise ValueError(f"state: {k} must be finite numbers of shape {self._s[k].shape}")
            new[k] = v
        self._s = new

    # ---- steps --------------------------------------------------------------------------

    def trial(self, x, h: float) -> np.ndarray:
        """The forces (N, N·m) after a step of ``h`` s with the inputs ``x`` (m, rad) held over it;
        the state is unchanged."""
        return self._step(x, h)[0].copy()

    def commit(self, x, h: float) -> np.ndarray:
        """:meth:`trial`, and the state advances to the end of the step."""
        force, eps, sf, tangent, xv, decay = self._step(x, h)
        s = self._s
        s["z"] = (s["z"] + (eps - s["eps"])[:, None]) * decay
        s["origin_eps"], s["origin_sig"] = layers.moved(eps, s["eps"], sf, s["origin_eps"], s["origin_sig"])
        s["eps"], s["sigf"] = eps, sf
        s["x"], s["force"] = xv, force
        s["tangent"], s["slope"] = tangent
        return force.copy()

    # ---- inside -------------------------------------------------------------------------

    def _initial_tangent(self) -> np.ndarray:
        """dF/dx at rest, elastic with friction's initial slope: the first step's predictor."""
        mu, _, smax, half = self._mat
        layer = self._inv_c * self._p / (2.0 * mu + smax / half)
        compliance = np.empty(len(self.channels))
        compliance[self._direct_ch] = layer[: self._nd]
        compliance[self._series_ch] = self._sum @ layer[self._nd:] + self._compliance
        return 1.0 / compliance

    def _decay(self, h: float) -> np.ndarray:
        """(e^{−λ_j h}, g_j e^{−λ_j h}) stacked, remembered per step length."""
        got = self._h_cache.get(h)
        if got is None:
            if len(self._h_cache) >= _H_CACHE:
                self._h_cache.clear()
            decay = np.exp(-self._rates * h)
            got = self._h_cache[h] = np.stack([decay, self._weights * decay])
        return got

    def _check(self, x, h):
        h = float(h) if isinstance(h, (int, float, np.floating, np.integer)) and not isinstance(h, bool) else None
        if h is None or not (0.0 < h < np.inf):
            raise ValueError("h: the step must be a positive finite number of seconds")
        xv = np.asarray(x, dtype=float).reshape(-1)
        if xv.size != len(self.channels) or not np.all(np.isfinite(xv)):
            raise ValueError(f"x: give {len(self.channels)} finite inputs ({', '.join(self.channels)}; m and rad)")
        if h not in self._warned:
            self._warned.add(h)
            mag, phase = self.held_error(h)
            if mag > HELD_LIMIT[0] or phase > HELD_LIMIT[1]:
                warnings.warn(ElementWarning(
                    f"step {h:.3g} s: with the input held over it, the fractional term is up to "
                    f"{100 * mag:.2g} % and {phase:.2g} rad off (iω)^α in the band {self.band[0]:g}–"
                    f"{self.band[1]:g} Hz (warned above {100 * HELD_LIMIT[0]:g} %, {HELD_LIMIT[1]:g} rad): "
                    "take a shorter step or a lower band top"), stacklevel=4)
        return xv, h

    def _step(self, x, h):
        xv, h = self._check(x, h)
        s = self._s
        co = self.coefficients
        decay = self._decay(h)
        a, b = layers.linear_part(co.mu, co.m, co.viscosity, h, decay[1], s["z"], s["eps"])
        mu, beta, smax, half = self._mat
        A, B = layers.branch_shape(s["origin_sig"], smax, half)
        force = np.empty(len(self.channels))
        tangent = s["tangent"]
        layer_slope = s["slope"]
        nd = self._nd
        if nd == len(self._p):  # every channel direct
            eps = xv[self._direct_ch] * self._c
        else:
            eps = np.empty_like(s["eps"])
            eps[:nd] = xv[self._direct_ch] * self._c[:nd]
            tangent = tangent.copy()
            layer_slope = layer_slope.copy()
            i = slice(nd, None)
            solve = layers.Inverse(a, b[i], s["eps"][i], s["sigf"][i], s["origin_eps"][:, i], s["origin_sig"][:, i],
                                   A[:, i], B[:, i], mu, beta)
            f, eps[i], dxdf, layer_slope[i] = self._solve(xv[self._series_ch], solve)
            force[self._series_ch] = f
            tangent[self._series_ch] = 1.0 / dxdf
        sf = layers.friction(eps, s["eps"], s["sigf"], s["origin_eps"], s["origin_sig"], A, B)
        if nd:
            sigma = a * eps[:nd] + b[:nd] + sf[:nd]
            if beta:
                sigma = sigma + 2.0 * mu * beta * eps[:nd] ** 3
            force[self._direct_ch] = sigma / self._p[:nd]
        else:
            self.iterations = 0
        return force, eps, sf, (tangent, layer_slope), xv, decay[0]

    def _solve(self, x, inverse):
        """Newton on each series channel's force F, with a bracket: Σ ε_k(p_k F)/c_k + C_b F = x.
        Returns (F, the layers' strains, dx/dF)."""
        comp = self._compliance
        s = self._s
        ch = self._series_ch
        k = s["tangent"][ch]
        # predictor: the last tangent, with the layers' stress at their committed strains under
        # this step's memory (the relaxation since the last step) moved along their last slopes
        relax = self._drive @ ((inverse.kink - s["force"][ch] @ self._to_layers) / s["slope"][self._nd:])
        f = s["force"][ch] + k * (x - s["x"][ch] + relax)
        tol = TOLERANCE * (np.abs(x) + np.abs(s["force"][ch]) / k)  # the layers' displacements' size
        tried = []  # (F, residual) of the iterations: the bracket where Newton needs one
        bracket = None
        for it in range(1, MAX_ITER + 1):
            tau = f @ self._to_layers
            e, slope = inverse(tau)
            g = self._drive @ e - x
            dg = self._drive_slope @ (1.0 / slope)
            if self._any_compliance:
                g += comp * f
                dg += comp
            small = np.abs(g)
            done = small <= tol
            if bracket is not None:  # a bracket as narrow as the floats allow counts as converged
                lo, hi = bracket
                done |= np.isfinite(hi - lo) & (hi - lo <= 4e-16 * np.maximum(np.abs(lo), np.abs(hi)))
            if done.all():
                self.iterations = it
                return f, e, dg, slope
            step = -g / dg
            if bracket is None and (small <= LAST_STEP * tol / TOLERANCE).all():
                # close enough that Newton's next residual, ~ (G''/2) step², is far below the
                # tolerance: take the step without another evaluation (the layers' strains along
                # their tangents), unless a layer would cross its friction kink in it
                dtau = step @ self._to_layers
                if ((tau + dtau > inverse.kink) == (tau > inverse.kink)).all():
                    self.iterations = it
                    return f + step, e + dtau / slope, dg, slope
            tried.append((f, g))
            new = f + step
            if it >= 2:  # Newton should have converged by now: keep it inside the bracket
                fs, gs = np.array([t[0] for t in tried]), np.array([t[1] for t in tried])
                lo = np.max(np.where(gs < 0, fs, -np.inf), axis=0)
                hi = np.min(np.where(gs > 0, fs, np.inf), axis=0)
                bracket = lo, hi
                new = bracketed(new, step, lo, hi)
            f = np.where(done, f, new)  # a channel that has converged stays where it is
        bad = int(np.argmax(np.abs(g) / tol))
        raise ConvergenceError(
            f"element: the series solve of channel {self.channels[ch[bad]]} did not converge in {MAX_ITER} "
            f"iterations (input {x[bad]:.6g}, residual {abs(g[bad]) / tol[bad] * TOLERANCE:.2e} of its size)")
