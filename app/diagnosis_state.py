"""State of the "Find the missing effect" tab: the data, the baseline, the diagnosis and its
plots' data. No Panel import: the view (:mod:`app.tabs.find_the_missing_effect`) is thin."""

from __future__ import annotations

import numpy as np
import param

from core.data import MeasuredStiffness
from core.effects import EFFECTS, effect_title
from core.identify.diagnose import BRANCHES, Diagnosis, diagnose
from core.identify.fit import fitted_name
from core.io.table import csv_text
from core.numbers import format_value
from core.synthetic import MYSTERIES, Mystery

from . import report_curves
from .state import ExplorerState, read_stiffness
from .work import Task


class DiagnosisState(param.Parameterized):
    """One session's discrepancy workflow, on the explorer's design (its geometry is known)."""

    data = param.ClassSelector(class_=MeasuredStiffness, default=None, allow_None=True,
                               doc="The measured stiffness to diagnose (SI).")
    source = param.String(default="", doc="Where the data came from.")
    baseline = param.ListSelector(default=list(BRANCHES), objects=list(BRANCHES), label="Baseline branches",
                                  doc="The branches the starting model has: elastic µ, fractional m(iω)^α, "
                                  "friction (the Fletcher–Gent effect).")
    result = param.ClassSelector(class_=Diagnosis, default=None, allow_None=True)
    running = param.Boolean(default=False)
    progress = param.Number(default=0.0, bounds=(0.0, 1.0))
    progress_message = param.String(default="")
    message = param.String(default="", doc="What went wrong, if anything.")
    note = param.String(default="", doc="What the data's units warn of (app.state.read_stiffness), if anything: "
                        "kept with the data.")
    mystery = param.ClassSelector(class_=Mystery, default=None, allow_None=True,
                                  doc="The demo's hidden truth (shown only after the diagnosis).")
    revealed = param.Boolean(default=False)

    def __init__(self, explorer: ExplorerState, **params):
        super().__init__(**params)
        self.explorer = explorer
        self._next_mystery = int(np.random.default_rng().integers(len(MYSTERIES)))

    # ---- data ----------------------------------------------------------------------------------

    def _set_data(self, data: MeasuredStiffness, source: str, mystery: Mystery | None = None, note: str = ""):
        self.param.update(data=data, source=source, result=None, message="", note=note, mystery=mystery,
                          revealed=False)

    def load_csv(self, content: bytes | str, filename: str = "stiffness file") -> bool:
        """A stiffness file, read and judged for the explorer's bushing as the measured-data tab
        does (:func:`app.state.read_stiffness`): refused with the same message, or loaded with
        the same warning."""
        data, message = read_stiffness(content, filename, self.explorer.design)
        if data is None:
            self.message = message
            return False
        self._set_data(data, filename, note=message)
        return True

    def use_measured(self) -> bool:
        """The stiffness loaded in the "Measured data and fit" tab."""
        if self.explorer.measured is None:
            self.message = "No measured stiffness is loaded in the “Measured data and fit” tab."
            return False
        self._set_data(self.explorer.measured, "the data of the “Measured data and fit” tab",
                       note=self.explorer.measured_warning)
        return True

    def load_mystery(self):
        """The next demo data set: its bushing goes into the explorer, its truth stays hidden."""
        mystery = MYSTERIES[self._next_mystery % len(MYSTERIES)]
        self._next_mystery += 1
        self.explorer.load_design(mystery.design)
        self.baseline = list(mystery.baseline)
        self._set_data(mystery.data(), f"mystery data set {MYSTERIES.index(mystery) + 1} of {len(MYSTERIES)} "
                       f"(synthetic, {mystery.design.name}, 0.5 % noise)", mystery)

    # ---- the diagnosis -------------------------------------------------------------------------

    def task(self) -> Task:
        """The diagnosis of the loaded data as a :class:`app.work.Task` (it can run in a worker
        process: the design, the data and the baseline are plain data); ValueError, saying
        what to do, if it cannot run."""
        if self.data is None:
            raise ValueError("load data first: a stiffness CSV, the measured data, or a mystery data set")
        if not self.baseline:
            raise ValueError("choose at least one baseline branch")
        design = self.explorer.design.replace(effects={})
        if self.data.of_mode(design.mode) is None:
            raise ValueError(f"the data hold no {design.mode} rows (they hold {', '.join(sorted(set(self.data.mode)))}): "
                             "switch the explorer's mode")
        data = self.data  # every mode at once: one material, each mode through its shape factor
        if data.mode is not None and len(set(data.mode)) == 1:
            data = data.of_mode(design.mode)
        return Task(diagnose, (design, data), {"baseline": [b for b in BRANCHES if b in self.baseline]})

    def compute(self, progress=None) -> Diagnosis:
        """Run the workflow here (pure: safe in a worker thread; the view stores the result)."""
        return self.task()(progress)

    def shown(self) -> Diagnosis | None:
        """The result as the plots show it: the rows of the mode it was run in."""
        return None if self.result is None else self.result.of_mode(self.result.final.design.mode)

    def use_final(self):
        """Take the final model into the explorer, keeping the operating point."""
        if self.result is None:
            return
        design = self.result.final.design
        # one name for a design whose values come from measured data, fitted here or in the fit tab
        self.explorer.adopt(design.replace(name=fitted_name(self.explorer.design.name or "Design")))

    def truth(self) -> str:
        """The demo's truth in words, and whether the diagnosis found it."""
        m = self.mystery
        if m is None:
            return ""
        missing = m.missing
        if not missing:
            said = "Nothing was hidden: the data came from the thesis model itself, with 0.5 % noise."
        else:
            parts = []
            for eid in missing:
                values = m.hidden.get(eid) or {p.name: getattr(m.design.material, p.name)
                                               for p in EFFECTS[eid].parameters}
                units = {p.name: p.unit_in(m.design.mode) for p in EFFECTS[eid].parameters}
                shown = ", ".join(f"{k} = {format_value(v, units.get(k, ''))}" for k, v in values.items())
                parts.append(f"**{EFFECTS[eid].title}** (`{eid}`{': ' + shown if shown else ''})")
            said = "Hidden in the data: " + " and ".join(parts) + "."
        if self.result is not None:
            found = sorted(self.result.added) == sorted(missing)
            said += " The diagnosis " + ("found exactly that." if found else
                                         f"named {', '.join(map(effect_title, self.result.added)) or 'nothing'}.")
        return said

    # ---- data for the plots --------------------------------------------------------------------

    def gap_stages(self) -> dict:
        """The gap after each stage: baseline, then each added effect."""
        return report_curves.gap_stages(self.result)

    def misfit(self, which: str) -> dict:
        """Model − data over the (frequency, amplitude) plane: |K| in %, loss factor."""
        return report_curves.misfit_points(self.shown(), which)

    def curves(self) -> dict:
        """Data and both models against frequency, one group per measured amplitude (the most
        populated five), display units."""
        return {"groups": report_curves.curve_groups(self.shown())}

    # ---- downloads -----------------------------------------------------------------------------

    def report_json(self) -> str:
        return self.result.to_json() if self.result is not None else ""

    def predictions_csv(self) -> str:
        return csv_text(self.result.predictions()) if self.result is not None else ""
