"""Display units of the explorer and of the plotting API: thin over the one table.

Files, the command line and the core use SI. What people read is in the display units of
:mod:`core.parameters`: each :class:`~core.parameters.Mode` names its drive amplitude's, its
stiffness' and its load's (display value × factor = SI value); the functions below look them up
by mode. The frequency ranges below are the explorer's own.
"""

from __future__ import annotations

from core.parameters import MODE, ROTATIONS, TRANSLATIONS
from core.parameters import mode as _mode

# the frequencies the explorer accepts (Hz), for the operating point and the sweeps
FREQUENCY_BOUNDS = (0.01, 10_000.0)
# the loop frequency's slider (Hz): taps and the slider stay inside it
OPERATING_FREQUENCIES = (0.1, 1000.0)
# the units of every translation (m, N/m: shown in mm, kN/mm) and of every rotation (rad, N·m/rad),
# as the bushing card puts them on two axes
TRANSLATION, ROTATION = MODE[TRANSLATIONS[0]], MODE[ROTATIONS[0]]
# the Fletcher–Gent range of the amplitude axis: equivalent strain from 1e-3 to 1e2 times ε½
FG_RANGE = (1e-3, 1e2)


def amplitude_unit(mode: str) -> str:
    """The drive amplitude's display unit: mm (translations) or rad (rotations)."""
    return _mode(mode).amplitude.display


def stiffness_unit(mode: str) -> str:
    """The stiffness' display unit: kN/mm (translations) or N·m/rad (rotations)."""
    return _mode(mode).stiffness.display


def force_unit(mode: str) -> str:
    """The load's display unit: N (translations) or N·m (rotations)."""
    return _mode(mode).force.display


def to_si_amplitude(x, mode: str):
    """A drive amplitude in display units (mm or rad) in SI (m or rad)."""
    return _mode(mode).amplitude.to_si(x)


def display_amplitude(x_si, mode: str):
    """A drive amplitude in SI (m or rad) in display units (mm or rad)."""
    return _mode(mode).amplitude.to_display(x_si)


def to_si_stiffness(k, mode: str):
    """A stiffness in display units (kN/mm or N·m/rad) in SI (N/m or N·m/rad)."""
    return _mode(mode).stiffness.to_si(k)


def display_stiffness(k, mode: str):
    """A stiffness in SI (N/m or N·m/rad) in display units (kN/mm or N·m/rad)."""
    return _mode(mode).stiffness.to_display(k)
