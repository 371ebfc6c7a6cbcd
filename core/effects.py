"""Effects the thesis model leaves out: named, parameterised extensions (docs/model.md's table).

Each effect is a small record: its id (as in docs/model.md and the design file's ``effects``
object), a title, its parameters with units, the physics in plain words and the signature it
leaves in measured stiffness. How an effect enters the model is in one of three places:

* material level (:func:`extended_modulus`): ``viscous``, ``strain_stiffening``,
  ``rate_amplitude_coupling`` change µ_eq(ω, ε̂);
* stiffness level (:mod:`core.bushing`): ``inertia`` (K − ω²M), ``wave_effects`` (standing
  shear waves, :func:`wave_stiffness`), ``nonuniform_strain`` (the continuum model);
* the branches themselves: ``friction`` and ``fractional`` are the thesis' own branches, whose
  parameters live in the design's ``material``; they are named here so that a baseline without
  them can be extended by them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import special

from .material import REFERENCE_FREQUENCY_HZ
from .material import branch_moduli as material_branch_moduli
from .parameters import BRANCH_PARAMETERS, BY_NAME, MODE, MODES, TRANSLATIONS, Parameter
from .parts import Material
from .rules import BAD_CHOICE, BAD_TYPE, MISSING_KEY, NEGATIVE, UNKNOWN_KEY, DesignError, excerpt
from .rules import number as _number
from .shape import long_shape_factor


def _branch(branch: str) -> tuple[Parameter, ...]:
    """The parameters of one of the thesis' branches, as the table of design parameters has them."""
    return tuple(BY_NAME[name].fitting for name in BRANCH_PARAMETERS[branch])


@dataclass(frozen=True)
class Effect:
    id: str
    title: str
    parameters: tuple[Parameter, ...]
    physics: str
    signature: str
    branch: bool = False  # one of the thesis' own branches (parameters live in `material`)
    requires: tuple[str, ...] = ()  # acts only on one of these (branches or effects)
    excludes: tuple[str, ...] = ()  # cannot be combined with these effects
    # lives on one test rig, not in the rubber: it acts in the mode it was measured in only (a
    # design file writes it for another mode as ``id@mode``, :func:`split_id`)
    rig: bool = False
    # a material-level effect's frequency-domain term: (material, its parameters, f in Hz, ε̂,
    # the thesis' own branch moduli) → (the branch it enters, what it adds to that branch's
    # modulus µ_eq, in Pa). The one
    # source of the effect's physics for the closed-form route: the equivalent modulus, the
    # branch-by-branch stiffness and the loop's branch amplitudes are derived from it.
    term: Callable[..., tuple[str, Any]] | None = None

    def fitting_name(self, parameter: str) -> str:
        """A parameter's name in fits and their reports: a branch's parameters are the
        material's, an added effect's are ``effect_id.name``."""
        return parameter if self.branch else f"{self.id}.{parameter}"


def _stiffening_term(material, p, f, eps, _base):
    """σ_el = 2µε(1 + βε²): its first harmonic at ε = ε̂ sin ωt is 2µ(1 + ¾βε̂²) ε̂."""
    return "elastic", material.shear_modulus * 0.75 * p["stiffening"] * eps**2


def _viscous_term(_material, p, f, _eps, _base):
    """σ = c dε/dt: µ_eq += iωc / 2."""
    return "viscoelastic", 1j * np.pi * f * p["viscosity"]


def _rate_term(_material, p, f, _eps, base):
    """µ_f(ε̂) (f / 10 Hz)^γ in place of µ_f(ε̂)."""
    return "friction", base["friction"] * ((f / REFERENCE_FREQUENCY_HZ) ** p["rate_exponent"] - 1.0)


EFFECTS: dict[str, Effect] = {
    e.id: e
    for e in (
        Effect(
            "friction",
            "Amplitude dependence (Fletcher–Gent effect)",
            _branch("friction"),
            "The carbon-black filler network breaks and re-forms as the rubber is strained: "
            "a rate-independent friction stress that saturates at σ_fmax (Berg's smooth "
            "friction).",
            "Stiffness falls and the loss factor first rises then falls as the amplitude "
            "grows, at every frequency alike.",
            branch=True,
        ),
        Effect(
            "fractional",
            "Frequency dependence (fractional viscoelasticity)",
            _branch("fractional"),
            "The rubber's polymer chains relax over a broad spectrum of times, which a "
            "fractional derivative of order α captures with two numbers.",
            "Stiffness rises as a power of frequency and the loss factor is nearly constant "
            "over decades of frequency.",
            branch=True,
        ),
        Effect(
            "inertia",
            "Apparent mass seen by the force sensor",
            # its unit is the mode's apparent mass' (Mode.mass): kg, kg·m² in the rotations
            (Parameter("mass", MODE[TRANSLATIONS[0]].mass,
                       "apparent mass M (a moment of inertia in torsion and conical)", (1e-12, 1e4),
                       mode_unit="mass"),),
            "Mass between the rubber and the force sensor (fixture, part of the rubber) is "
            "accelerated with the drive; its inertial force adds to the rubber's.",
            "Measured stiffness falls below the model more and more at high frequency, as ω², "
            "the same at every amplitude; the loss factor rises with it.",
            rig=True,
        ),
        Effect(
            "viscous",
            "Integer-order viscous damping",
            (Parameter("viscosity", "Pa·s", "viscous coefficient c (σ = c dε/dt)", (1e-3, 1e9)),),
            "A damping stress proportional to the strain rate, as from a fluid or a very "
            "fast relaxation mechanism.",
            "The loss factor grows in proportion to frequency at every amplitude, more than "
            "the fractional branch allows.",
            term=_viscous_term,
        ),
        Effect(
            "strain_stiffening",
            "Elastic stiffening at large strain",
            (Parameter("stiffening", "–", "β in σ_el = 2µε(1 + βε²)", (1e-6, 1e9)),),
            "The rubber network stiffens as its chains approach their full extension.",
            "At the largest amplitudes the stiffness is higher than the model, growing with "
            "the amplitude squared, at every frequency; the loss factor drops there.",
            term=_stiffening_term,
        ),
        Effect(
            "rate_amplitude_coupling",
            "Friction that stiffens with rate",
            (Parameter("rate_exponent", "–", "γ in µ_f · (f / 10 Hz)^γ", (0.0, 2.0), log=False),),
            "The filler network's friction is not quite rate independent: it stiffens at "
            "higher rates, which the separable model (friction independent of frequency) "
            "cannot show.",
            "The amplitude dependence is stronger at high frequency than at low: the gap "
            "between small- and large-amplitude stiffness grows with frequency.",
            requires=("friction",),
            term=_rate_term,
        ),
        Effect(
            "nonuniform_strain",
            "Non-homogeneous strain inside the bushing",
            (),
            "The strain is not one equivalent value: it varies across the rubber (as 1/r² in "
            "torsion, 1/r axially), so each layer softens by its own amplitude.",
            "At amplitudes in the knee of the Fletcher–Gent curve, the measured stiffness "
            "softens more gradually with amplitude than the single equivalent strain gives.",
            requires=("friction", "strain_stiffening"),
            excludes=("wave_effects",),
        ),
        Effect(
            "wave_effects",
            "Standing shear waves in the rubber",
            (Parameter("density", "kg/m³", "rubber density ρ (fitted within 300–5000, rubbers' range)",
                       (300.0, 5000.0)),),
            "The rubber's own mass: at high frequency shear waves stand across the rubber "
            "and the stiffness shows resonances.",
            "Stiffness rises above the model at the highest frequencies, steeply (towards a "
            "resonance), the same at every amplitude.",
            excludes=("nonuniform_strain",),
        ),
    )
}


def split_id(eid: str) -> tuple[str, str | None]:
    """An effect id of a design file and the mode it is tied to: ``inertia@torsion`` is the
    apparent mass of the torsion rig, carried by a design of another mode (``None``: the
    design's own mode, or every mode for an effect of the rubber)."""
    base, sep, mode = eid.partition("@")
    return base, (mode if sep else None)


def effect_of(eid: str) -> Effect:
    """The library's effect behind an id, mode-tied or not (:func:`split_id`)."""
    return EFFECTS[split_id(eid)[0]]


def effect_title(eid: str) -> str:
    """The name a person reads for an effect id: its title, and the rig of a mode-tied one
    ("Apparent mass seen by the force sensor on the torsion rig")."""
    base, mode = split_id(eid)
    return EFFECTS[base].title + (f" on the {mode} rig" if mode else "")


def validate_effects(effects: Any) -> dict[str, dict[str, float]]:
    """Check an ``effects`` object of a design file; return it as plain floats.

    Refuses unknown ids, the branch ids (their parameters belong in ``material``), unknown or
    missing parameters, non-numbers and negative values, naming the key. A rig effect may be
    tied to another mode as ``id@mode``; an effect of the rubber may not.
    """
    if not isinstance(effects, Mapping):
        raise DesignError("effects", "must be an object mapping effect ids to their parameters",
                          BAD_TYPE)
    out: dict[str, dict[str, float]] = {}
    for eid, params in effects.items():
        key = f"effects.{eid}"
        base, mode = split_id(str(eid))
        if base not in EFFECTS:
            raise DesignError(key, f"unknown effect (known: {', '.join(EFFECTS)})", UNKNOWN_KEY)
        effect = EFFECTS[base]
        if mode is not None and not effect.rig:
            rigs = ", ".join(e.id for e in EFFECTS.values() if e.rig)
            raise DesignError(key, f"only an effect of the test rig ({rigs}) can be tied to a mode; "
                                   f"{base} is the rubber's and acts in every mode", BAD_CHOICE)
        if mode is not None and mode not in MODES:
            raise DesignError(key, f"the mode after @ must be one of {', '.join(MODES)}, got {excerpt(repr(mode))}",
                              BAD_CHOICE)
        if effect.branch:
            raise DesignError(key, "is a branch of the material model; its parameters belong in "
                                   "material", BAD_CHOICE)
        if not isinstance(params, Mapping):
            raise DesignError(key, "must be an object of parameter values", BAD_TYPE)
        names = [p.name for p in effect.parameters]
        for name in params:
            if name not in names:
                allowed = ", ".join(names) or "none"
                raise DesignError(f"{key}.{name}", f"unknown parameter (allowed: {allowed})",
                                  UNKNOWN_KEY)
        values = {}
        for name in names:
            if name not in params:
                raise DesignError(f"{key}.{name}", "missing (required)", MISSING_KEY)
            v = _number(f"{key}.{name}", params[name])
            if v < 0:
                raise DesignError(f"{key}.{name}", f"must be ≥ 0, got {v!r}", NEGATIVE)
            values[name] = v
        out[eid] = values
    return out


# --------------------------------------------------------------------------------------------
# Material level
# --------------------------------------------------------------------------------------------


BRANCH_NAMES = ("elastic", "viscoelastic", "friction")


def branch_moduli(material: Material, effects: Mapping, frequency_hz, strain_amplitude) -> dict:
    """µ_eq(ω, ε̂) split by branch, broadcast over frequency and strain amplitude, in Pa:
    ``elastic`` µ, ``viscoelastic`` m (iω)^α / 2, ``friction`` µ_f(ε̂) (eq 16 by the closed-form
    route), each with the terms of the material-level effects that enter it (:attr:`Effect.term`)."""
    f = np.asarray(frequency_hz, dtype=float)
    eps = np.asarray(strain_amplitude, dtype=float)
    zeros = np.zeros(np.broadcast_shapes(f.shape, eps.shape), dtype=complex)
    base = {name: value + zeros for name, value in material_branch_moduli(material, f, eps).items()}
    out = dict(base)
    for eid, params in effects.items():
        term = EFFECTS[eid].term
        if term is not None:
            branch, value = term(material, params, f, eps, base)
            out[branch] = out[branch] + value
    return out


def extended_modulus(material: Material, effects: Mapping, frequency_hz, strain_amplitude):
    """µ_eq with the material-level effects, broadcast over frequency and strain amplitude: the
    sum of :func:`branch_moduli`, µ (1 + ¾ β ε̂²) + m (iω)^α / 2 + i ω c / 2 + µ_f(ε̂) (f / 10 Hz)^γ."""
    parts = branch_moduli(material, effects, frequency_hz, strain_amplitude)
    return parts["elastic"] + parts["viscoelastic"] + parts["friction"]


# --------------------------------------------------------------------------------------------
# Stiffness level
# --------------------------------------------------------------------------------------------


def inertia_correction(stiffness, frequency_hz, mass: float):
    """K_measured = K − ω² M (M in kg in axial and radial, kg·m² in torsion and conical)."""
    omega = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)
    return stiffness - omega**2 * mass


# |Im ka| beyond which the standing waves' cross product is taken from scaled Hankel functions:
# J_n and Y_n's products then cancel to e^−4 of their size at most on the other side
DECAYING = 2.0


def wave_stiffness(mode: str, inner_radius, outer_radius, length, modulus, frequency_hz, density):
    """Stiffness with standing shear waves in the rubber (docs/model.md, ``wave_effects``).

    Axial: w'' + w'/r + k² w = 0, k² = ρω²/µ_eq, w(a) = 0, w(b) = d, so
    w = A J0(kr) + B Y0(kr) and K = 2π a L µ_eq w'(a) / d.
    Torsion: v = rθ, v'' + v'/r − v/r² + k² v = 0, v(a) = 0, v(b) = bφ, so
    v = A J1(kr) + B Y1(kr) and K = 2π a² L µ_eq v'(a) / φ (τ = µ_eq (v' − v/r) at r = a).
    Tends to eqs 17/18 as ρω²/µ → 0, and is that limit where |kb| < 1e-6 (ρ = 0 included: its
    Bessel functions of the second kind diverge at 0; the rest is O((kb)²) below 1e-12).
    Broadcast over ``modulus`` and ``frequency_hz``.
    """
    a, b, L = inner_radius, outer_radius, length
    mu = np.asarray(modulus, dtype=complex)
    omega = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)
    k = omega * np.sqrt(density / mu)
    static = np.abs(k * b) < 1e-6
    if np.any(static):
        with np.errstate(all="ignore"):
            waves = _standing_waves(mode, a, b, L, mu, np.where(static, 1.0 / b, k))
        waves = np.where(static, long_shape_factor(a, b, L, mode) * mu, waves)
    else:
        waves = _standing_waves(mode, a, b, L, mu, k)
    lost = (waves == 0) & (mu != 0)  # below the least double: no loss factor, no number
    if np.any(lost):
        where = np.argwhere(lost)[0]
        f = np.broadcast_to(np.asarray(frequency_hz, dtype=float), lost.shape)[tuple(where)]
        raise ValueError(f"wave_effects: at {f:.6g} Hz the shear waves die out across the rubber: the stiffness "
                         "they pass to the inner sleeve is below the smallest number the computation holds; "
                         "lower the frequency, or check the density, the moduli and the radii")
    return waves


def _standing_waves(mode: str, a, b, L, mu, k):
    """:func:`wave_stiffness`'s Bessel solution at wavenumber ``k`` (complex, nonzero).

    With u = A Z(kr) + B W(kr) (order n = 0 axially, 1 in torsion) held at r = a and driven at
    r = b, the Wronskian J_n'(z) Y_n(z) − J_n(z) Y_n'(z) = −2/(π z) makes the inner face's traction
    a ratio of one cross product: K = 4 L µ_eq / D_0 axially and K = 4 a b L µ_eq / D_1 in
    torsion, D_n = J_n(ka) Y_n(kb) − J_n(kb) Y_n(ka). Where the waves decay across the rubber
    (|Im ka| above :data:`DECAYING`) J and Y grow like e^|Im z| and their products cancel to
    e^−2|Im ka| of their size, all of it past |Im ka| ≈ 18 (at 1 MHz: NaN in torsion, a wrong sign
    axially); D_n is then taken from the exponentially scaled Hankel functions, the growing
    exponential factored out: D_n = (H²_n(ka) H¹_n(kb) − H¹_n(ka) H²_n(kb)) / 2i."""
    n = 0 if mode == "axial" else 1
    k = np.asarray(k, dtype=complex)
    ka, kb = np.broadcast_arrays(k * a, k * b)  # a geometry of samples: a row each
    inverse = np.empty(ka.shape, dtype=complex)  # 1 / D_n
    decaying = np.abs(ka.imag) > DECAYING
    near = ~decaying
    if near.any():
        za, zb = ka[near], kb[near]
        inverse[near] = 1.0 / (special.jv(n, za) * special.yv(n, zb) - special.jv(n, zb) * special.yv(n, za))
    if decaying.any():
        za, zb = ka[decaying], kb[decaying]
        d = zb - za  # H¹(z) = h¹(z) e^{iz}, H²(z) = h²(z) e^{−iz}: D_n 2i = h²_a h¹_b e^{id} − h¹_a h²_b e^{−id}
        up = d.imag < 0  # e^{id} the larger
        phase = np.exp(np.where(up, -1j * d, 1j * d))  # the smaller of e^{±id}, |phase| ≤ 1
        ab, ba = special.hankel2e(n, za) * special.hankel1e(n, zb), special.hankel1e(n, za) * special.hankel2e(n, zb)
        inverse[decaying] = 2j * phase / np.where(up, ab - ba * phase**2, ab * phase**2 - ba)
    factor = 4.0 * L if mode == "axial" else 4.0 * a * b * L
    return factor * mu * inverse
