"""The bushing's parts as values: its geometry (the bonded radii and the length) and its
compound (the five parameters of the material model, and optionally its bulk modulus), validated
and immutable, in SI units.

:class:`core.design.Design` puts them together with a mode; :mod:`core.material` computes with a
:class:`Material`. A value that breaks a rule is refused with a :class:`core.rules.DesignError`
naming the key (``geometry.outer_radius``) and the rule's code.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from .numbers import format_number
from .parameters import BY_NAME
from .rules import (
    ORDER_RANGE,
    OUT_OF_RANGE,
    OUTER_NOT_LARGER,
    DesignError,
    number,
    positive,
    within,
)

SIZE_RANGE = (1e-6, 1e3)  # m: radii and lengths from a micrometre to a kilometre, no further
MAX_MODULUS = 1e12  # Pa: µ, m and σ_fmax at most 1 TPa (diamond's shear modulus is about half that)
STRAIN_HALF_RANGE = BY_NAME["friction_strain_half"].fit_range  # ε½: the range the fit searches
# K/µ: from Poisson's ratio 0.49 (50) to 0.4999995 (10⁶); filled rubber's lies at about 700–4000
BULK_RATIO_RANGE = (50.0, 1e6)


@dataclass(frozen=True)
class Geometry:
    """Bonded radii and length of a cylindrical bushing, in metres.

    Attributes
    ----------
    inner_radius : float
        a, the inner (bonded) radius, in m.
    outer_radius : float
        b, the outer (bonded) radius, in m; b > a.
    length : float
        L, the bushing's length, in m.

    Raises
    ------
    DesignError
        If a value is no finite number in :data:`SIZE_RANGE` (m) or b ≤ a; it names the key.
    """

    inner_radius: float
    outer_radius: float
    length: float

    def __post_init__(self):
        for f in fields(self):
            key = f"geometry.{f.name}"
            object.__setattr__(self, f.name, within(key, getattr(self, f.name), *SIZE_RANGE, "m"))
        if self.outer_radius <= self.inner_radius:
            raise DesignError(
                "geometry.outer_radius",
                f"must be larger than geometry.inner_radius (b > a), got b = {self.outer_radius!r}"
                f" and a = {self.inner_radius!r}",
                OUTER_NOT_LARGER,
            )


@dataclass(frozen=True)
class Material:
    """The five parameters of the elastic + fractional + friction model (eqs 1–7), SI units.

    Attributes
    ----------
    shear_modulus : float
        µ, the elastic branch's shear modulus (eq 1), in Pa.
    fractional_coefficient : float
        m, the fractional-derivative coefficient (eq 3), in Pa·s^α.
    fractional_order : float
        α, the fractional order, 0 < α ≤ 1, dimensionless.
    friction_stress_max : float
        σ_fmax, the largest friction stress (eq 6), in Pa.
    friction_strain_half : float
        ε½, the strain at which half of σ_fmax is built (eq 6), dimensionless.
    bulk_modulus : float or None, default None
        K, the rubber's bulk modulus, in Pa; elastic (the rubber's volume responds without loss).
        None: nearly incompressible, K = 5000 µ, the finite-length shape factors' own
        (:data:`core.shape.BULK_RATIO`), the incompressible closed forms for ``shape="long"``.

    Raises
    ------
    DesignError
        If a value is no finite number, a modulus is not in (0, :data:`MAX_MODULUS`] (Pa), α is
        not in (0, 1] or ε½ not in :data:`STRAIN_HALF_RANGE`; it names the key (K/µ is an input
        rule, :func:`check_bulk_ratio`).
    """

    shear_modulus: float
    fractional_coefficient: float
    fractional_order: float
    friction_stress_max: float
    friction_strain_half: float
    bulk_modulus: float | None = None

    def __post_init__(self):
        for f in fields(self):
            key = f"material.{f.name}"
            value = getattr(self, f.name)
            if f.name == "bulk_modulus" and value is None:
                continue
            if f.name == "fractional_order":
                value = number(key, value)
                if not 0.0 < value <= 1.0:
                    raise DesignError(key, f"must lie in (0, 1], got {value!r}", ORDER_RANGE)
            elif f.name == "friction_strain_half":
                value = within(key, value, *STRAIN_HALF_RANGE)
            else:
                value = positive(key, value)
                if value > MAX_MODULUS:
                    raise DesignError(key, f"must be at most {MAX_MODULUS:g} Pa, got {value!r}", OUT_OF_RANGE)
            object.__setattr__(self, f.name, value)


def check_bulk_ratio(material: Material) -> None:
    """The input rule of the bulk modulus against the shear modulus: K/µ within
    :data:`BULK_RATIO_RANGE` (a design file, the explorer's fields, a link). A fit may wander past
    it while it searches (the model stays finite there); what people give may not. DesignError
    naming ``material.bulk_modulus`` otherwise."""
    if material.bulk_modulus is None:
        return
    low, high = BULK_RATIO_RANGE
    ratio = material.bulk_modulus / material.shear_modulus
    if not low <= ratio <= high:
        k, mu = BY_NAME["bulk_modulus"].unit, BY_NAME["shear_modulus"].unit
        raise DesignError(
            "material.bulk_modulus",
            f"must lie between {low:g} and {format_number(high)} times the shear modulus (Poisson's ratio 0.49 to "
            f"0.4999995; filled rubber has about 2 GPa): with µ = {mu.shown(material.shear_modulus)}, "
            f"{k.shown(low * material.shear_modulus)} to {k.shown(high * material.shear_modulus)}; got "
            f"{k.shown(material.bulk_modulus)} (K/µ = {format_number(ratio, 3)})", OUT_OF_RANGE)


def as_dict(value) -> dict[str, float]:
    """A Geometry's or a Material's fields by name (SI); an optional field left unset (None) is
    not among them."""
    return {f.name: getattr(value, f.name) for f in fields(value) if getattr(value, f.name) is not None}
