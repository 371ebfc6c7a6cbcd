"""Every parameter of a model by its fitting name: what fits, diagnoses and what-ifs vary.

A fitting name is a material parameter's own name (``shear_modulus``, :data:`core.parameters.MATERIAL`)
or ``effect_id.name`` for a parameter of an effect a design carries (``inertia.mass``, or
``inertia@torsion.mass`` for the apparent mass of another mode's rig, :func:`core.effects.split_id`).
Each has its :class:`core.parameters.Parameter`: unit, meaning, the range a fit searches and
whether it is fitted as its logarithm.
"""

from __future__ import annotations

from .design import Design
from .effects import EFFECTS, split_id
from .parameters import BY_NAME, MATERIAL, OPTIONAL, Parameter
from .parts import as_dict


def parameter(name: str) -> Parameter:
    """The fitting range and scale of a parameter: a material name, or ``effect_id.name``."""
    eid, _, pname = name.rpartition(".")
    if not eid and (pname in MATERIAL or pname in OPTIONAL):
        return BY_NAME[pname].fitting
    base = split_id(eid)[0]
    for p in EFFECTS[base].parameters if eid and base in EFFECTS else ():
        if p.name == pname:
            return p
    raise ValueError(f"unknown parameter {name!r}")


def parameter_unit(name: str, mode: str) -> str:
    """The unit of a parameter (its fitting name) in a design of ``mode``: a rig effect tied to
    another mode (``inertia@torsion.mass``) is in that mode's unit."""
    tied = split_id(name.rpartition(".")[0])[1]
    return parameter(name).unit_in(tied or mode)


def parameter_values(design: Design) -> dict[str, float]:
    """Every parameter of a design by its fitting name: the material's, then ``effect.name``."""
    values = as_dict(design.material)
    for eid, params in design.effects:
        values.update({f"{eid}.{p}": v for p, v in params})
    return values


def with_values(design: Design, values: dict[str, float]) -> Design:
    """``design`` with parameters (fitting names, as :func:`parameter_values`) replaced. The
    effects are rebuilt (and validated) only when an effect parameter is among them: this runs
    at every residual evaluation of a fit."""
    changes: dict = {k: v for k, v in values.items() if "." not in k}
    if len(changes) < len(values):
        effects = design.every_effect
        for k, v in values.items():
            if "." in k:
                eid, _, p = k.rpartition(".")
                effects.setdefault(eid, {})[p] = v
        changes["effects"] = effects
    return design.replace(**changes)
