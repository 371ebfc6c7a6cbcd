"""The element's coefficients from a design (docs/element.md, "Coefficients").

Six channels at the bushing's centre, axis z: ``dx``, ``dy`` radial, ``dz`` axial, ``rx``, ``ry``
conical, ``rz`` torsion, each the design turned to its direction (:meth:`Design.in_mode`). A
channel is a stack of layers in series, layer k with shape factor S_k (m or m³/rad) and strain
factor c_k (1/m or 1/rad), plus a linear compliance C_b (m/N or rad/(N·m)) where a bulk modulus
squeezes the rubber. N slices (:func:`core.slices.slice_nodes`) are layers where the core
derives slices (axial and torsion with the long shape factors); elsewhere one layer.

The bulk modulus: where the finite-length table's series law holds, a shear layer in series
with the compliance C_b (:func:`core.compressible.bulk_series`, the one place of that form; the
hysteresis loop uses it too). The long radial closed form of a compressible rubber has no global
series form; its series is matched at one operating point (:func:`core.compressible.series_at`
at :data:`core.compressible.REFERENCE_FREQUENCY` and :data:`core.compressible.REFERENCE_STRAIN`),
exact there and within the bound docs/element.md states elsewhere.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from ..bushing import STRUCTURAL_EFFECTS, modulus_function
from ..compressible import REFERENCE_FREQUENCY, REFERENCE_STRAIN, bulk_series, series_at
from ..design import Design
from ..parameters import MODE, THESIS_MODES
from ..slices import slice_nodes
from .prony import DEFAULT_BAND, MAGNITUDE_TARGET, PHASE_TARGET, check_band, fit_power

CHANNELS = ("dx", "dy", "dz", "rx", "ry", "rz")
OUTPUTS = ("fx", "fy", "fz", "mx", "my", "mz")
CHANNEL_MODES = {"dx": "radial", "dy": "radial", "dz": "axial", "rx": "conical", "ry": "conical", "rz": "torsion"}
MAX_SLICES = 100
# effects with no time-domain form, and why (docs/element.md)
REFUSED_EFFECTS = {
    "rate_amplitude_coupling": "it is defined for harmonic drives only (friction scaled by the drive frequency)",
    "nonuniform_strain": "use slices instead (the continuum has no finite set of layers)",
    "wave_effects": "the rubber's mass belongs in the simulation, not in the element",
    "inertia": "it is a test rig's apparent mass, not the bushing's",
}
assert set(STRUCTURAL_EFFECTS) <= set(REFUSED_EFFECTS)


# the material scalars: (name, unit, description), in the C kernel's order (enum BK_MU …
# BK_VISCOSITY in fmu/c/bushing_kernel.h); "alpha" in a unit stands for α's value
SCALARS = (
    ("mu", "Pa", "µ, the elastic branch's shear modulus"),
    ("m", "Pa.s^alpha", "m, the fractional branch's coefficient"),
    ("alpha", "1", "α, the fractional order (for reading: the weights carry it)"),
    ("sigma_f_max", "Pa", "σ_fmax, the friction stress limit (0: no friction)"),
    ("eps_half", "1", "ε½, the friction half strain"),
    ("beta", "1", "β, strain stiffening in 2µε(1 + βε²) (0: none)"),
    ("viscosity", "Pa.s", "c_v, the viscous coefficient (0: none)"),
)


class Parameter(NamedTuple):
    """One coefficient as the FMU carries it: its name, value (SI), unit and a sentence."""

    name: str
    value: float
    unit: str
    description: str


@dataclass(frozen=True)
class ChannelCoefficients:
    """One channel: its direction and its layers in series.

    Attributes
    ----------
    mode : str
        The design's mode for this channel (axial, torsion, radial, conical).
    shape : str
        The shape factor used (``long`` or ``finite``).
    S : tuple of float
        The layers' shape factors, m (translations) or m³/rad (rotations).
    c : tuple of float
        The layers' strain factors, 1/m or 1/rad.
    compliance : float
        The series bulk spring C_b, m/N or rad/(N·m) (0: none).
    sliced : bool
        Whether the channel got the asked slices (else one layer).
    """

    mode: str
    shape: str
    S: tuple[float, ...]
    c: tuple[float, ...]
    compliance: float
    sliced: bool

    def as_dict(self) -> dict:
        return {"mode": self.mode, "shape": self.shape, "S": list(self.S), "c": list(self.c),
                "compliance": self.compliance, "sliced": self.sliced}


@dataclass(frozen=True)
class Coefficients:
    """Everything the element (Python or C) needs, SI, by the names of docs/element.md.

    Attributes
    ----------
    mu, m, alpha, sigma_f_max, eps_half : float
        µ (Pa), m (Pa·s^α), α, σ_fmax (Pa), ε½.
    beta : float
        Strain stiffening β (0: none).
    viscosity : float
        c_v, Pa·s (0: none); with α = 1 it carries the fractional term m too.
    rate, weight : tuple of float
        λ_j (1/s) and g_j (s^−α) of the sum of exponentials (empty with α = 1).
    channels : dict of str to ChannelCoefficients
        By input name, in :data:`CHANNELS`' order.
    band : tuple of float
        (f₁, f₂), Hz: where the fit holds.
    magnitude_error, phase_error : float
        The fit's largest relative magnitude error and phase error (rad) inside the band.
    slices : int
        The slices asked.
    """

    mu: float
    m: float
    alpha: float
    sigma_f_max: float
    eps_half: float
    beta: float
    viscosity: float
    rate: tuple[float, ...]
    weight: tuple[float, ...]
    channels: dict
    band: tuple[float, float]
    magnitude_error: float
    phase_error: float
    slices: int

    @property
    def fractional_as_viscosity(self) -> bool:
        """α = 1: the fractional term is m·dε/dt, carried by :attr:`viscosity`."""
        return self.alpha == 1.0

    @property
    def meets_target(self) -> bool:
        return self.magnitude_error <= MAGNITUDE_TARGET and self.phase_error <= PHASE_TARGET

    @property
    def sliced_channels(self) -> tuple[str, ...]:
        return tuple(name for name, ch in self.channels.items() if ch.sliced)

    def as_dict(self) -> dict:
        """A JSON-able dict (lists for the arrays, channels nested by input name)."""
        return {
            "mu": self.mu, "m": self.m, "alpha": self.alpha, "sigma_f_max": self.sigma_f_max,
            "eps_half": self.eps_half, "beta": self.beta, "viscosity": self.viscosity,
            "rate": list(self.rate), "weight": list(self.weight),
            "channels": {name: ch.as_dict() for name, ch in self.channels.items()},
            "band": list(self.band), "magnitude_error": self.magnitude_error,
            "phase_error": self.phase_error, "slices": self.slices,
            "sliced_channels": list(self.sliced_channels),
        }

    def parameters(self) -> list[Parameter]:
        """The coefficients as :class:`Parameter` rows (name, value, unit, description): THE one
        list of their names, units and order (docs/element.md's table), which the FMU's
        ``modelDescription.xml`` carries as its parameters and its C kernel reads in this order.

        Order: the scalars ``mu`` … ``viscosity``, ``rate[1…J]``, ``weight[1…J]``, then per
        channel (``dx`` … ``rz``) ``S[1…N]``, ``c[1…N]``, ``compliance``. Indices count from 1
        (FMI's structured names). Units are SI names in ASCII, ``.`` a product (``N.m``), ``1``
        dimensionless; the fractional ones carry α's value (``Pa.s^0.2``, ``s^-0.2``)."""
        a = f"{self.alpha:.6g}"
        rows = [Parameter(name, getattr(self, name), unit.replace("^alpha", "" if a == "1" else f"^{a}"), text)
                for name, unit, text in SCALARS]
        rows += [Parameter(f"rate[{j}]", v, "1/s", f"λ_{j}, the rate of exponential {j}")
                 for j, v in enumerate(self.rate, 1)]
        rows += [Parameter(f"weight[{j}]", v, f"s^-{a}", f"g_{j}, the weight of exponential {j}")
                 for j, v in enumerate(self.weight, 1)]
        for name, ch in self.channels.items():
            turn = MODE[ch.mode].rotation
            what = f"{ch.mode} channel {name}"
            rows += [Parameter(f"{name}.S[{k}]", v, "m3/rad" if turn else "m", f"{what}: layer {k}'s shape factor")
                     for k, v in enumerate(ch.S, 1)]
            rows += [Parameter(f"{name}.c[{k}]", v, "1/rad" if turn else "1/m", f"{what}: layer {k}'s strain factor")
                     for k, v in enumerate(ch.c, 1)]
            rows.append(Parameter(f"{name}.compliance", ch.compliance, "rad/(N.m)" if turn else "m/N",
                                  f"{what}: the series bulk compliance C_b (0: none)"))
        return rows


def check_slices(slices) -> int:
    """``slices`` as a whole number 1 … :data:`MAX_SLICES`, or ValueError."""
    if isinstance(slices, bool) or not isinstance(slices, int) or not 1 <= slices <= MAX_SLICES:
        raise ValueError(f"slices: must be a whole number from 1 to {MAX_SLICES}, got {slices!r}")
    return slices


def refuse_effects(design: Design) -> None:
    """ValueError naming the first effect acting in ``design``'s mode that has no time-domain form."""
    for eid in design.effect_parameters:
        if eid in REFUSED_EFFECTS:
            raise ValueError(f"effects.{eid}: the time-domain element has no form for it ({design.mode} "
                             f"direction): {REFUSED_EFFECTS[eid]}")


def channel_coefficients(design: Design, slices: int = 1) -> ChannelCoefficients:
    """The layers of ``design`` in its own mode (see the module's docstring)."""
    refuse_effects(design)
    geo = design.geometry
    if slices > 1 and design.mode in THESIS_MODES and design.shape_kind == "long":
        nodes = slice_nodes(geo, design.mode, slices)  # p = 2c/S, q = 1/S per slice
        S = tuple(float(1.0 / q) for q in nodes.q)
        c = tuple(float(p / (2.0 * q)) for p, q in zip(nodes.p, nodes.q, strict=True))
        return ChannelCoefficients(design.mode, design.shape_kind, S, c, 0.0, True)
    series = bulk_series(design) if design.shape_kind != "long" else series_at(
        design, modulus_function(design), REFERENCE_FREQUENCY, design.drive(REFERENCE_STRAIN), "the time-domain element")
    if series is None:
        s, c, compliance = design.shape_factor, design.strain_factor, 0.0
    else:
        s, c, compliance = series.shape_factor, series.strain_factor, series.compliance
    return ChannelCoefficients(design.mode, design.shape_kind, (float(s),), (float(c),), float(compliance), False)


def coefficients(design: Design, slices: int = 1, band=DEFAULT_BAND) -> Coefficients:
    """The element's coefficients for ``design`` (docs/element.md).

    Parameters
    ----------
    design : Design
        The bushing, in any mode: each channel turns it to its own (:meth:`Design.in_mode`).
    slices : int, default 1
        Layers in series for the channels the core slices (axial ``dz`` and torsion ``rz`` with
        the long shape factors); 1 … :data:`MAX_SLICES`.
    band : (float, float), default (0.1, 2000)
        f₁ < f₂ in Hz where the fractional term's sum of exponentials holds.

    Returns
    -------
    Coefficients
        SI values; :meth:`Coefficients.as_dict` is JSON-able.

    Raises
    ------
    ValueError
        If ``slices`` or ``band`` is not allowed, a channel's design has an effect without a
        time-domain form.
    """
    slices = check_slices(slices)
    band = check_band(band)
    mat = design.material
    channels = {name: channel_coefficients(design.in_mode(mode), slices) for name, mode in CHANNEL_MODES.items()}
    effects = design.in_mode("axial").effect_parameters  # the rubber's effects act in every mode
    beta = effects.get("strain_stiffening", {}).get("stiffening", 0.0)
    viscosity = effects.get("viscous", {}).get("viscosity", 0.0)
    alpha = float(mat.fractional_order)
    if alpha == 1.0:
        rate, weight, mag, phase = (), (), 0.0, 0.0
        viscosity += mat.fractional_coefficient
    else:
        fit = fit_power(alpha, band)
        rate, weight = tuple(fit.rates.tolist()), tuple(fit.weights.tolist())
        mag, phase = fit.magnitude_error, fit.phase_error
    return Coefficients(
        mu=float(mat.shear_modulus), m=float(mat.fractional_coefficient), alpha=alpha,
        sigma_f_max=float(mat.friction_stress_max), eps_half=float(mat.friction_strain_half),
        beta=float(beta), viscosity=float(viscosity), rate=rate, weight=weight, channels=channels,
        band=band, magnitude_error=mag, phase_error=phase, slices=slices,
    )

