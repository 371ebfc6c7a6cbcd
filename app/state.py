"""The explorer's state: one parameterized design session, with no Panel import.

Values only. The inputs are in the units engineers read (mm, MPa, kPa, Hz; the drive amplitude in
mm axially and rad in torsion). Computed from them, read-only, in one update per change
(:meth:`ExplorerState._derive`): :attr:`ExplorerState.design`, the last *valid* core design in SI;
:attr:`ExplorerState.errors`, field by field, what is wrong with the current input;
:attr:`ExplorerState.freq_range`, the sweeps' valid range. The views (:mod:`app.tabs`) read these
values and call the pure functions of :mod:`app.curves`; :data:`SHOWN` names what each of them
draws. The fit workflow has its own state (:mod:`app.fit_state`), the what-if targets form its own
(:mod:`app.targets_form`); nothing here draws, and no view writes here while it draws.
"""

from __future__ import annotations

import math

import numpy as np
import param

from core import PAPER_B, TABLE_1, Design
from core.data import DataError, MeasuredLoop, MeasuredStiffness
from core.io.measured import combined, parse_loop, parse_stiffness
from core.numbers import format_number, rounded
from core.parameters import MODE_TABLE, MODES
from core.plausibility import loop_verdict, stiffness_column, stiffness_verdict

from . import curves, units
from .bands import BAND_INPUTS, ToleranceBands
from .fields import DESIGN_FIELDS, DesignFields, design_from_fields, display_values
from .units import FREQUENCY_BOUNDS

PRESETS = {"Paper B bushing (axial)": PAPER_B, "Table 1 bushing (torsion)": TABLE_1}


def _shown_values(design: Design) -> dict:
    """The state parameters that show ``design``."""
    return {"mode": design.mode, "finite_length": design.shape == "finite", **display_values(design)}


def read_measured(parse, content: bytes | str, filename: str):
    """``(parse(content), "")``, or ``(None, message)`` naming the file and what is wrong with it
    (a file the formats of docs/files.md refuse)."""
    try:
        return parse(content), ""
    except DataError as exc:
        return None, f"{filename}: {exc}"


def read_stiffness(content: bytes | str, filename: str, design: Design):
    """A measured-stiffness file read and judged for ``design``'s bushing
    (:func:`core.plausibility.stiffness_verdict`): ``(data, warning)``, or ``(None, message)``
    for a file refused by its format or by its units. The one route every tab loads a stiffness
    file by."""
    data, message = read_measured(parse_stiffness, content, filename)
    if data is None:
        return None, message
    verdict = stiffness_verdict(design, data, filename, stiffness_column(content))
    return (None, verdict.message) if verdict.refused else (data, verdict.warning)


def _shape_doc() -> str:
    """The shape switch's doc: the modes whose closed forms it switches, and the others."""
    long, finite = ([m.name for m in MODE_TABLE if m.default_shape == k] for k in ("long", "finite"))
    return (f"{' and '.join(long).capitalize()}: the thesis' closed forms (long bushing) or the finite-element "
            f"shape factor of this length (torsion's are the same). {' and '.join(finite).capitalize()} always "
            "use the finite-element one.")


def _amplitude_doc() -> str:
    """The drive amplitude's doc: each mode's drive with its unit."""
    drives: dict[tuple[str, str], list[str]] = {}
    for m in MODE_TABLE:
        drives.setdefault((m.drive.lower(), m.amplitude.display), []).append(m.name)
    words = [f"{drive} ({unit}: {', '.join(names)})" for (drive, unit), names in drives.items()]
    return f"Peak {', '.join(words[:-1])} or {words[-1]} of the operating point."


class ExplorerState(DesignFields, ToleranceBands):
    """One user's design session: inputs (the design's fields, :class:`app.fields.DesignFields`),
    the operating point, the pinned reference, measured data, the tolerance bands' inputs
    (:class:`app.bands.ToleranceBands`). The fit of the measured data is the session's
    :class:`app.fit_state.FitState`."""

    preset = param.Selector(
        objects=list(PRESETS), default=None, allow_None=True, label="Preset",
        doc="Load a bushing from the thesis: Paper B (axial) or Table 1 (torsion).",
    )
    mode = param.Selector(
        objects=list(MODES), default=PAPER_B.mode, label="Mode",
        doc=" ".join(f"{m.name.capitalize()}: {m.description}." for m in MODE_TABLE),
    )
    finite_length = param.Boolean(False, label="Finite-length shape factor", doc=_shape_doc())

    amplitude = param.Number(0.1, bounds=(1e-12, None), label="Drive amplitude", doc=_amplitude_doc())
    frequency_hz = param.Number(
        10.0, bounds=FREQUENCY_BOUNDS, label="Loop frequency",
        doc="Frequency of the operating point: the hysteresis loop and the highlighted curves.",
    )
    freq_min = param.Number(1.0, allow_None=True, label="Sweep from (Hz)", doc="Lowest frequency of the sweeps.")
    freq_max = param.Number(100.0, allow_None=True, label="Sweep to (Hz)", doc="Highest frequency of the sweeps.")

    # computed from the inputs above (read-only: ExplorerState._derive writes them, in one update)
    design = param.ClassSelector(class_=Design, default=PAPER_B, constant=True, doc="The last valid design (SI).")
    errors = param.Dict(default={}, constant=True, doc="Input field → what is wrong with it.")
    freq_range = param.NumericTuple(default=(1.0, 100.0), length=2, constant=True,
                                    doc="The sweeps' frequency range (Hz): freq_min to freq_max, or 1–100 Hz "
                                    "while they are not valid.")
    reference = param.ClassSelector(class_=Design, default=None, allow_None=True, doc="Pinned design.")

    effects = param.Dict(default={}, doc="Model extensions carried by a loaded design.")

    measured = param.ClassSelector(class_=MeasuredStiffness, default=None, allow_None=True,
                                   doc="Measured dynamic stiffness (SI).")
    measured_loop = param.ClassSelector(class_=MeasuredLoop, default=None, allow_None=True,
                                        doc="A measured steady loop (SI).")
    data_message = param.String(default="", doc="What was wrong with the last file, if anything.")
    data_note = param.String(default="", doc="What the last load warns of or did beyond loading (a unit "
                             "that looks wrong, the operating point moved to a loop's), if anything.")
    measured_warning = param.String(default="", doc="The unit warnings of the stiffness loaded (kept with "
                                    "those data: the diagnosis tab repeats them when it uses them).")

    def __init__(self, **params):
        self._loaded = []  # the last design loaded (a file, a fit): kept while the inputs show it
        super().__init__(**params)
        self.param.watch(self._derive, [*DERIVED_FROM, "amplitude"])
        self._derive()

    # ---- inputs → design -------------------------------------------------------------------

    @param.depends("preset", watch=True)
    def _apply_preset(self):
        if self.preset is None:
            return
        self.load_design(PRESETS[self.preset])

    def _derive(self, *events):
        """The computed values (design, errors, freq_range) from the inputs, in one update: a view
        that draws several of them is told once. A mode changed alone (not with the amplitude, as
        a preset or a link sets both) also moves the amplitude to the same equivalent strain in
        the new mode's unit."""
        names = {e.name for e in events}
        if names == {"amplitude"}:
            return
        shape = "finite" if self.finite_length else None
        fields = {name: getattr(self, name) for name in DESIGN_FIELDS}
        design, errors = design_from_fields(fields, self.design, self.mode, shape, self.effects, edited=names)
        design = self.design if design is None else _match_shown(design, [*PRESETS.values(), *self._loaded])
        errors.update(frequency_errors(self.freq_min, self.freq_max))
        values = {"freq_range": (1.0, 100.0) if {"freq_min", "freq_max"} & set(errors)
                  else (float(self.freq_min), float(self.freq_max))}
        if design != self.design:
            values["design"] = design
        if errors != self.errors:
            values["errors"] = errors
        if names == {"mode"}:
            (event,) = events
            amplitude = same_strain(self.amplitude, event.old, event.new, design, shape)
            if amplitude is not None:
                values["amplitude"] = amplitude
        with param.edit_constant(self):
            self.param.update(values)

    def load_design(self, design: Design):
        """Show ``design`` (a preset, a file, a fit), its operating amplitude mid-range."""
        x_mid = curves.fletcher_gent_amplitudes(design)[2]
        self._loaded = [design]
        self.param.update(
            **_shown_values(design),
            effects=design.portable_effects,  # a rig's mass stays with its mode
            amplitude=rounded(x_mid, 3),
        )

    # ---- measured data (their fit: app.fit_state.FitState) ------------------------------------

    def load_measured(self, content: bytes | str, filename: str = "stiffness file") -> bool:
        """Read a measured-stiffness CSV (docs/files.md); on a bad file say why and keep the last."""
        return self.load_measured_files({filename: content})

    def load_measured_loop(self, content: bytes | str, filename: str = "loop file") -> bool:
        """Read a measured-loop CSV, judged for the design's bushing
        (:func:`core.plausibility.loop_verdict`); the operating point moves to the loop's
        frequency and amplitude, so that the model's loop is drawn over the measured one, and
        ``data_note`` says so."""
        def parse(text):
            loop = parse_loop(text)
            return loop, loop.harmonic()

        read, message = read_measured(parse, content, filename)
        if read is None:
            self.data_message = message
            return False
        data, (f, amp, _) = read
        verdict = loop_verdict(self.design, data, filename)
        if verdict.refused:
            self.data_message = verdict.message
            return False
        x = float(units.display_amplitude(amp, self.design.mode))
        lo, hi = curves.amplitude_bounds(self.design)
        unit = units.amplitude_unit(self.design.mode)
        problem = None
        if not FREQUENCY_BOUNDS[0] <= f <= FREQUENCY_BOUNDS[1]:
            problem = f"its frequency {format_number(f, 3)} Hz is outside {FREQUENCY_BOUNDS[0]:g}–{FREQUENCY_BOUNDS[1]:g} Hz"
        elif not lo <= x <= hi:
            problem = (f"its amplitude {format_number(x, 3)} {unit} is outside this bushing's amplitude axis "
                       f"({format_number(lo, 3)}–{format_number(hi, 3)} {unit})")
        if problem:
            self.data_message = f"{filename}: {problem}; not loaded"
            return False
        # the loop's own frequency and amplitude are estimates (0.09999999973 Hz): the quantities' digits
        frequency, amplitude = rounded(float(np.clip(f, *FREQUENCY_BOUNDS)), 4), rounded(x, 4)
        moved = ""
        if (frequency, amplitude) != (self.frequency_hz, self.amplitude):
            moved = (f"{filename}: the operating point moved to the loop's {format_number(frequency, 4)} Hz and {format_number(amplitude, 4)} "
                     f"{unit} (it was {format_number(self.frequency_hz, 4)} Hz, {format_number(self.amplitude, 4)} {unit}), so that the "
                     "model's loop is drawn over the measured one.")
        self.param.update(measured_loop=data, frequency_hz=frequency, amplitude=amplitude, data_message="",
                          data_note=" ".join(n for n in (verdict.warning, moved) if n))
        return True

    def clear_measured(self):
        self.param.update(measured=None, measured_loop=None, data_message="", data_note="", measured_warning="")

    def load_measured_files(self, files: dict) -> bool:
        """Several measured-stiffness files (name → content) as one table: a file without a mode
        column is in the design's mode. A bad file (its format, or units its numbers betray:
        :func:`read_stiffness`) is left out with its message; the others load. None good: the
        last data kept."""
        parts, refused, warned = [], [], []
        for name, content in files.items():
            data, message = read_stiffness(content, name, self.design)
            if data is None:
                refused.append(message)
            else:
                parts.append(data)
                warned.append(message)
        if parts:  # each refused file's own "Not loaded." said once, for them all
            refused = [m.removesuffix(" Not loaded.") for m in refused]
        note = "; ".join(refused) + (" (not loaded; the other files are)" if refused and parts else "")
        if not parts:
            self.data_message = note
            return False
        warning = " ".join(w for w in warned if w)
        self.param.update(measured=combined(parts, self.design.mode), data_message=note, data_note=warning,
                          measured_warning=warning)
        return not refused

    def adopt(self, design: Design):
        """Show ``design`` (a fit, a diagnosis) at the operating point the user had."""
        amplitude, frequency = self.amplitude, self.frequency_hz
        self.load_design(design)
        self.param.update(amplitude=amplitude, frequency_hz=frequency)

    def apply_url_values(self, values: dict, refused: dict[str, str] | None = None):
        """Apply values from a shared link (together; one by one if one is refused after all,
        so that it spoils no other) and say, beside each field, why the link's ``refused`` ones
        (field → message, :mod:`app.link`) were not applied."""
        unusable = dict(refused or {})
        try:
            self.param.update(values)
        except Exception:  # noqa: BLE001 - a value its parameter refuses: apply the others
            for name, value in values.items():
                try:
                    self.param.update({name: value})
                except Exception:  # noqa: BLE001 - keep the last value, say so
                    unusable[name] = f"The link's value {value!r} was not usable; kept {getattr(self, name)!r}."
        if unusable:
            with param.edit_constant(self):
                self.errors = {**self.errors, **unusable}

    def name_design(self, name: str):
        """Call the design the inputs show ``name`` (a link's), as long as they show it."""
        self._loaded = [self.design.replace(name=name)]
        self._derive()

    def pin_reference(self):
        self.reference = self.design

    def clear_reference(self):
        self.reference = None


# what the computed values (design, errors, freq_range) are computed from
DERIVED_FROM = (*DESIGN_FIELDS, "mode", "finite_length", "effects", "freq_min", "freq_max")


def frequency_errors(freq_min, freq_max) -> dict[str, str]:
    """What is wrong with the sweeps' frequency range (field → message), or nothing."""
    if freq_min is None or not math.isfinite(freq_min) or freq_min <= 0:
        return {"freq_min": "Enter a positive frequency."}
    if freq_max is None or not math.isfinite(freq_max) or freq_max <= freq_min:
        return {"freq_max": "Must be above the lowest frequency."}
    if freq_max > FREQUENCY_BOUNDS[1]:
        return {"freq_max": f"At most {FREQUENCY_BOUNDS[1]:g} Hz."}
    return {}


def same_strain(amplitude: float, old: str, new: str, design: Design, shape: str | None) -> float | None:
    """The drive amplitude (display units of mode ``new``, 3 digits) at the equivalent strain
    that ``amplitude`` (display units of mode ``old``) gives ``design``'s bushing, or None for a
    geometry outside the finite-length table (the validation says so)."""
    g, m = design.geometry, design.material
    try:
        eps = Design(old, g, m, shape=shape).strain(units.to_si_amplitude(amplitude, old))
        x = units.display_amplitude(Design(new, g, m, shape=shape).drive(eps), new)
    except ValueError:
        return None
    return rounded(x, 3)


def measured_amplitudes(measured: MeasuredStiffness | None) -> list[float]:
    """The distinct measured amplitudes (SI), most frequent first."""
    return [] if measured is None else [float(v) for v in measured.amplitudes()]


# what the views draw, by what it is: the state's parameters of each, and those of the session's
# fit (app.fit_state.FitState) as "fit.NAME" (a view names the ones it shows, app.views.PlotView.shows;
# it is told of a change of any of their parameters)
SHOWN = {
    "design": ("design",),  # the last valid design (SI)
    "frequency": ("frequency_hz",),  # the operating point's frequency
    "amplitude": ("amplitude",),  # the operating point's amplitude (display units)
    "sweep range": ("freq_range",),
    "reference": ("reference",),
    "measured": ("measured", "measured_loop"),
    "bands": (*BAND_INPUTS, "fit.fit_result"),  # the band inputs, and the fit whose covariance they may use
    "fit": ("fit.fit_result", "fit.fit_method"),
}


def _match_shown(design: Design, known) -> Design:
    """A known design itself (exact SI values, its name) when the inputs show it: a preset, or
    the design last loaded from a file or a fit."""
    shown = _shown_values(design)
    for candidate in known:
        if _shown_values(candidate) == shown and candidate.effects == design.effects:
            return candidate
    return design
