"""The hostile corpus' vocabulary (tests/hostile_corpus.py): what a case is and what it expects
(:class:`Refused` or :class:`Accepted`), the corpus' good design, and the JSON values it puts in
place of numbers, read as docs/files.md reads them.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass

DESIGN = {"name": "corpus", "mode": "axial", "geometry": {"inner_radius": 0.02, "outer_radius": 0.035, "length": 0.09},
          "material": {"shear_modulus": 2420000.0, "fractional_coefficient": 600000.0, "fractional_order": 0.2,
                       "friction_stress_max": 19200.0, "friction_strain_half": 0.004}}
_A, _B = DESIGN["geometry"]["inner_radius"], DESIGN["geometry"]["outer_radius"]
STRAIN_FACTOR = 1.0 / math.sqrt(2.0 * (_B * _B - _A * _A) * math.log(_B / _A))  # ε_eq = c·x, eq 15
# JSON texts put in place of a number
BAD_NUMBERS = ["0", "-1", "-0.0", "1e-300", "1e300", "1" + "0" * 400, "NaN", "Infinity", "-Infinity", '"2.4e6"',
               "null", "true", "[]", "{}", "1e-12", "4_858_578", "0x10", '""']


@dataclass(frozen=True)
class Refused:
    words: tuple[str, ...]
    status: int = 2


def no(*words: str) -> Refused:
    return Refused(words)


@dataclass(frozen=True)
class Accepted:
    output: str  # stiffness, band, loop, fit, diagnose or design
    same_as: tuple[str, ...] | None = None
    words: tuple[str, ...] = ()
    rtol: float = 1e-12  # for same_as: the same computation, up to a term below round-off


@dataclass(frozen=True)
class Case:
    name: str
    argv: tuple[str, ...]
    expect: Refused | Accepted


NOT_JSON = object()


def parsed(text: str):
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return NOT_JSON


def finite(value) -> float | None:
    """A JSON value as a finite float, or None (not a number, NaN, infinite, too large)."""
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    return float(value) if number and abs(value) <= sys.float_info.max else None
