"""Display units of the explorer and of the plotting API, in one place.

Files, the command line and the core use SI. What people read is in the units below: lengths in
mm, moduli in MPa (σ_fmax in kPa), the drive amplitude in mm axially and radially and rad in
torsion and tilt (conical), the stiffness in kN/mm (= MN/m) and N·m/rad. Each table maps a mode to
``(unit, factor)``: display value × factor = SI value.
"""

from __future__ import annotations

import numpy as np

AMPLITUDE = {"axial": ("mm", 1e-3), "torsion": ("rad", 1.0), "radial": ("mm", 1e-3), "conical": ("rad", 1.0)}
STIFFNESS = {"axial": ("kN/mm", 1e6), "torsion": ("N·m/rad", 1.0), "radial": ("kN/mm", 1e6),
             "conical": ("N·m/rad", 1.0)}
FORCE = {"axial": ("N", 1.0), "torsion": ("N·m", 1.0), "radial": ("N", 1.0), "conical": ("N·m", 1.0)}
DRIVE = {"axial": "Displacement", "torsion": "Angle", "radial": "Displacement", "conical": "Tilt angle"}
LOAD = {"axial": "Force", "torsion": "Moment", "radial": "Force", "conical": "Moment"}

# the frequencies the explorer accepts (Hz), for the operating point and the sweeps
FREQUENCY_BOUNDS = (0.01, 10_000.0)
# the loop frequency's slider (Hz): taps and the slider stay inside it
OPERATING_FREQUENCIES = (0.1, 1000.0)
# the Fletcher–Gent range of the amplitude axis: equivalent strain from 1e-3 to 1e2 times ε½
FG_RANGE = (1e-3, 1e2)


def amplitude_unit(mode: str) -> str:
    return AMPLITUDE[mode][0]


def stiffness_unit(mode: str) -> str:
    return STIFFNESS[mode][0]


def force_unit(mode: str) -> str:
    return FORCE[mode][0]


def to_si_amplitude(x, mode: str):
    """A drive amplitude in display units (mm or rad) in SI (m or rad)."""
    return np.asarray(x, dtype=float) * AMPLITUDE[mode][1]


def display_amplitude(x_si, mode: str):
    """A drive amplitude in SI (m or rad) in display units (mm or rad)."""
    return np.asarray(x_si, dtype=float) / AMPLITUDE[mode][1]


def to_si_stiffness(k, mode: str):
    """A stiffness in display units (kN/mm or N·m/rad) in SI (N/m or N·m/rad)."""
    return np.asarray(k, dtype=float) * STIFFNESS[mode][1]


def display_stiffness(k, mode: str):
    """A stiffness in SI (N/m or N·m/rad) in display units (kN/mm or N·m/rad)."""
    return np.asarray(k) / STIFFNESS[mode][1]
