"""The stateful time-domain element: six uncoupled channels, one step at a time, O(1) per step
(docs/element.md).

:class:`Element` keeps each layer's state as Python floats (the layers are few: NumPy's cost
per call would dominate) and the exponentials' states as one array (layers × terms), so a step
is a handful of array operations and O(layers) float arithmetic whatever the history. A
channel of one layer without a bulk spring needs no solve: its strain is c·x. A channel of
layers in series (slices, or a bulk spring) solves for its force F by Newton's method on
Σ_k ε_k(p_k F)/c_k + C_b F = x, each layer's strain ε_k(τ) exact on its friction branch
(:func:`core.element.layers.strain`), safeguarded by a bracket on F (bisection where a friction
kink throws Newton outside it or Newton stops halving the residual), to 1e−13 of the size of
the equation's terms.
"""

from __future__ import annotations

import math
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
_LISTS = ("eps", "sigf", "x", "force", "tangent", "slope")  # kept as lists of floats inside
_H_CACHE = 64  # step lengths remembered (e^{−λh} per h)
HELD_LIMIT = (0.01, 0.01)  # relative magnitude, phase (rad): the fractional term's error that warns


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
        p = 2.0 * c / S  # stress (Pa) per unit force
        self._p, self._c, self._inv_c = p.tolist(), c.tolist(), (1.0 / c).tolist()
        # the direct channels (channel, layer) and the series ones (channel, first, end, C_b)
        self._direct = list(zip(self._direct_ch.tolist(), range(self._nd), strict=True))
        ends = self._nd + np.cumsum([len(chs[i].S) for i in self._series_ch])
        self._series = [(int(i), int(e - len(chs[i].S)), int(e), float(compliance[i]))
                        for i, e in zip(self._series_ch, ends, strict=True)]
        # per series channel, per layer: (p_k, 1/c_k, p_k/c_k)
        self._series_layers = [tuple((self._p[j], self._inv_c[j], self._p[j] * self._inv_c[j]) for j in range(first, end))
                               for _, first, end, _ in self._series]
        self._rates = np.array(co.rate)
        self._weights = np.array(co.weight)
        self._mat = (co.mu, co.beta, co.sigma_f_max, co.eps_half)
        self._k3 = 2.0 * co.mu * co.beta  # Pa: the cubic's coefficient 2µβ
        self._h_cache: dict[float, tuple] = {}
        self._warned: set[float] = set()
        self.iterations = 0  # Newton iterations of the last step's series solve (the most of its channels)
        n_layers, n_terms = S.size, self._rates.size
        zeros = [0.0] * n_layers
        self._s = {"eps": list(zeros), "sigf": list(zeros), "z": np.zeros((n_layers, n_terms)),
                   "origin": [(0.0, 0.0, 0.0, 0.0)] * n_layers, "x": [0.0] * len(chs), "force": [0.0] * len(chs), "tangent": self._initial_tangent(),
                   "slope": [2.0 * co.mu + co.sigma_f_max / co.eps_half] * n_layers}

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
        s = self._s
        out = {k: np.array(s[k], dtype=float) for k in _LISTS}
        out["z"] = s["z"].copy()
        origin = np.array(s["origin"], dtype=float).reshape(-1, 4).T
        out["origin_eps"], out["origin_sig"] = origin[0::2].copy(), origin[1::2].copy()
        out["version"] = STATE_VERSION
        return out

    def restore(self, state: dict) -> None:
        """Set the state to ``state`` (from :meth:`state`, of an element of the same coefficients
        and channels), copying it; ValueError if it does not fit."""
        if not isinstance(state, dict) or state.get("version") != STATE_VERSION:
            raise ValueError(f"state: not an element state of version {STATE_VERSION}")
        n_layers = len(self._p)
        shapes = {k: (len(self._s[k]),) for k in _LISTS}
        shapes.update(z=self._s["z"].shape, origin_eps=(2, n_layers), origin_sig=(2, n_layers))
        got = {}
        for k in _STATE_KEYS:
            try:
                v = np.array(state.get(k), dtype=float)
            except (TypeError, ValueError):
                v = None
            if v is None or v.shape != shapes[k] or not np.all(np.isfinite(v)):
                raise ValueError(f"state: {k} must be finite numbers of shape {shapes[k]}")
            got[k] = v
        new = {k: got[k].tolist() for k in _LISTS}
        new["z"] = got["z"]
        oe, os = got["origin_eps"].tolist(), got["origin_sig"].tolist()
        new["origin"] = list(zip(oe[0], os[0], oe[1], os[1], strict=True))
        self._s = new

    # ---- steps --------------------------------------------------------------------------

    def trial(self, x, h: float) -> np.ndarray:
        """The forces (N, N·m) after a step of ``h`` s with the inputs ``x`` (m, rad) held over it;
        the state is unchanged."""
        return np.array(self._step(x, h)[0])

    def commit(self, x, h: float) -> np.ndarray:
        """:meth:`trial`, and the state advances to the end of the step."""
        force, eps, sf, tangent, slope, xs, decay = self._step(x, h)
        s = self._s
        last = s["eps"]
        z = s["z"]  # the element's own (state() and restore() copy)
        z += np.array([e - e_last for e, e_last in zip(eps, last, strict=True)])[:, None]
        z *= decay
        moved = layers.moved
        s["origin"] = [moved(o, e, e_last, f) for o, e, e_last, f in zip(s["origin"], eps, last, sf, strict=True)]
        s["eps"], s["sigf"] = eps, sf
        s["x"], s["force"] = xs, force
        s["tangent"], s["slope"] = tangent, slope
        return np.array(force)

    # ---- inside -------------------------------------------------------------------------

    def _initial_tangent(self) -> list[float]:
        """dF/dx at rest, elastic with friction's initial slope: the first step's predictor."""
        mu, _, smax, half = self._mat
        layer = [ic * p / (2.0 * mu + smax / half) for ic, p in zip(self._inv_c, self._p, strict=True)]
        tangent = [0.0] * len(self.channels)
        for ch, k in self._direct:
            tangent[ch] = 1.0 / layer[k]
        for ch, first, end, comp in self._series:
            tangent[ch] = 1.0 / (sum(layer[first:end]) + comp)
        return tangent

    def _decay(self, h: float) -> tuple:
        """(e^{−λ_j h}, a, k) per step length, remembered: a = 2µ + k and k = m Σ_j g_j e^{−λ_j h} +
        c_v/h (Pa) of :mod:`core.element.layers`, and the array of g_j e^{−λ_j h}."""
        got = self._h_cache.get(h)
        if got is None:
            if len(self._h_cache) >= _H_CACHE:
                self._h_cache.clear()
            co = self.coefficients
            decay = np.exp(-self._rates * h)
            wh = self._weights * decay
            k = co.m * float(np.sum(wh)) + co.viscosity / h
            got = self._h_cache[h] = (decay, wh, 2.0 * co.mu + k, k)
        return got

    def _check(self, x, h):
        if isinstance(h, bool) or not isinstance(h, (int, float, np.floating, np.integer)) or not 0.0 < h < math.inf:
            raise ValueError("h: the step must be a positive finite number of seconds")
        h = float(h)
        try:
            xs = np.asarray(x, dtype=float).reshape(-1).tolist()
        except (TypeError, ValueError):
            xs = None
        if xs is None or len(xs) != len(self.channels) or not all(map(math.isfinite, xs)):
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
        return xs, h

    def _step(self, x, h):
        """(forces, the layers' strains and friction stresses, tangents dF/dx, the layers' slopes
        dσ/dε, inputs, e^{−λ_j h}) after a step: lists of floats, and the decays' array."""
        xs, h = self._check(x, h)
        s = self._s
        decay, wh, a, k = self._decay(h)
        mu, beta, smax, half = self._mat
        m = self.coefficients.m
        last, sigf = s["eps"], s["sigf"]
        b = [m * zw - k * e for zw, e in zip(s["z"].dot(wh).tolist(), last, strict=True)]
        origin = s["origin"]
        ratio = half / smax
        k3 = 2.0 * mu * beta
        n = len(last)
        eps, sf = [0.0] * n, [0.0] * n
        force = [0.0] * len(xs)
        friction, stress = layers.friction, layers.stress
        for ch, j in self._direct:
            e = eps[j] = xs[ch] * self._c[j]
            f = sf[j] = friction(e, last[j], sigf[j], origin[j], smax, ratio)
            force[ch] = stress(e, a, b[j], f, k3) / self._p[j]
        tangent, slope = s["tangent"], s["slope"]
        self.iterations = 0
        if self._series:
            tangent, slope = list(tangent), list(slope)
            for (ch, first, end, comp), static in zip(self._series, self._series_layers, strict=True):
                law = [(pk, ik, pik, b[j], stress(last[j], a, b[j], sigf[j], k3), origin[j], slope[j])
                       for j, (pk, ik, pik) in zip(range(first, end), static, strict=True)]
                f, dxdf, eps[first:end], slope[first:end] = self._solve(ch, xs[ch], comp, a, law)
                force[ch], tangent[ch] = f, 1.0 / dxdf
                for j in range(first, end):
                    sf[j] = friction(eps[j], last[j], sigf[j], origin[j], smax, ratio)
        return force, eps, sf, tangent, slope, xs, decay

    def _solve(self, ch, x, compliance, a, law):
        """Newton on one series channel's force F (N or N·m), with a bracket: Σ ε_k(p_k F)/c_k +
        C_b F = x; ``law`` holds each layer's (p_k, 1/c_k, p_k/c_k, b, kink, branch origins, last
        slope) of :func:`core.element.layers.strain`. Returns (F, dx/dF, the layers' strains, their
        slopes dσ/dε)."""
        s = self._s
        _, _, smax, half = self._mat
        k3 = self._k3
        ratio = half / smax
        on_branch = layers.on_branch
        f_last = s["force"][ch]
        # predictor: the last tangent, with the layers' stress at their committed strains under
        # this step's memory (the relaxation since the last step) moved along their last slopes
        relax = 0.0
        for pk, ik, _, _, kink, _, sl in law:
            relax += ik * (kink - f_last * pk) / sl
        f = f_last + s["tangent"][ch] * (x - s["x"][ch] + relax)
        lo, hi = -math.inf, math.inf
        g = size = math.nan
        last_small = math.inf
        for it in range(1, MAX_ITER + 1):
            g, dg = compliance * f - x, compliance
            size = abs(x) + abs(compliance * f)  # the size of the equation's terms: their rounding
            es, sls = [], []
            for pk, ik, pik, b, kink, o, _ in law:
                tau = pk * f
                if k3:
                    e, sl = layers.strain(tau, a, b, kink, o, smax, half, k3)
                    origin_eps = o[0] if tau > kink else o[2]
                elif tau > kink:  # layers.strain without stiffening, inline: the hot loop
                    e, sl = on_branch(tau, a, b, o[0], o[1], 1.0, smax, ratio)
                    origin_eps = o[0]
                else:
                    e, sl = on_branch(tau, a, b, o[2], o[3], -1.0, smax, ratio)
                    origin_eps = o[2]
                es.append(e)
                sls.append(sl)
                g += e * ik
                # ε = ε_s + s v is as exact as the larger of |ε| and |ε_s| allows
                size += max(abs(origin_eps), abs(e)) * ik
                dg += pik / sl
            if not (math.isfinite(g) and math.isfinite(dg)):
                break
            small = abs(g)
            step = -g / dg
            new = f + step
            if small <= TOLERANCE * size or new == f:
                break
            if small <= LAST_STEP * size:
                # close enough that Newton's next residual, ~ (G''/2) step², is far below the
                # tolerance: take the step without another evaluation (the layers' strains along
                # their tangents), unless a layer would cross its friction kink in it
                for pk, _, _, _, kink, _, _ in law:
                    if (pk * f + pk * step > kink) != (pk * f > kink):
                        break
                else:
                    es = [e + law_k[0] * step / sl for e, law_k, sl in zip(es, law, sls, strict=True)]
                    f = new
                    break
            if g < 0.0:
                lo = f
            else:
                hi = f
            inside = lo < new < hi
            if not inside and (math.isinf(lo) or math.isinf(hi)):
                break  # the step moved F by less than its resolution
            # bisect where Newton leaves the bracket (a friction kink) or stops halving the
            # residual (it can cycle across an inflection of strong stiffening)
            if not inside or (small > 0.5 * last_small and not (math.isinf(lo) or math.isinf(hi))):
                new = 0.5 * (lo + hi)
                if new in (lo, hi):  # a bracket as narrow as the floats allow
                    break
            last_small = small
            f = new
        else:
            raise ConvergenceError(
                f"element: the series solve of channel {self.channels[ch]} did not converge in {MAX_ITER} "
                f"iterations (input {x:.6g}, residual {abs(g) / size:.2e} of its size)")
        if not (math.isfinite(f) and math.isfinite(g)):
            raise ConvergenceError(f"element: the series solve of channel {self.channels[ch]} met a "
                                   f"non-finite force or strain (input {x:.6g})")
        self.iterations = max(self.iterations, it)
        return f, dg, es, sls
