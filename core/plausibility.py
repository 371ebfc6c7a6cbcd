"""Is a measured file in the units docs/files.md asks for? One verdict per file, from physics:
the design's own geometry and material say what a test of this bushing can show.

- The amplitudes (m or rad) give this bushing an equivalent strain; one above
  :data:`MAX_PLAUSIBLE_STRAIN` tears any rubber: the file is refused ("the amplitudes look like mm").
- The measured |K| against the model's at the file's own points: a ratio of
  :data:`REFUSED_RATIO` or more either way is no material of this bushing but a unit (kN/mm
  for N/m is 10⁻⁶): refused; from :data:`WARNED_RATIO` on, loaded with a warning.
- A file that fits this bushing in another direction (a torsion file, rad and N·m/rad, loaded
  in axial mode) is named as such.

Pure: the app (at upload, stored once in the session), the diagnosis and the command line all
call :func:`stiffness_verdict` and :func:`loop_verdict`, so they never disagree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .bushing import MIN_MEASURED_STRAIN, check_measured_amplitude, stiffness_points
from .data import MeasuredLoop, MeasuredStiffness
from .design import Design
from .parameters import MODE, MODE_TABLE, MODES

MAX_PLAUSIBLE_STRAIN = 1.0  # equivalent strain amplitude: 100 %, beyond any dynamic test of rubber
REFUSED_RATIO = 100.0  # measured |K| / model |K| (or its inverse) from which a file is refused
WARNED_RATIO = 10.0  # … from which it is loaded with a warning
MODEL_STRAIN = (1e-5, 0.3)  # the model is asked at strains clipped to this range (the file's may be absurd)
# a ratio near one of these powers of ten names the unit the file is likely in (translations)
STIFFNESS_UNITS = {-6: "kN/mm (or N/µm)", -3: "N/mm (or kN/m)", 3: "mN/m", 6: "N/km"}


@dataclass(frozen=True)
class Verdict:
    """What a file's numbers say about its units: ``refused`` (not loaded), or loaded with
    ``warnings``; ``messages`` name the file, the column and the likely cause."""

    refused: bool = False
    messages: tuple[str, ...] = ()

    @property
    def message(self) -> str:
        return " ".join(self.messages)

    @property
    def warning(self) -> str:
        """The warnings of a loaded file ("" if none or refused)."""
        return "" if self.refused else self.message


PLAUSIBLE = Verdict()


def stiffness_column(text: str | bytes | None) -> str:
    """The name of the |K| column(s) in a stiffness file's header, for messages."""
    if isinstance(text, bytes):
        text = text[:4096].decode("utf-8", "replace")
    header = next((line for line in (text or "").splitlines() if line.strip() and not line.startswith("#")), "")
    cols = [c.strip().lower() for c in header.split(",")]
    return "stiffness_real and stiffness_imag" if "stiffness_real" in cols else "magnitude"


def _ratio_cause(ratio: float, mode: str, per_amplitude: bool = False) -> str:
    """The likely unit of a |K| ``ratio`` times the model's (``per_amplitude``: a loop's force
    over its displacement)."""
    unit = MODE[mode].stiffness.si
    power = 3 * round(math.log10(ratio) / 3)
    if per_amplitude:
        force = MODE[mode].force.si
        return (f"the forces look like k{force}, not {force}" if power == -3 and not MODE[mode].rotation
                else f"are the forces in {force} and the displacements in {MODE[mode].amplitude.si}?")
    if MODE[mode].rotation or power not in STIFFNESS_UNITS:
        return f"is |K| in {unit}?"
    return f"the |K| values look like {STIFFNESS_UNITS[power]}, not {unit}"


def _other_mode(design: Design, amplitude, frequency_hz, magnitude, within: float) -> str | None:
    """The other direction whose model is nearest the file (plausible strains, |K| within
    ``within`` times the model's), if one is."""
    best, nearest = None, math.log10(within)
    for mode in MODES:
        if mode == design.mode:
            continue
        other = design.in_mode(mode)
        strain = other.strain(amplitude)
        if float(np.max(strain)) > MAX_PLAUSIBLE_STRAIN or float(np.min(strain)) < MIN_MEASURED_STRAIN:
            continue
        far = abs(math.log10(_median_ratio(other, frequency_hz, amplitude, magnitude)))
        if far < nearest:
            best, nearest = mode, far
    return best


def _mode_cause(design: Design, other: str | None) -> str:
    """A file of another direction: the one named, or any of the other kind of motion."""
    if other is not None:
        unit = MODE[other]
        return (f"it looks like a {other} file ({unit.amplitude.si}, {unit.stiffness.si}): give the design "
                f"in {other} mode (the explorer: switch its mode) first")
    kind = [m for m in MODE_TABLE if m.rotation != MODE[design.mode].rotation]
    names = " or ".join(m.name for m in kind)
    return (f"both columns are off: it looks like a file of another direction ({names}: "
            f"{kind[0].amplitude.si}, {kind[0].stiffness.si}); give the design in that mode (the explorer: switch its mode) first")


def _median_ratio(design: Design, frequency_hz, amplitude, magnitude) -> float:
    """Median measured |K| / the model's at the same points (strains clipped to :data:`MODEL_STRAIN`)."""
    strain = np.clip(design.strain(amplitude), *MODEL_STRAIN)
    model = np.abs(stiffness_points(design, frequency_hz, design.drive(strain)))
    return float(np.median(magnitude / model))


def _span(values, unit: str) -> str:
    lo, hi = float(np.min(values)), float(np.max(values))
    return f"{lo:.3g} {unit}" if f"{lo:.3g}" == f"{hi:.3g}" else f"{lo:.3g}–{hi:.3g} {unit}"


def _judge(design: Design, filename: str, frequency_hz, amplitude, magnitude, column: str,
           amplitude_column: str = "amplitude", per_amplitude: bool = False) -> Verdict:
    """One direction's points: the strains, then |K| against the model. ``per_amplitude``: the
    |K| is a force over these amplitudes (a loop's), so an amplitude in mm scales it too."""
    mode = MODE[design.mode]
    a_unit = mode.amplitude.si
    strain = design.strain(amplitude)
    top, bottom = float(np.max(strain)), float(np.min(strain))
    ratio = _median_ratio(design, frequency_hz, amplitude, magnitude)
    far = max(ratio, 1 / ratio)
    if top > MAX_PLAUSIBLE_STRAIN or bottom < MIN_MEASURED_STRAIN:
        where = f"{filename}: " + (f"column {amplitude_column}" if amplitude_column == "amplitude" else
                                   f"the amplitude of column {amplitude_column}")
        try:  # the data rule (resolution to breaking strain), in its own words
            check_measured_amplitude(design, amplitude, where)
            said = (f"{where}: {_span(amplitude, a_unit)} would strain this {design.mode} bushing up to "
                    f"{top:.3g}, beyond any rubber")
        except ValueError as exc:
            if top <= MAX_PLAUSIBLE_STRAIN:  # below resolution: the rule says why and what to check
                return Verdict(True, (f"{exc} Not loaded.",))
            said = str(exc)
        milli = ratio * 1e3 if per_amplitude else ratio  # as if the amplitudes were mm
        if max(milli, 1 / milli) < REFUSED_RATIO:
            likely = f"the amplitudes look like {'degrees or mrad' if mode.rotation else 'mm'}, not {a_unit}"
        elif far >= REFUSED_RATIO:
            likely = _mode_cause(design, _other_mode(design, amplitude, frequency_hz, magnitude, REFUSED_RATIO))
        else:
            likely = f"check that they are in {a_unit}"
        return Verdict(True, (f"{said}; {likely}. Not loaded.",))
    if far < WARNED_RATIO:
        return PLAUSIBLE
    said = (f"{filename}: column {column}: the measured |K| is {ratio:.3g} × this {design.mode} design's "
            f"at the same points")
    if far >= REFUSED_RATIO:
        likely = _ratio_cause(ratio, design.mode, per_amplitude)
        other = _other_mode(design, amplitude, frequency_hz, magnitude, WARNED_RATIO)
        if other is not None:
            likely += f", or {_mode_cause(design, other).removeprefix('it looks like ')}"
        return Verdict(True, ((f"{said}; {likely} (if the design is not this bushing, set its geometry "
                              "and material first). Not loaded."),))
    return Verdict(False, ((f"{said}: check the unit ({mode.stiffness.si}) or the design's geometry and "
                           "material. Loaded."),))


def stiffness_verdict(design: Design, data: MeasuredStiffness, filename: str = "stiffness file",
                      column: str = "magnitude") -> Verdict:
    """The verdict on measured stiffness (SI as read) for ``design``'s bushing: each mode's rows
    (the file's ``mode`` column, or the design's mode) against the design in that mode.
    ``column`` names the file's |K| column(s) (:func:`stiffness_column`)."""
    refused, messages = False, []
    modes = data.modes(design.mode).astype(str)
    for mode in np.unique(modes):
        rows = modes == mode
        v = _judge(design.in_mode(mode) if mode != design.mode else design, filename,
                   data.frequency_hz[rows], data.amplitude[rows], data.magnitude[rows], column)
        refused |= v.refused
        messages += v.messages
    return Verdict(refused, tuple(messages))


def loop_verdict(design: Design, loop: MeasuredLoop, filename: str = "loop file") -> Verdict:
    """The verdict on a measured loop for ``design``'s bushing: its amplitude (the strain) and
    its peak force per peak displacement against the model's |K| at its frequency and amplitude."""
    f, amp, _ = loop.harmonic()
    force = loop.force - np.mean(loop.force)
    ratio_k = float(np.max(np.abs(force))) / amp
    return _judge(design, filename, np.array([f]), np.array([amp]), np.array([ratio_k]),
                  "force (per displacement)", "displacement",
                  per_amplitude=True)
