"""The What-ifs tab's design-from-targets form: its values (targets at the explorer's operating
point and limits, in display units), the targets file it makes (docs/files.md), the search and
its last result, and the adoption of a found design into the session's state. No Panel: the
tab's view (:mod:`app.tabs.what_ifs`) shows it."""

from __future__ import annotations

import json
import logging

import param

from core.io.targets import problem_from_dict
from core.parameters import BY_NAME, GEOMETRY, TRANSLATIONS
from core.whatif.target import Found, TargetError, solve

from . import units
from .state import ExplorerState
from .work import PageClosed, in_thread

log = logging.getLogger("bushing.app")

A, B, L, MU = (BY_NAME[n] for n in (*GEOMETRY, "shear_modulus"))
# the what-if's ratio target: radial over axial |K| (a pair chosen by meaning, not a list of modes)
STIFFNESS_RATIO = ("radial", "axial")


class TargetsForm(param.Parameterized):
    """The design form of one session: its fields (blank: no target, no limit), the search's
    state (``running``), its last result (``found``, or ``message`` saying why there is none)."""

    state = param.ClassSelector(class_=ExplorerState, doc="The session whose operating point the targets are at.")
    target_magnitude = param.Number(default=None, allow_None=True, bounds=(0, None), label="|K| target")
    target_tolerance_pct = param.Number(default=1.0, bounds=(0.001, 50.0), label="Met within ± %")
    loss_factor_min = param.Number(default=None, allow_None=True, bounds=(0, 10), label="Loss factor at least")
    ratio_min = param.Number(default=None, allow_None=True, bounds=(0, None), label="Radial / axial at least")
    b_max_mm = param.Number(default=None, allow_None=True, bounds=(0, None),
                            label=f"{B.symbol} at most ({B.unit.display})")
    length_max_mm = param.Number(default=None, allow_None=True, bounds=(0, None),
                                 label=f"{L.symbol} at most ({L.unit.display})")
    thickness_min_mm = param.Number(default=2.0, allow_None=True, bounds=(0, None),
                                    label=f"Rubber {B.symbol} − {A.symbol} at least ({B.unit.display})")
    hold_inner = param.Boolean(default=True, label="Keep the inner radius (the shaft)")
    mu_min_mpa = param.Number(default=None, allow_None=True, bounds=(0, None),
                              label=f"{MU.symbol} from ({MU.unit.display})")
    mu_max_mpa = param.Number(default=None, allow_None=True, bounds=(0, None),
                              label=f"{MU.symbol} to ({MU.unit.display})")
    running = param.Boolean(default=False, doc="A search is under way.")
    progress_message = param.String(default="", doc="Where the running search is (its start of how many).")
    found = param.Parameter(default=None, doc="The last search's core.whatif.target.Found.")
    message = param.String(default="", doc="Why the last search found nothing (empty after a search that ran).")

    def __init__(self, state: ExplorerState, **params):
        super().__init__(state=state, **params)

    def spec(self) -> dict:
        """The targets file (docs/files.md) of the form, in SI units: targets at the explorer's
        operating point (mode, frequency in Hz, amplitude in m or rad)."""
        s = self.state
        design = s.design
        mode, f = design.mode, s.frequency_hz
        x = float(units.to_si_amplitude(s.amplitude, mode))
        targets = []
        if self.target_magnitude:
            targets.append({"mode": mode, "frequency_hz": f, "amplitude": x,
                            "magnitude": float(units.to_si_stiffness(self.target_magnitude, mode)),
                            "tolerance": self.target_tolerance_pct / 100.0})
        if self.loss_factor_min:
            targets.append({"mode": mode, "frequency_hz": f, "amplitude": x, "loss_factor": {"min": self.loss_factor_min}})
        if self.ratio_min:
            drive = x if mode in TRANSLATIONS else 1e-4  # a translation's drive: the operating one, or 0.1 mm
            targets.append({"ratio": list(STIFFNESS_RATIO), "frequency_hz": f, "amplitude": drive,
                            "magnitude": {"min": self.ratio_min}})
        limits = {}
        if self.b_max_mm:
            limits["outer_radius"] = {"max": float(B.unit.to_si(self.b_max_mm))}
        if self.length_max_mm:
            limits["length"] = {"max": float(L.unit.to_si(self.length_max_mm))}
        if self.thickness_min_mm:
            limits["thickness"] = {"min": float(B.unit.to_si(self.thickness_min_mm))}
        out = {"design": design.to_dict(), "targets": targets, "limits": limits, "solutions": 5}
        if self.hold_inner:
            out["fixed"] = ["inner_radius"]
        if self.mu_min_mpa or self.mu_max_mpa:
            out["free_material"] = {MU.name: {k: float(MU.unit.to_si(v)) for k, v in (("min", self.mu_min_mpa),
                                                                                  ("max", self.mu_max_mpa)) if v}}
        return out

    def targets_text(self) -> str:
        """The targets file's text (JSON, two-space indent, a final newline): the download."""
        return json.dumps(self.spec(), indent=2) + "\n"

    def compute(self, progress=None) -> Found:
        """The search (pure: safe in a worker thread); ``progress(fraction, message)`` told of
        each start (:func:`core.whatif.target.solve`)."""
        spec = self.spec()
        if not spec["targets"]:
            raise TargetError("give at least one target: |K|, a least loss factor or a radial/axial ratio")
        return solve(problem_from_dict(spec), progress=progress)

    def run(self):
        """The search, on this thread (tests and scripts): its result in ``found`` or ``message``."""
        try:
            self.param.update(found=self.compute(), message="")
        except (TargetError, ValueError) as exc:
            self.param.update(found=None, message=str(exc))

    async def search(self, doc=None):
        """The search in a worker thread (the page's button), its progress in ``progress_message``
        as it goes (:func:`app.work.in_thread`; ``doc`` the page's document): one at a time;
        never raises (a failure is its ``message``). A page closed meanwhile: nothing more is
        set (its views would write to a closed page)."""
        if self.running:
            return
        self.param.update(running=True, message="", progress_message="")
        try:
            found = await in_thread(self.compute, self._show_progress, doc)
        except PageClosed:
            return
        except (TargetError, ValueError) as exc:
            self.param.update(found=None, message=str(exc), running=False)
        except Exception as exc:  # noqa: BLE001 - never a traceback in the page
            log.warning("design search failed: %s: %s", type(exc).__name__, exc)
            self.param.update(found=None, message=f"The search failed ({type(exc).__name__}): {exc}",
                              running=False)
        else:
            self.param.update(found=found, message="", running=False)

    def _show_progress(self, _fraction: float, message: str):
        self.progress_message = message

    def rows(self) -> list:
        """The designs to show and take: the solutions, or the closest design when none meets
        every target (empty without a search, or when there is not even a closest one)."""
        found = self.found
        if found is None:
            return []
        return found.solutions or ([found.closest] if found.closest is not None else [])

    def use_solution(self, index: int = 0):
        """Take the found design ``index`` (of :meth:`rows`) into the explorer (the operating point kept)."""
        if self.found is None:
            return
        rows = self.found.solutions or [self.found.closest]
        design = rows[int(index or 0)].design
        self.state.adopt(design.replace(name=f"{self.state.design.name or 'Design'} (from targets)"))
