"""The one table of the design's parameters, the modes and their units.

Every other list of parameters or modes (the design file's keys, the fit's names and ranges, the
sensitivities, the tolerances, the explorer's fields and link, the exports' units, the words of
the diagnosis) is made from these two tables; none is typed out elsewhere.

Design parameters (docs/model.md, "Symbols"):

====== ========================== ========= ========= ======= ===========================================
symbol name                       SI unit   display   factor  meaning
====== ========================== ========= ========= ======= ===========================================
a      ``inner_radius``           m         mm        1e-3    inner (bonded) radius
b      ``outer_radius``           m         mm        1e-3    outer (bonded) radius, b > a
L      ``length``                 m         mm        1e-3    bushing length
µ      ``shear_modulus``          Pa        MPa       1e6     elastic shear modulus
m      ``fractional_coefficient`` Pa·s^α    MPa·s^α   1e6     fractional-derivative coefficient
α      ``fractional_order``       –         –         1       fractional order, 0 < α ≤ 1
σ_fmax ``friction_stress_max``    Pa        kPa       1e3     largest friction stress
ε½     ``friction_strain_half``   –         –         1       strain at which half of σ_fmax is built
====== ========================== ========= ========= ======= ===========================================

A display value × factor is the SI value. Modes: axial and radial are translations (m, N/m,
shown in mm and kN/mm), torsion and conical rotations (rad, N·m/rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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


@dataclass(frozen=True)
class DesignParameter:
    """One parameter of a design: its key in files and code, where it lives (``geometry`` or
    ``material``), its symbol, units, its key in a link's tolerances (``tol=mu:10``), the label
    and one-line doc of its field, and the range a fit searches (SI; None: not fitted)."""

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
                    "shear modulus µ", (1e2, 1e11)),
    DesignParameter("fractional_coefficient", "material", "m", Unit("Pa·s^α", "MPa·s^α", 1e6), "m",
                    "Fractional coefficient m", "Fractional coefficient m: size of the frequency dependence.",
                    "fractional coefficient m", (1e-2, 1e11)),
    DesignParameter("fractional_order", "material", "α", Unit("–", "–"), "alpha", "Fractional order α",
                    "Fractional order α in (0, 1]: how fast stiffness rises with frequency.",
                    "fractional order α in (0, 1]", (1e-3, 1.0), log=False),
    DesignParameter("friction_stress_max", "material", "σ_fmax", Unit("Pa", "kPa", 1e3), "sigma",
                    "Friction stress σ_fmax", "Largest friction stress σ_fmax: size of the amplitude dependence.",
                    "largest friction stress σ_fmax", (1e-3, 1e9)),
    DesignParameter("friction_strain_half", "material", "ε½", Unit("–", "–"), "eps_half", "Friction strain ε½",
                    "Strain ε½ at which half of σ_fmax is built: where the softening happens.",
                    "strain ε½ to build half of σ_fmax", (1e-9, 10.0)),
)
BY_NAME = {p.name: p for p in PARAMETERS}
GEOMETRY = tuple(p.name for p in PARAMETERS if p.group == "geometry")
MATERIAL = tuple(p.name for p in PARAMETERS if p.group == "material")
NAMES = GEOMETRY + MATERIAL


@dataclass(frozen=True)
class Mode:
    """One direction of the bushing: how its sleeves move, and the units of its drive, load,
    stiffness and apparent mass."""

    name: str
    motion: str  # "translation" or "rotation"
    description: str
    drive: str  # what the drive is called: Displacement, Angle, Tilt angle
    load: str  # Force or Moment
    amplitude: Unit
    stiffness: Unit
    force: Unit
    mass: str  # the unit of an apparent mass in this mode: kg or kg·m²
    default_shape: str  # the shape factor used unless a design names one (SHAPES)

    @property
    def rotation(self) -> bool:
        return self.motion == "rotation"


_TRANSLATION = {"amplitude": Unit("m", "mm", 1e-3), "stiffness": Unit("N/m", "kN/mm", 1e6),
                "force": Unit("N", "N"), "mass": "kg", "load": "Force"}
_ROTATION = {"amplitude": Unit("rad", "rad"), "stiffness": Unit("N·m/rad", "N·m/rad"),
             "force": Unit("N·m", "N·m"), "mass": "kg·m²", "load": "Moment"}

MODE_TABLE: tuple[Mode, ...] = (
    # axial and torsion: the thesis' closed forms (eqs 17, 18); radial and conical have none that
    # holds at real lengths, so the finite-length table (core.shape)
    Mode("axial", "translation", "the sleeves moved apart along the axis", "Displacement",
         default_shape="long", **_TRANSLATION),
    Mode("torsion", "rotation", "the sleeves turned about the axis", "Angle", default_shape="long", **_ROTATION),
    Mode("radial", "translation", "the sleeves moved apart across the axis", "Displacement",
         default_shape="finite", **_TRANSLATION),
    Mode("conical", "rotation", "the sleeves tilted about a diameter", "Tilt angle", default_shape="finite",
         **_ROTATION),
)
MODE = {m.name: m for m in MODE_TABLE}
MODES = tuple(MODE)
SHAPES = ("long", "finite")  # closed forms of long bushings, or the finite-length table
DEFAULT_SHAPE = {m.name: m.default_shape for m in MODE_TABLE}
TRANSLATIONS = tuple(m.name for m in MODE_TABLE if not m.rotation)  # amplitude in m, stiffness in N/m
ROTATIONS = tuple(m.name for m in MODE_TABLE if m.rotation)  # amplitude in rad, stiffness in N·m/rad


def mode(name: str) -> Mode:
    """The :class:`Mode` called ``name``; ValueError naming the modes otherwise."""
    try:
        return MODE[name]
    except (KeyError, TypeError):
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {name!r}") from None

