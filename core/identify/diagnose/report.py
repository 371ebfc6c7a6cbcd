"""What the diagnosis returns: fitted models, the accepted steps, the report and its summary."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace

import numpy as np

from ...data import MeasuredStiffness
from ...design import Design
from ...effects import effect_of
from ...numbers import format_value
from ...response import loss_factor
from ..fit import FitResult
from .model import Model
from .statistics import BIC_THRESHOLD


@dataclass(frozen=True)
class Fitted:
    """A model fitted to the data, with its residual statistics."""

    model: Model
    fit: FitResult
    stiffness: np.ndarray  # the model's complex K at the data points
    residual: np.ndarray  # relative_residual(stiffness, data.stiffness)
    bic: float

    @property
    def design(self) -> Design:
        return self.fit.design

    @property
    def gap(self) -> float:
        return self.fit.gap

    @property
    def mean_square(self) -> float:
        return float(np.mean(np.abs(self.residual) ** 2))


@dataclass(frozen=True)
class Step:
    effect: str
    title: str
    where: str
    bic_drop: float
    explained_fraction: float | None
    parameters: dict[str, float]
    gap_before: float
    gap_after: float
    candidates: dict[str, float]  # every candidate's BIC drop at this step
    extra: dict = field(default_factory=dict)  # more evidence (the partner of a pair)
    standard_errors: dict[str, float] = field(default_factory=dict)  # of ``parameters``, linearised
    mode: str | None = None  # data of several modes: the rig a rig effect (a mass) was found on
    by_mode: dict = field(default_factory=dict)  # data of several modes: each mode's evidence
    undetermined: tuple[str, ...] = ()  # of ``parameters``, those the final model's profile leaves open

    @property
    def supported_by(self) -> list[str]:
        return [m for m, e in self.by_mode.items() if e["verdict"] == "supports"]

    def parameter_words(self, mode: str) -> str:
        """The fitted parameters in words, each with its unit (in ``mode``, or in the mode of the
        rig the effect was found on) and its standard error, or "(not determined)":
        ``mass = 0.509 kg ± 0.017 kg``; "no parameters" for an effect without any."""
        spec = {p.name: p for p in effect_of(self.effect).parameters}
        words = []
        for name, value in self.parameters.items():
            unit = spec[name.rpartition(".")[2]].unit_in(self.mode or mode)
            error = self.standard_errors.get(name, math.nan)
            words.append(f"{name} = {format_value(value, unit)}" + (
                f" ± {format_value(error, unit, 'error')}" if math.isfinite(error)
                else " (not determined)" if name in self.undetermined or math.isinf(error) else ""))
        return ", ".join(words) or "no parameters"

    def report(self) -> dict:
        evidence = {"bic_drop": self.bic_drop, "candidates_bic_drop": self.candidates, **self.extra}
        if self.explained_fraction is not None:
            evidence["explained_fraction"] = self.explained_fraction
        if self.by_mode:
            evidence["by_mode"] = self.by_mode
        errors = {k: (v if math.isfinite(v) else None) for k, v in self.standard_errors.items()}
        out = {"effect": self.effect, "title": self.title, "where": self.where, "evidence": evidence,
               "parameters": self.parameters, "standard_errors": errors, "gap_before": self.gap_before,
               "gap_after": self.gap_after}
        if self.mode:
            out["mode"] = self.mode
        if self.by_mode:
            out["supported_by"] = self.supported_by
        return out

    def support_words(self) -> str:
        """Which modes' data support the step, in words ('' for data of one mode)."""
        if self.mode:
            return f"on the {self.mode} rig only"
        if not self.by_mode:
            return ""
        groups = {v: [m for m, e in self.by_mode.items() if e["verdict"] == v] for v in ("supports", "neutral", "against")}
        if len(groups["supports"]) == len(self.by_mode):
            return "supported by every mode"
        parts = [f"supported by {' and '.join(groups['supports'])}" if groups["supports"] else "no mode alone supports it"]
        if groups["neutral"]:
            parts.append(f"{' and '.join(groups['neutral'])} neither for nor against")
        if groups["against"]:
            parts.append(f"{' and '.join(groups['against'])} against it")
        return "; ".join(parts)


@dataclass(frozen=True)
class Diagnosis:
    data: MeasuredStiffness
    baseline: Fitted
    steps: list[Step]
    final: Fitted
    noise_variance: float | None
    unexplained: bool
    where_baseline: str
    where_remaining: str
    held_out: dict = field(default_factory=dict)
    modes: dict = field(default_factory=dict)  # data of several modes: one material or one per mode

    @property
    def modes_disagree(self) -> bool:
        return bool(self.modes.get("disagree"))

    @property
    def added(self) -> list[str]:
        return [s.effect for s in self.steps]

    @property
    def noise_gap(self) -> float | None:
        """The gap pure noise of the estimated size gives."""
        return None if self.noise_variance is None else math.sqrt(self.noise_variance)

    def report(self) -> dict:
        """The report of docs/files.md's ``bushing diagnose``."""
        out = {
            "baseline": list(self.baseline.model.branches),
            "added": self.added,
            "steps": [s.report() for s in self.steps],
            "gap_baseline": self.baseline.gap,
            "gap_final": self.final.gap,
            "unexplained": self.unexplained,
            "where_baseline": self.where_baseline,
            "where_remaining": self.where_remaining,
            "noise_gap": self.noise_gap,
            "points": len(self.data),
            "bic_threshold": BIC_THRESHOLD,
            "design": self.final.design.to_dict(),
        }
        if self.baseline.design.effects:
            out["baseline_effects"] = [eid for eid, _ in self.baseline.design.effects]
        if self.held_out:
            out["held_out"] = self.held_out
        if self.modes:
            out["modes"] = self.modes
        fit = self.final.fit.report()
        if "intervals" in fit:
            out["uncertainty"] = {k: fit[k] for k in ("confidence", "intervals", "undetermined")}
            out["uncertainty"]["warnings"] = fit.get("warnings", [])
        return out

    def to_json(self) -> str:
        """The report as JSON text (strict: no NaN)."""
        return json.dumps(self.report(), indent=2, allow_nan=False) + "\n"

    def of_mode(self, mode: str) -> Diagnosis:
        """The diagnosis seen on one mode's rows (for plots of one direction): its data and both
        models' stiffness there, the models in that mode. The evidence stays the joint one."""
        if self.data.mode is None:
            return self
        rows = self.data.mode == mode

        def part(f: Fitted) -> Fitted:
            fit = replace(f.fit, design=f.fit.design.in_mode(mode))
            return replace(f, fit=fit, stiffness=f.stiffness[rows], residual=f.residual[rows])

        return replace(self, data=self.data.of_mode(mode), baseline=part(self.baseline), final=part(self.final))

    def predictions(self) -> dict[str, np.ndarray]:
        """Per data row: the baseline's and the final model's |K| and loss factor, the six
        columns of docs/files.md in their order (and the row's mode last, for data with a `mode`
        column, so that a reader by position finds the six where they always are)."""
        kb, kf = self.baseline.stiffness, self.final.stiffness
        return {
            "frequency_hz": self.data.frequency_hz,
            "amplitude": self.data.amplitude,
            "baseline_magnitude": np.abs(kb),
            "baseline_loss_factor": loss_factor(kb),
            "final_magnitude": np.abs(kf),
            "final_loss_factor": loss_factor(kf),
            **({} if self.data.mode is None else {"mode": self.data.mode}),
        }


def summary(diagnosis: Diagnosis) -> str:
    """The diagnosis in plain words, a few lines (the command line's summary)."""
    lines = [f"baseline ({', '.join(diagnosis.baseline.model.branches)}): gap {diagnosis.baseline.gap:.4g}"]
    if diagnosis.noise_gap is not None:
        lines[0] += f" (noise alone gives about {diagnosis.noise_gap:.4g})"
    lines.append(f"  where it disagrees: {diagnosis.where_baseline}")
    for n, s in enumerate(diagnosis.steps, 1):
        params = s.parameter_words(diagnosis.baseline.model.design.mode)
        support = s.support_words()
        lines.append(f"step {n}: add {s.effect} ({s.title}){' ' + support if s.mode else ''}: {params}; "
                     f"BIC drop {s.bic_drop:.1f}; gap {s.gap_before:.4g} -> {s.gap_after:.4g}"
                     + (f"; {support}" if support and not s.mode else ""))
    if not diagnosis.steps:
        lines.append("no effect of the library is needed: nothing added")
    modes = diagnosis.modes
    if modes:
        joint = ", ".join(f"{m} {g:.3g}" for m, g in modes["gap_joint_by_mode"].items())
        alone = ", ".join(f"{m} {g:.3g}" for m, g in modes["gap_alone_by_mode"].items())
        if modes["disagree"]:
            lines.append(f"the modes disagree: one material does not describe them together (gap by mode "
                         f"{joint}; each mode fitted alone {alone}; BIC drop {modes['bic_drop']:.1f} for a "
                         f"material per mode): check that every part is of one compound and every rig's "
                         f"geometry and calibration")
        else:
            lines.append(f"the modes agree: one material describes them all (gap by mode {joint})")
    if diagnosis.unexplained:
        lines.append(f"unexplained: a misfit above the noise remains, no effect of the library explains it: "
                     f"{diagnosis.where_remaining}")
    for warning in diagnosis.final.fit.warnings:
        lines.append(f"warning: {warning}")
    held = diagnosis.held_out
    if held:
        lines.append(f"held out ({held['left_out']}): gap {held['gap_baseline']:.4g} baseline, "
                     f"{held['gap_final']:.4g} final")
    return "\n".join(lines) + "\n"
