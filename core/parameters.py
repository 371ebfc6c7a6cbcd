"""The one table of the design's parameters, the modes and their units.

Every other list of parameters or modes (the design file's keys, the fit's names and ranges, the
sensitivities, the tolerances, the explorer's fields and link, the exports' units, the words of
the diagnosis) is made from these two tables; none is typed out elsewhere.

Design parameters: docs/model.md's "Symbols and units" shows them (symbol, name, SI unit, the
unit people read, meaning), and tests/test_parameters.py checks that page against
:data:`PARAMETERS`. A display value × factor is the SI value. The material's parameters belong
to the branches of the thesis' model (:data:`BRANCH_PARAMETERS`) and carry the range a fit
searches (:attr:`DesignParameter.fitting`, a :class:`Parameter` as an effect's parameters are).

Modes: axial and radial are translations (m, N/m, shown in mm and kN/mm), torsion and conical
rotations (rad, N·m/rad); axial and torsion act along or about the bushing's axis, radial and
conical across it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .numbers import format_number


@dataclass(frozen=True)
class Unit:
    """A quantity's SI unit and the unit people read: display value × ``factor`` = SI value."""

    si: str
    display: str
    factor: float = 1.0

    def to_si(self, value):
        """``value`` in display units, in SI (arrays too)."""
        return np.asarray(value, dtype=float) * self.factor

    def to_display(self, value):
        """``value`` in SI, in display units (arrays too; complex kept)."""
        return np.asarray(value) / self.factor

    def shown(self, value: float, digits: int = 3) -> str:
        """``value`` (SI) as people read it: in the display unit, to ``digits`` significant
        digits (:func:`core.numbers.format_number`): ``3.55 MPa``; a pure number alone."""
        text = format_number(float(self.to_display(value)), digits)
        return text if self.display == "–" else f"{text} {self.display}"


@dataclass(frozen=True)
class Parameter:
    """What a fit needs of one parameter (the material's or an effect's): its name, SI unit, a
    few words of meaning, the range searched (SI) and whether it is fitted as its logarithm (a
    scale) or as itself. A parameter whose unit is its mode's (an apparent mass: kg, kg·m² in
    the rotations) names the :class:`Mode` field that gives it, ``mode_unit``; its ``unit`` is
    then the translations'."""

    name: str
    unit: str
    meaning: str
    bounds: tuple[float, float] = (0.0, math.inf)
    log: bool = True
    mode_unit: str | None = None  # "mass": its unit is the Mode.mass of the mode at hand

    def unit_in(self, mode: str) -> str:
        """The parameter's one unit in ``mode`` (a mode's name)."""
        return getattr(MODE[mode], self.mode_unit) if self.mode_unit else self.unit


@dataclass(frozen=True)
class DesignParameter:
    """One parameter of a design: its key in files and code, where it lives (``geometry`` or
    ``material``), its symbol, units, its key in a link's tolerances (``tol=mu:10``), the label
    and one-line doc of its field, the range a fit searches (SI; None: not fitted) and, for the
    material, the branch of the thesis' model it belongs to (elastic, fractional, friction)."""

    name: str
    group: str
    symbol: str
    unit: Unit
    tolerance_key: str
    label: str
    doc: str
    meaning: str  # a few words for sentences: "shear modulus µ"
    fit_range: tuple[float, float] | None = None
    log: bool = True  # fitted as its logarithm (a scale) or as itself
    branch: str | None = None  # the material's: the branch of the model (eqs 1, 2, 6) it sizes or shapes
    step: float = 0.5  # the explorer's step for its field, in the display unit
    optional: bool = False  # may be left out of a design (None): the bulk modulus

    @property
    def field(self) -> str:
        """The explorer's field name (display units in the name: ``shear_modulus_mpa``)."""
        unit = self.unit.display
        return self.name if unit == "–" else f"{self.name}_{unit.split('·')[0].lower()}"

    @property
    def url_key(self) -> str:
        """The key of the field in a link (``mu_MPa``; plain numbers by their symbol's name)."""
        unit = self.unit.display
        return self.tolerance_key if unit == "–" else f"{self.tolerance_key}_{unit.split('·')[0]}"

    @property
    def display_label(self) -> str:
        """The field's label with its display unit: ``Shear modulus µ (MPa)``."""
        return f"{self.label} ({self.unit.display})"

    @property
    def fitting(self) -> Parameter:
        """The parameter as a fit sees it (SI unit, meaning, range, scale); ValueError for one no
        fit varies (the geometry)."""
        if self.fit_range is None:
            raise ValueError(f"{self.name} is not fitted")
        return Parameter(self.name, self.unit.si, self.meaning, self.fit_range, self.log)


PARAMETERS: tuple[DesignParameter, ...] = (
    DesignParameter("inner_radius", "geometry", "a", Unit("m", "mm", 1e-3), "a", "Inner radius a",
                    "Radius of the inner (bonded) sleeve.", "inner radius a"),
    DesignParameter("outer_radius", "geometry", "b", Unit("m", "mm", 1e-3), "b", "Outer radius b",
                    "Radius of the outer (bonded) sleeve; larger than a.", "outer radius b"),
    DesignParameter("length", "geometry", "L", Unit("m", "mm", 1e-3), "L", "Length L",
                    "Axial length of the rubber.", "length L"),
    # µ's fitting range is far wider than any rubber's: it keeps the search finite
    DesignParameter("shear_modulus", "material", "µ", Unit("Pa", "MPa", 1e6), "mu", "Shear modulus µ",
                    "Elastic shear modulus µ: the stiffness that stays at any rate and amplitude.",
                    "shear modulus µ", (1e2, 1e11), branch="elastic"),
    DesignParameter("fractional_coefficient", "material", "m", Unit("Pa·s^α", "MPa·s^α", 1e6), "m",
                    "Fractional coefficient m", "Fractional coefficient m: size of the frequency dependence.",
                    "fractional coefficient m", (1e-2, 1e11), branch="fractional"),
    DesignParameter("fractional_order", "material", "α", Unit("–", "–"), "alpha", "Fractional order α",
                    "Fractional order α in (0, 1]: how fast stiffness rises with frequency.",
                    "fractional order α in (0, 1]", (1e-3, 1.0), log=False, branch="fractional", step=0.05),
    DesignParameter("friction_stress_max", "material", "σ_fmax", Unit("Pa", "kPa", 1e3), "sigma",
                    "Friction stress σ_fmax", "Largest friction stress σ_fmax: size of the amplitude dependence.",
                    "largest friction stress σ_fmax", (1e-3, 1e9), branch="friction"),
    DesignParameter("friction_strain_half", "material", "ε½", Unit("–", "–"), "eps_half", "Friction strain ε½",
                    "Strain ε½ at which half of σ_fmax is built: where the softening happens.",
                    "strain ε½ to build half of σ_fmax", (1e-9, 10.0), branch="friction", step=5e-4),
    # optional: without it the rubber is nearly incompressible (K = 5000 µ, core.shape.BULK_RATIO);
    # known by default in fits, identified only when a fit frees it (radial data are sensitive)
    DesignParameter("bulk_modulus", "material", "K", Unit("Pa", "GPa", 1e9), "K", "Bulk modulus K",
                    "Bulk modulus K of the rubber (filled rubber about 2 GPa); empty: nearly incompressible, "
                    "K = 5000 µ.", "bulk modulus K", (1e7, 1e12), step=0.1, optional=True),
)
BY_NAME = {p.name: p for p in PARAMETERS}
GEOMETRY = tuple(p.name for p in PARAMETERS if p.group == "geometry")
# the thesis model's five, which every design has; OPTIONAL: what a design may leave out
MATERIAL = tuple(p.name for p in PARAMETERS if p.group == "material" and not p.optional)
OPTIONAL = tuple(p.name for p in PARAMETERS if p.optional)
NAMES = GEOMETRY + MATERIAL
# the material's parameters by branch of the model, in the table's order: elastic (µ),
# fractional (m, α), friction (σ_fmax, ε½)
BRANCH_PARAMETERS = {b: tuple(p.name for p in PARAMETERS if p.branch == b)
                     for b in dict.fromkeys(p.branch for p in PARAMETERS if p.branch)}


@dataclass(frozen=True)
class Mode:
    """One direction of the bushing: how its sleeves move (along or about the axis, or across
    it), and the units of its drive, load, stiffness and apparent mass."""

    name: str
    motion: str  # "translation" or "rotation"
    description: str
    drive: str  # what the drive is called: Displacement, Angle, Tilt angle
    drive_kind: str  # the drive's quantity in results' units: displacement or angle
    load: str  # Force or Moment
    amplitude: Unit
    stiffness: Unit
    force: Unit
    mass: str  # the unit of an apparent mass in this mode: kg or kg·m²
    default_shape: str  # the shape factor used unless a design names one (SHAPES)
    on_axis: bool  # along or about the bushing's axis (one direction); else across it (two alike)
    long_form: bool = True  # a closed form of a long bushing exists (the shape "long" is allowed)
    long_equation: int | None = None  # the thesis' equation of its long-bushing shape factor, if it has one

    @property
    def rotation(self) -> bool:
        return self.motion == "rotation"

    @property
    def units(self) -> dict[str, str]:
        """The SI units of a result in this mode: amplitude, stiffness, force (or moment) and
        what the drive is (``displacement`` or ``angle``)."""
        return {"amplitude": self.amplitude.si, "stiffness": self.stiffness.si, "force": self.force.si,
                "drive": self.drive_kind}


_TRANSLATION = {"amplitude": Unit("m", "mm", 1e-3), "stiffness": Unit("N/m", "kN/mm", 1e6),
                "force": Unit("N", "N"), "mass": "kg", "load": "Force",
                "drive_kind": "displacement"}
_ROTATION = {"amplitude": Unit("rad", "rad"), "stiffness": Unit("N·m/rad", "N·m/rad"),
             "force": Unit("N·m", "N·m"), "mass": "kg·m²", "load": "Moment",
             "drive_kind": "angle"}

MODE_TABLE: tuple[Mode, ...] = (
    # axial and torsion: the thesis' closed forms (eqs 17, 18); radial and conical have none that
    # holds at real lengths, so the finite-length table (core.shape)
    Mode("axial", "translation", "the sleeves moved apart along the axis", "Displacement",
         default_shape="long", on_axis=True, long_equation=18, **_TRANSLATION),
    Mode("torsion", "rotation", "the sleeves turned about the axis", "Angle", default_shape="long", on_axis=True,
         long_equation=17, **_ROTATION),
    Mode("radial", "translation", "the sleeves moved apart across the axis", "Displacement",
         default_shape="finite", on_axis=False, **_TRANSLATION),
    Mode("conical", "rotation", "the sleeves tilted about a diameter", "Tilt angle", default_shape="finite",
         on_axis=False, long_form=False, **_ROTATION),
)
MODE = {m.name: m for m in MODE_TABLE}
MODES = tuple(MODE)
# every frequency a file or the command line gives (measured data, targets, --freq): from
# creep-like tests to the acoustic range; beyond, the time base or the units are wrong
FREQUENCY_HZ = (1e-4, 1e5)
SHAPES = ("long", "finite")  # closed forms of long bushings, or the finite-length table
# the design file's words for them (docs/files.md): "thesis" names the thesis' closed forms, axial
# (eq 18) and torsion (eq 17) only; "long", this project's earlier word for every long-bushing
# closed form, is read as well and written for the plane-strain radial one, no formula of the thesis
FILE_SHAPE = {"long": "thesis", "finite": "finite"}
SHAPE_FROM_FILE = {"thesis": "long", "long": "long", "finite": "finite"}
DEFAULT_SHAPE = {m.name: m.default_shape for m in MODE_TABLE}
TRANSLATIONS = tuple(m.name for m in MODE_TABLE if not m.rotation)  # amplitude in m, stiffness in N/m
ROTATIONS = tuple(m.name for m in MODE_TABLE if m.rotation)  # amplitude in rad, stiffness in N·m/rad
# the thesis' own modes, long by default: its closed forms (eqs 17, 18), slices and continuum
THESIS_MODES = tuple(m.name for m in MODE_TABLE if m.default_shape == "long")


def file_shape(mode_name: str, shape: str) -> str:
    """The design file's word for the shape ``shape`` (:data:`SHAPES`) in mode ``mode_name``."""
    return "long" if shape == "long" and MODE[mode_name].long_equation is None else FILE_SHAPE[shape]


def thesis_shape_refused(mode_name: str) -> str | None:
    """Why a design file's shape ``thesis`` does not go with ``mode_name`` (its rule's words), or
    None where the thesis has a closed form in that mode."""
    if mode_name not in MODE or MODE[mode_name].long_equation is not None:
        return None
    return f"{mode_name}: the thesis' closed forms are axial (eq 18) and torsion (eq 17); use shape 'finite'"


def mode(name: str) -> Mode:
    """The :class:`Mode` called ``name``; ValueError naming the modes otherwise."""
    try:
        return MODE[name]
    except (KeyError, TypeError):
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {name!r}") from None


def no_long_form(mode_name: str) -> str | None:
    """Why ``mode_name`` has no shape ``long`` (its rule's words), or None where it has one."""
    if MODE[mode_name].long_form:
        return None
    return f"{mode_name}: no closed form holds for bushings of real length (shape 'thesis'); use shape 'finite'"
