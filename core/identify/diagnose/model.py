"""The models the diagnosis fits: a design with a subset of the thesis' branches, extended by
effects of the library."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from ...design import Design
from ...effects import EFFECTS, effect_of, split_id
from ...parameters import BRANCH_PARAMETERS, BY_NAME
from ...registry import with_values

BRANCHES = tuple(BRANCH_PARAMETERS)  # elastic, fractional, friction
# a branch switched off: its modulus (its parameter in Pa) 1e-30 Pa, thirty orders below any rubber's
OFF = {name: 1e-30 for names in BRANCH_PARAMETERS.values() for name in names
       if BY_NAME[name].unit.si.startswith("Pa")}


@dataclass(frozen=True)
class Model:
    """A design with a subset of the thesis' branches (the others held at :data:`OFF`)."""

    design: Design
    branches: tuple[str, ...] = BRANCHES

    @property
    def parts(self) -> tuple[str, ...]:
        """Branches and effects: what the model has."""
        return (*self.branches, *(eid for eid, _ in self.design.effects))

    @property
    def free(self) -> tuple[str, ...]:
        names = [p for b in self.branches for p in BRANCH_PARAMETERS[b]]
        names += [f"{eid}.{p}" for eid, params in self.design.effects for p, _ in params]
        return tuple(names)

    def add(self, effect_id: str, values: dict[str, float]) -> Model:
        """The model with ``effect_id`` (a branch, an effect, or a rig effect tied to a mode,
        ``inertia@torsion``) at ``values`` (by parameter name)."""
        if effect_of(effect_id).branch:
            branches = tuple(b for b in BRANCHES if b in self.branches or b == effect_id)
            return Model(with_values(self.design, values), branches)
        effects = {**self.design.every_effect, effect_id: values}
        return Model(self.design.replace(effects=effects), self.branches)

    def alone(self, mode: str) -> Model:
        """This model for data of ``mode`` only: the design in that mode, its free parameters
        those that act there (not other rigs' masses)."""
        return Model(self.design.in_mode(mode), self.branches)

    @property
    def acting(self) -> tuple[str, ...]:
        """The free parameters that act in the design's own mode."""
        return tuple(n for n in self.free if "@" not in n)


def fitting_names(effect_id: str) -> list[str]:
    """The fitting names of a candidate's parameters: a branch's are the material's, an
    effect's ``effect_id.name`` (``inertia@torsion.mass`` for a mode-tied rig effect)."""
    effect = effect_of(effect_id)
    return [p.name if effect.branch else f"{effect_id}.{p.name}" for p in effect.parameters]


def baseline_model(design: Design, branches: Iterable[str] = BRANCHES) -> Model:
    branches = tuple(branches)
    unknown = [b for b in branches if b not in BRANCHES]
    if unknown or not branches:
        raise ValueError(f"baseline: give one or more of {', '.join(BRANCHES)}, got {','.join(branches) or 'none'}")
    off = {p: OFF[p] for b in BRANCHES if b not in branches for p in BRANCH_PARAMETERS[b] if p in OFF}
    return Model(with_values(design, off), tuple(b for b in BRANCHES if b in branches))


def candidates(model: Model, modes: Iterable[str] = ()) -> list[str]:
    """The effects that can extend ``model``: not in it, whatever they act on present, nothing
    they exclude present. With data of several ``modes``, an effect of the test rig is a
    candidate on each mode's rig (``inertia`` on the design's own, ``inertia@torsion`` on
    another's)."""
    parts = set(model.parts)
    kinds = {split_id(p)[0] for p in parts}
    own = model.design.mode
    out = []
    for eid, effect in EFFECTS.items():
        if any(x in kinds for x in effect.excludes):
            continue
        if effect.requires and not any(r in kinds for r in effect.requires):
            continue
        tied = [eid if m == own else f"{eid}@{m}" for m in sorted(set(modes))] if effect.rig and modes else [eid]
        out += [t for t in tied if t not in parts]
    return out
