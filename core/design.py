"""Bushing designs: validated, immutable geometry, material and mode (the design file is
:mod:`core.io.design_file`).

The parameters' symbols, names and units are those of the one table, :mod:`core.parameters`
(docs/model.md, "Symbols and units"): geometry in m, moduli and stresses in Pa.

A value that breaks a rule is refused at the door with a :class:`DesignError` whose message
names the key (``geometry.outer_radius``) and the rule, and whose ``code`` says which rule
(:mod:`core.rules`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from .effects import EFFECTS, validate_effects
from .parameters import BY_NAME, DEFAULT_SHAPE, MODES, SHAPES, file_shape, no_long_form
from .parts import Geometry, Material, as_dict
from .rules import (
    BAD_CHOICE,
    BAD_TYPE,
    DUPLICATE_KEY,
    DesignError,
    excerpt,
)
from .shape import shape_factor, strain_factor


def _frozen_effects(effects: Mapping[str, Mapping[str, float]]) -> tuple:
    """Validated effects as a hashable, sorted tuple of (id, ((parameter, value), ...))."""
    if isinstance(effects, tuple):
        effects = {eid: dict(params) for eid, params in effects}
    if isinstance(effects, Mapping) and not effects:
        return ()
    checked = validate_effects(effects)
    return tuple(sorted((eid, tuple(sorted(p.items()))) for eid, p in checked.items()))


@dataclass(frozen=True)
class Design:
    """A bushing: mode, geometry and material, optionally named, with its model's effects.

    ``effects`` holds the model extensions of the discrepancy workflow (docs/model.md's table,
    :mod:`core.effects`); pass a mapping ``{effect_id: {parameter: value}}``: it is validated
    and frozen into a hashable tuple. An effect of the test rig (an apparent mass) acts in the
    design's mode only; one measured on another mode's rig is kept as ``id@mode`` and acts when
    the design is taken into that mode (:meth:`in_mode`).

    Attributes
    ----------
    mode : str
        The direction, one of :data:`core.parameters.MODES` (axial, torsion, radial, conical).
    geometry : Geometry
        The bonded radii and length, in m.
    material : Material
        The material model's five parameters, SI.
    name : str or None
        A name for the design, if any.
    effects : tuple
        ((id, ((parameter, value), …)), …), sorted; SI values (a mass in kg, a viscosity in Pa·s).
    shape : str or None
        ``long`` (the closed forms), ``finite`` (finite-length FE), None (:data:`DEFAULT_SHAPE`).
    shape_factor : float
        S with K = S·µ_eq (eqs 17, 18 if long), in m (translations) or m³/rad (rotations).
    strain_factor : float
        c with ε_eq = c·x̂ (eqs 14, 15 if long), in 1/m (translations) or 1/rad (rotations).
    shape_kind : str
        The shape factor used: ``shape``, or the mode's default.
    effect_parameters : dict of str to dict
        The effects acting in this mode, id → {parameter: value}, SI as ``effects`` (kg, …).
    portable_effects : dict of str to dict
        Every effect, this mode's rig effects as ``id@mode``, SI as ``effects`` (kg, …).
    every_effect : dict of str to dict
        Every effect, those tied to other modes' rigs too, SI as ``effects`` (kg, …).

    Raises
    ------
    DesignError
        If a field breaks its rule (an unknown mode or shape, a wrong type); it names the key.
    """

    mode: str
    geometry: Geometry
    material: Material
    name: str | None = None
    effects: tuple = field(default=())
    shape: str | None = None

    def __post_init__(self):
        if self.mode not in MODES:
            raise DesignError("mode", f"must be one of {', '.join(MODES)}, got {excerpt(repr(self.mode))}", BAD_CHOICE)
        if self.shape is not None and self.shape not in SHAPES:
            raise DesignError("shape", f"must be one of {', '.join(SHAPES)}, got {excerpt(repr(self.shape))}", BAD_CHOICE)
        if self.shape == "long" and no_long_form(self.mode):
            raise DesignError("shape", no_long_form(self.mode), BAD_CHOICE)
        if not isinstance(self.geometry, Geometry):
            raise DesignError("geometry", "must be a Geometry", BAD_TYPE)
        if not isinstance(self.material, Material):
            raise DesignError("material", "must be a Material", BAD_TYPE)
        if self.name is not None and not isinstance(self.name, str):
            raise DesignError("name", f"must be a string, got {excerpt(repr(self.name))}", BAD_TYPE)
        effects = _frozen_effects(self.effects)
        own = f"@{self.mode}"
        if any(eid.endswith(own) for eid, _ in effects):  # tied to this design's own mode: plain
            ids = [eid.removesuffix(own) for eid, _ in effects]
            twice = sorted({i for i in ids if ids.count(i) > 1})
            if twice:
                raise DesignError(f"effects.{twice[0]}{own}", f"{twice[0]} is given for the {self.mode} "
                                                             f"mode twice (with and without {own})", DUPLICATE_KEY)
            effects = tuple(sorted((eid.removesuffix(own), p) for eid, p in effects))
        object.__setattr__(self, "effects", effects)

    def in_mode(self, mode: str) -> Design:
        """This bushing and material in another direction, with the same ``shape`` if it can.

        Conical has no long form: its default then. Effects of the rubber go with it; an effect
        of this mode's test rig stays with this mode (as ``id@mode``); one tied to ``mode`` acts.

        Parameters
        ----------
        mode : str
            The new direction, one of :data:`core.parameters.MODES`.

        Returns
        -------
        Design
            The design in ``mode`` (this one if nothing changes).

        Raises
        ------
        DesignError
            If ``mode`` is unknown.
        """
        shape = None if (self.shape == "long" and no_long_form(mode)) else self.shape
        if (mode, shape) == (self.mode, self.shape):
            return self
        return self.replace(mode=mode, shape=shape, effects=self.portable_effects)

    @property
    def shape_factor(self) -> float:
        """S with K = S·µ_eq (eqs 17, 18 for long bushings; m or m³/rad)."""
        return shape_factor(self.geometry, self.mode, self.shape)

    @property
    def strain_factor(self) -> float:
        """c with ε_eq = c·x̂ (eqs 14, 15 for long bushings; 1/m or 1/rad)."""
        return strain_factor(self.geometry, self.mode, self.shape)

    def value(self, name: str) -> float:
        """The geometric or material parameter called ``name``, in SI units.

        Parameters
        ----------
        name : str
            A name of :data:`core.parameters.NAMES` (``outer_radius``, ``shear_modulus``…).

        Returns
        -------
        float or None
            Its value: m for the geometry, Pa or Pa·s^α for the moduli, dimensionless for α and ε½;
            None for an optional parameter left out (the bulk modulus).
        """
        value = getattr(getattr(self, BY_NAME[name].group), name)
        return None if value is None else float(value)

    def strain(self, amplitude):
        """The equivalent strain amplitude ε_eq = c·x̂ of a drive amplitude (eqs 14, 15).

        Parameters
        ----------
        amplitude : float or array_like
            The drive amplitude x̂: in m (translations) or rad (rotations).

        Returns
        -------
        float or numpy.ndarray
            ε_eq, dimensionless, shaped as ``amplitude``.
        """
        return self.strain_factor * amplitude

    def drive(self, strain):
        """The drive amplitude x̂ = ε_eq / c of an equivalent strain: :meth:`strain` inverted.

        Parameters
        ----------
        strain : float or array_like
            The equivalent strain amplitude ε_eq, dimensionless.

        Returns
        -------
        float or numpy.ndarray
            x̂, shaped as ``strain``: in m (translations) or rad (rotations).
        """
        return strain / self.strain_factor

    @property
    def shape_kind(self) -> str:
        """The shape factor used: ``shape``, or the mode's default."""
        return self.shape or DEFAULT_SHAPE[self.mode]

    @property
    def effect_parameters(self) -> dict[str, dict[str, float]]:
        """The effects acting in this design's mode, by id."""
        return {eid: dict(params) for eid, params in self.effects if "@" not in eid}

    @property
    def portable_effects(self) -> dict[str, dict[str, float]]:
        """Every effect, this mode's rig effects tied to it (``id@mode``): what a design of any
        mode built from them carries (the tie to its own mode falls away)."""
        return {(f"{eid}@{self.mode}" if "@" not in eid and EFFECTS[eid].rig else eid): dict(p)
                for eid, p in self.effects}

    @property
    def every_effect(self) -> dict[str, dict[str, float]]:
        """Every effect the design carries, those tied to other modes' rigs (``id@mode``) too."""
        return {eid: dict(params) for eid, params in self.effects}

    def replace(self, **changes) -> Design:
        """A copy with top-level fields, or geometry/material fields by their own names, changed.

        Parameters
        ----------
        **changes : object
            New values by field name: the design's, or a geometry field's (in m) or a material
            field's (in Pa, Pa·s^α or dimensionless) by its own name.

        Returns
        -------
        Design
            The changed copy, validated anew.

        Raises
        ------
        DesignError
            If a changed value breaks its rule (TypeError: a name that is no field).
        """
        if changes and all(k in _MATERIAL_KEYS or k == "effects" for k in changes):
            fast = self._values_replaced(changes)
            if fast is not None:
                return fast
        geo = {k: changes.pop(k) for k in list(changes) if k in _GEOMETRY_KEYS}
        mat = {k: changes.pop(k) for k in list(changes) if k in _MATERIAL_KEYS}
        current = {f.name: getattr(self, f.name) for f in fields(self)}
        current.update(changes)
        if geo:
            current["geometry"] = Geometry(**{**as_dict(self.geometry), **geo})
        if mat:
            current["material"] = Material(**{**as_dict(self.material), **mat})
        return Design(**current)

    def _values_replaced(self, changes: dict) -> Design | None:
        """:meth:`replace` of material values and effect values only, the set of effects the
        same: the new material and effects validated, the rest (mode, shape, geometry, name,
        which have not changed) not checked again. What a fit asks at every evaluation. None
        where the effects' ids change (the full :meth:`replace` then checks their ties)."""
        effects = self.effects
        if "effects" in changes:
            effects = _frozen_effects(changes["effects"])
            if [eid for eid, _ in effects] != [eid for eid, _ in self.effects]:
                return None
        mat = {k: v for k, v in changes.items() if k != "effects"}
        material = Material(**{**as_dict(self.material), **mat}) if mat else self.material
        new = object.__new__(Design)
        new.__dict__.update(self.__dict__)
        object.__setattr__(new, "material", material)
        object.__setattr__(new, "effects", effects)
        return new

    def to_dict(self) -> dict:
        """The design-file object of docs/files.md.

        Returns
        -------
        dict
            ``name``, ``mode``, ``shape``, ``geometry`` (in m), ``material`` (in Pa, Pa·s^α and
            dimensionless) and ``effects`` (SI); those unset left out.
        """
        out: dict[str, Any] = {}
        if self.name is not None:
            out["name"] = self.name
        out["mode"] = self.mode
        if self.shape is not None:
            out["shape"] = file_shape(self.mode, self.shape)
        out["geometry"] = as_dict(self.geometry)
        out["material"] = as_dict(self.material)
        if self.effects:
            out["effects"] = self.every_effect
        return out


_GEOMETRY_KEYS = tuple(f.name for f in fields(Geometry))
_MATERIAL_KEYS = tuple(f.name for f in fields(Material))


# Reference designs of the thesis (docs/model.md, "Reference data").
PAPER_B = Design(
    name="VP 40/70120 (Paper B)",
    mode="axial",
    geometry=Geometry(inner_radius=0.020, outer_radius=0.035, length=0.090),
    material=Material(
        shear_modulus=2.42e6,
        fractional_coefficient=6.0e5,
        fractional_order=0.20,
        friction_stress_max=1.92e4,
        friction_strain_half=4.0e-3,
    ),
)

TABLE_1 = Design(
    name="Table 1 torsion example (Paper A)",
    mode="torsion",
    geometry=Geometry(inner_radius=0.005, outer_radius=0.011, length=0.022),
    material=Material(
        shear_modulus=2.0e6,
        fractional_coefficient=2.0e5,
        fractional_order=0.40,
        friction_stress_max=4.0e3,
        friction_strain_half=1.0e-3,
    ),
)
