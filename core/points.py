"""The model at a fit's points for many parameter values at once (:class:`PointsModel`): what a
fit asks at every evaluation, its finite-difference Jacobian's columns, in one pass over arrays
of parameters, with the numbers :func:`core.bushing.stiffness_points` gives design by design.
"""

from __future__ import annotations

import dataclasses
import functools
from types import SimpleNamespace

import numpy as np

from . import material as mat
from .bushing import _check_series, bulk_correction, check_strain, equivalent_stiffness, factors
from .design import Design
from .effects import EFFECTS, extended_modulus, inertia_correction, wave_stiffness
from .parts import Material
from .registry import parameter


class PointsModel:
    """:func:`stiffness_points` of one design at fixed points (``frequency_hz``, ``amplitude``
    broadcast; Hz, m or rad) for many values of some of its parameters at once, ``names``
    (fitting names, :mod:`core.registry`: a material field, or ``effect_id.name`` of an effect
    the design carries). Called with ``values`` shaped (n, len(names)), each row one set of
    values within the parameters' fitting ranges (ValueError otherwise), it gives K shaped
    (n, *points): the same formulas over arrays of parameters, so the same numbers as design by
    design. The design and the points are checked once, here (as :func:`stiffness_points` checks
    them), not at every call: what a fit asks at every evaluation, its finite-difference
    Jacobian's columns (one parameter changed in each) at once.

    Only where the route is the single equivalent modulus (eqs 14–18, with the material-level
    effects, inertia and standing waves): :attr:`usable` is False for slices, the continuum of
    ``nonuniform_strain`` or an effect tied to another mode's rig (the caller then evaluates
    design by design)."""

    def __init__(self, design: Design, names: tuple[str, ...], frequency_hz, amplitude):
        self.design, self.names = design, tuple(names)
        self.effects = design.effect_parameters
        self.usable = "nonuniform_strain" not in self.effects and not any("@" in n for n in self.names)
        self.f, self.x = np.asarray(frequency_hz, float), np.asarray(amplitude, float)
        self.shape = np.broadcast_shapes(self.f.shape, self.x.shape)
        if self.usable:
            check_strain(design, self.x)
            _check_series(design, 1)
        self.low, self.high = (np.array(b, dtype=float) for b in zip(*(parameter(n).bounds for n in self.names)))
        self.factors = factors(design)
        self.strain = design.strain(self.x)
        self.terms = any(EFFECTS[e].term is not None for e in self.effects)
        column = {name: j for j, name in enumerate(self.names)}
        # where each material field and effect parameter comes from: a column, or the design
        self.material = [(name, column.get(name), getattr(design.material, name)) for name in _MATERIAL_FIELDS]
        self.params = [(eid, p, column.get(f"{eid}.{p}"), v) for eid, ps in self.effects.items() for p, v in ps.items()]

    def __call__(self, values: np.ndarray) -> np.ndarray:
        if not self.usable:
            raise ValueError("these points of this design are computed design by design (stiffness_points)")
        values = np.asarray(values, dtype=float)
        n = values.shape[0]
        inside = (values >= self.low) & (values <= self.high)
        if not inside.all():
            j = int(np.flatnonzero(~inside.all(axis=0))[0])
            raise ValueError(f"{self.names[j]}: the values must lie within its fitting range "
                             f"{self.low[j]:g} to {self.high[j]:g}")
        by_design = values.reshape((n, len(self.names), *(1,) * len(self.shape)))  # a column: (n, 1, …)
        material = SimpleNamespace(**{name: v if j is None else by_design[:, j] for name, j, v in self.material})
        params: dict = {eid: {} for eid in self.effects}
        for eid, p, j, v in self.params:
            params[eid][p] = v if j is None else by_design[:, j]
        if self.terms:
            modulus = functools.partial(extended_modulus, material, params)
        else:
            modulus = functools.partial(mat.equivalent_modulus, material)
        f, x = self.f, self.x
        if "wave_effects" in self.effects:
            geo = self.design.geometry
            k = wave_stiffness(self.design.mode, geo.inner_radius, geo.outer_radius, geo.length,
                               modulus(f, self.strain), f, params["wave_effects"]["density"])
        else:
            k = equivalent_stiffness(modulus, *self.factors, f, x, bulk_correction(self.design, material.bulk_modulus))
        if "inertia" in self.effects:
            k = inertia_correction(k, f, params["inertia"]["mass"])
        k = np.broadcast_to(k, (n, *self.shape))
        if not np.isfinite(k).all():
            raise ValueError("the stiffness is not finite at these points (check the design's effects)")
        return np.array(k)


_MATERIAL_FIELDS = tuple(f.name for f in dataclasses.fields(Material))
