"""The explorer's design fields, made from the one table (:mod:`core.parameters`).

One number per design parameter, in its display unit (``shear_modulus_mpa``: µ in MPa), labelled
and documented as the table says; a design shown in them; and the design they give, or what is
wrong with each field in the words of the input panel. No Panel import.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import param

from core import PAPER_B, Design, DesignError, Geometry, Material
from core.bushing import factors
from core.numbers import format_number, range_problem, rounded
from core.parameters import (
    BY_NAME,
    DEFAULT_SHAPE,
    GEOMETRY,
    MATERIAL,
    OPTIONAL,
    PARAMETERS,
    DesignParameter,
)
from core.parts import MAX_MODULUS, SIZE_RANGE, STRAIN_HALF_RANGE, as_dict, check_bulk_ratio
from core.rules import NOT_POSITIVE, ORDER_RANGE, OUT_OF_RANGE, OUTER_NOT_LARGER
from core.shape import OutsideTable, table

# field name → its design parameter, in the table's order (geometry, then material)
DESIGN_FIELDS: dict[str, DesignParameter] = {p.field: p for p in PARAMETERS}
GEOMETRY_FIELDS = tuple(BY_NAME[n].field for n in GEOMETRY)
MATERIAL_FIELDS = tuple(BY_NAME[n].field for n in MATERIAL)
OPTIONAL_FIELDS = tuple(BY_NAME[n].field for n in OPTIONAL)  # may be left empty (None)
# design-error key → the field to show the message beside
ERROR_FIELD = {f"{p.group}.{p.name}": p.field for p in PARAMETERS}
# the fields named by the rule b > a, and by a geometry outside the finite-length table
_INNER, _OUTER, _LENGTH = BY_NAME["inner_radius"].field, BY_NAME["outer_radius"].field, BY_NAME["length"].field


def display_values(design: Design) -> dict[str, float]:
    """The fields' values for ``design`` (display units, to 12 digits: no 19.200000000000003; the
    fields show them to their quantity's digits, a link writes :data:`core.numbers.LINK_DIGITS`)."""
    values = {name: design.value(p.name) for name, p in DESIGN_FIELDS.items()}
    return {name: None if v is None else rounded(DESIGN_FIELDS[name].unit.to_display(v), 12) for name, v in values.items()}


def _field(p: DesignParameter, default: float) -> param.Number:
    return param.Number(default, allow_None=True, label=p.display_label, doc=p.doc)


_FIRST = display_values(PAPER_B)  # the fields show the Paper B bushing at first
DesignFields = type("DesignFields", (param.Parameterized,), {
    "__doc__": "The design's fields (display units), one param.Number per parameter of core.parameters.",
    **{name: _field(p, _FIRST[name]) for name, p in DESIGN_FIELDS.items()},
})


def design_from_fields(fields: Mapping, shown: Design, mode: str, shape: str | None,
                       effects, edited: Iterable[str] = ()) -> tuple[Design | None, dict[str, str]]:
    """The design that ``fields`` (field name → value in display units) give in ``mode`` with
    ``shape`` and ``effects``, and ``{}``; or None and, field by field, what is wrong. The core's
    rules judge: a field alone against the values of ``shown`` (the design shown last), b > a
    whatever else is wrong, then the whole design (its shape factor must exist: a geometry
    outside the finite-length table is said beside the geometry field just ``edited``, else
    beside the fields whose ratio is outside, by :func:`outside_table`)."""
    errors: dict[str, str] = {}
    values: dict[str, float] = {}
    for name, p in DESIGN_FIELDS.items():
        v = fields[name]
        if v is None and p.optional:  # left empty: the rubber's default (the bulk modulus: 5000 µ)
            continue
        if v is None or not isinstance(v, (int, float)) or not math.isfinite(v):
            errors[name] = "Enter a number."
            continue
        values[p.name] = float(p.unit.to_si(v))
        try:  # the core's own rule for this field alone (cross-field rules below)
            if p.group == "material":
                check_bulk_ratio(Material(**{**as_dict(shown.material), p.name: values[p.name]}))
            elif not SIZE_RANGE[0] <= values[p.name] <= SIZE_RANGE[1]:  # this field alone
                Geometry(**{**as_dict(shown.geometry), p.name: values[p.name]})
        except DesignError as exc:
            errors[name] = _plain(exc, v)
    if _INNER not in errors and _OUTER not in errors:
        try:  # b > a, whatever else is wrong
            Geometry(values["inner_radius"], values["outer_radius"], shown.geometry.length)
        except DesignError as exc:
            errors[_OUTER] = _plain(exc)
    if errors:
        return None, errors
    try:
        geometry = Geometry(**{n: values[n] for n in GEOMETRY})
        material = Material(**{n: values[n] for n in MATERIAL + OPTIONAL if n in values})
        check_bulk_ratio(material)
        design = Design(mode, geometry, material, effects=effects, shape=shape)
        factors(design)  # the shape factor exists for this geometry (the FE table's range)
    except DesignError as exc:
        return None, {ERROR_FIELD.get(exc.key, "mode"): _plain(exc)}
    except OutsideTable:  # a geometry to change
        message, involved = outside_table(geometry, mode)
        edited_geometry = [n for n in GEOMETRY_FIELDS if n in edited]
        return None, dict.fromkeys(edited_geometry or involved, message)
    return design, {}


def outside_table(geometry: Geometry, mode: str) -> tuple[str, tuple[str, ...]]:
    """Why ``geometry`` has no finite-length shape factor, in the panel's words and display
    units: the table's limits, this bushing's ratios, the range each field may take with the
    others as they are, and (where ``mode`` has one) the long-bushing formula as the other way
    out; and the fields whose ratio is outside the table."""
    t = table()
    (lo_r, hi_r), (lo_l, hi_l) = t.radius_ratio[[0, -1]], t.length_ratio[[0, -1]]
    a, b, L = geometry.inner_radius, geometry.outer_radius, geometry.length
    mm = {n: BY_NAME[n].unit for n in GEOMETRY}

    def span(name: str, low: float, high: float) -> str:
        unit = mm[name]
        return f"{format_number(unit.to_display(low), 3)}–{format_number(unit.to_display(high), 3)} {unit.display}"

    def value(name: str, v: float) -> str:
        return f"{BY_NAME[name].symbol} = {mm[name].shown(v)}"

    parts, involved = [], []
    if not lo_r <= b / a <= hi_r:
        parts.append(f"b/a is {format_number(b / a, 3)}, the table covers {lo_r:g}–{hi_r:g}: with {value('inner_radius', a)}, "
                     f"b may be {span('outer_radius', lo_r * a, hi_r * a)}")
        involved += [_INNER, _OUTER]
    if not lo_l <= L / (b - a) <= hi_l:
        parts.append(f"L/(b − a) is {format_number(L / (b - a), 3)}, the table covers {lo_l:g}–{hi_l:g}: with b − a = "
                     f"{format_number(mm['length'].to_display(b - a), 3)} {mm['length'].display}, L may be "
                     f"{span('length', lo_l * (b - a), hi_l * (b - a))}")
        involved += [_INNER, _OUTER, _LENGTH]
    way_out = (" Or switch off the finite-length shape factor (the long-bushing formula)."
               if DEFAULT_SHAPE[mode] != "finite" else "")
    message = "Outside the finite-length table: " + "; ".join(parts) + "." + way_out
    return message, tuple(dict.fromkeys(involved)) or (_LENGTH,)


# what the input panel says for a rule, by the rule's code (core.rules): the panel's own words
PANEL_WORDS = {
    OUTER_NOT_LARGER: "Must be larger than the inner radius a.",
    NOT_POSITIVE: "Must be positive.",
    ORDER_RANGE: "Must lie in (0, 1].",
}


# the range (SI) of a parameter the core holds it in (core.parts), by parameter name
SI_RANGES = {**{n: SIZE_RANGE for n in GEOMETRY}, BY_NAME["friction_strain_half"].name: STRAIN_HALF_RANGE,
             **{p.name: (0.0, MAX_MODULUS) for p in PARAMETERS if p.unit.si.startswith("Pa")}}


def _plain(exc: DesignError, typed: float | None = None) -> str:
    """A design error in the words of the input panel: by its rule code where the panel has its
    own words; a value out of its range with the range in the field's display unit
    (:func:`core.numbers.range_problem`); else the core's rule with the file's keys
    (``material.shear_modulus``) replaced by the panel's names."""
    if exc.code in PANEL_WORDS:
        return PANEL_WORDS[exc.code]
    p = BY_NAME.get(exc.key.partition(".")[2])
    if exc.code == OUT_OF_RANGE and typed is not None and p is not None and p.name in SI_RANGES:
        low, high = (float(p.unit.to_display(b)) for b in SI_RANGES[p.name])
        wrong = range_problem(typed, low, high, p.unit.display, "parameter", low_open=low == 0.0)
        if wrong:
            return wrong[0].upper() + wrong[1:] + "."
    rule = exc.rule
    for name, key in ((p.field, p.name) for p in PARAMETERS):
        rule = rule.replace(f"geometry.{key}", name).replace(f"material.{key}", name)
    rule = rule.replace(BY_NAME["outer_radius"].field, "b").replace(BY_NAME["inner_radius"].field, "a")
    return rule[0].upper() + rule[1:]
