"""The fit workflow of a session: fit the five material parameters to the session's measured
data (:class:`app.state.ExplorerState` keeps the data and its loaders), keep the result, take
it into the explorer. No Panel import.

The fit belongs to the data it was made on: a new data load or a clear forgets it
(:meth:`FitState._forget`), before any view hears of the new data, so that every view reads
the new data and no fit together (and is drawn once: :class:`app.views.PlotView` draws values it
has drawn once only).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import param

from core.identify.fit import FitResult, Progress, fit_global, fit_two_step, predicted, selection
from core.numbers import parse_number
from core.parameters import MODE, MODE_TABLE
from core.rules import RuleError

from .state import ExplorerState, measured_amplitudes

# the session's data a fit is made on (ExplorerState's parameters): a change of either forgets the fit
FIT_DATA = ("measured", "measured_loop")
# what a view that shows the fit depends on, as a view with a ``state`` and a ``fit`` names it in
# @param.depends: the fit, and the data (the fit is forgotten when they change, :meth:`FitState._forget`)
FIT_DEPENDS = ("fit.fit_result", *(f"state.{n}" for n in FIT_DATA))


class FitState(param.Parameterized):
    """The fit workflow of one session: its settings, the last fit, and the steps (compute,
    store, use). ``state`` holds the measured data (SI) and the design (the fit's first start)."""

    state = param.ClassSelector(class_=ExplorerState, constant=True, doc="The session whose data is fitted.")

    fit_result = param.ClassSelector(class_=FitResult, default=None, allow_None=True,
                                     doc="The last fit of the current data, or None.")
    fit_method = param.Selector(
        objects=["global", "two-step"], default="global", label="Method",
        doc="Global: all five parameters to all data at once. Two-step (the thesis'): the loop "
        "gives µ, σ_fmax and ε½, the frequency sweep at one amplitude gives m and α.",
    )
    sweep_amplitude = param.Number(default=None, allow_None=True, label="Sweep amplitude",
                                   doc="The amplitude (SI) whose frequency sweep the two-step fit uses.")
    fit_on = param.String(default="", label="Fit on (the rest is predicted)",
                          doc="Empty: fit every row. Else mode=NAME[+NAME…] and/or amplitude=VALUE[+VALUE…] "
                          "in the tab's units (mm for axial and radial rows, rad for torsion and conical), "
                          "comma-separated, e.g. mode=axial,amplitude=0.1: the fit uses those rows and "
                          "predicts the others, with the gap of each mode and amplitude.")

    # a fit under way (app.work.in_thread): where it is, for the page's progress line
    running = param.Boolean(default=False, doc="Whether a fit of this session is under way.")
    progress = param.Number(default=0.0, bounds=(0.0, 1.0), doc="How far the running fit is (0–1).")
    progress_message = param.String(default="", doc="Where the running fit is, in words (\"start 2 of 8\").")

    def __init__(self, state: ExplorerState, **params):
        super().__init__(state=state, **params)

    @param.depends(*(f"state.{n}" for n in FIT_DATA), watch=True)
    def _forget(self):
        """New data (or none): the fit of the old data is gone. The session's FitState is made
        before its views (:class:`app.main.App`), so this watcher of the data is called before
        theirs (Param calls the watchers of one precedence in the order they were made): a view
        told of the fit's change reads the new data too, and is not drawn again when it hears
        of the data (the same values)."""
        self.fit_result = None

    def compute_fit(self, progress: Progress | None = None) -> FitResult:
        """Fit the five material parameters to the measured data (the current design is the
        first start), telling ``progress(fraction, message)`` where it is, if given
        (:func:`core.identify.fit.fit_global`). Pure: safe to run in a worker thread;
        :meth:`store_fit` stores it."""
        s = self.state
        if s.measured is None and s.measured_loop is None:
            raise ValueError("load measured stiffness (and optionally a loop) first")
        if self.fit_method == "two-step":
            if s.measured is None or s.measured_loop is None:
                raise ValueError("the two-step fit needs a loop and a frequency sweep: load both")
            amps = measured_amplitudes(s.measured)
            amp = self.sweep_amplitude if self.sweep_amplitude in amps else amps[0]
            sweep = s.measured.select(s.measured.amplitude == amp)
            if len(sweep) < 3:
                raise ValueError("the sweep at that amplitude has fewer than 3 points")
            return fit_two_step(s.design, s.measured_loop, sweep, progress=progress)
        if not self.fit_on.strip() or s.measured is None:
            return fit_global(s.design, s.measured, s.measured_loop, progress=progress)
        spec = self.fit_on.strip()[:500]
        chosen = shown_selection(s.measured, s.design.mode, spec)
        result = fit_global(s.design, s.measured.select(chosen), s.measured_loop, progress=progress)
        return dataclasses.replace(result, prediction=predicted(result, s.measured, chosen, spec))

    def try_fit(self, progress: Progress | None = None) -> FitResult | str:
        """:meth:`compute_fit`, or why it cannot run (pure: safe in a worker thread)."""
        try:
            return self.compute_fit(progress)
        except ValueError as exc:
            return str(exc)

    def store_fit(self, outcome: FitResult | str):
        """Keep a fit (and forget an earlier message), or say why there is none (the state's
        ``data_message``)."""
        if isinstance(outcome, FitResult):
            self.fit_result = outcome
            self.state.data_message = ""
        else:
            self.state.data_message = outcome

    def run_fit(self):
        self.store_fit(self.try_fit())

    def use_fit(self):
        """Take the fitted design into the explorer, keeping the operating point."""
        if self.fit_result is not None:
            self.state.adopt(self.fit_result.design)


# the amplitudes' display units, in the words of a message: "mm (axial, radial) or rad (torsion, conical)"
_AMPLITUDE_UNITS = " or ".join(
    f"{u} ({', '.join(m.name for m in MODE_TABLE if m.amplitude.display == u)})"
    for u in dict.fromkeys(m.amplitude.display for m in MODE_TABLE))


def shown_selection(data, design_mode: str, spec: str) -> np.ndarray:
    """The rows of ``data`` that *Fit on* chooses: as :func:`core.identify.fit.selection` (the
    command line's ``--fit-on``, SI), but the amplitudes in the tab's display units, each row's
    in its mode's (mm or rad), matched to the 4 digits the tab shows them with. ValueError on a
    bad spec or an empty choice, in the tab's words."""
    chosen = np.ones(len(data), dtype=bool)
    modes = data.modes(design_mode).astype(str)
    shown = np.asarray(data.amplitude, dtype=float) / np.array([MODE[m].amplitude.factor for m in modes])
    for item in filter(None, (part.strip() for part in spec.split(","))):
        key, _, value = item.partition("=")
        if key.strip() != "amplitude":
            chosen &= selection(data, design_mode, item)  # mode=…, and the words for a bad item
            continue
        try:
            amps = [parse_number(v) for v in value.split("+") if v.strip()]
        except RuleError as exc:
            raise ValueError(f"Fit on: {item!r}: {exc.rule}; amplitudes are in {_AMPLITUDE_UNITS}") from None
        if not amps:
            raise ValueError(f"Fit on: {item!r}: give amplitude=VALUE[+VALUE…] in {_AMPLITUDE_UNITS}")
        chosen &= np.any([np.isclose(shown, a, rtol=5e-4, atol=0) for a in amps], axis=0)
    if not chosen.any():
        raise ValueError(f"Fit on {spec!r} chooses none of the {len(data)} rows (amplitudes in {_AMPLITUDE_UNITS})")
    return chosen
