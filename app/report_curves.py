"""A diagnosis (:class:`core.identify.diagnose.Diagnosis`) as the curves its report draws: the
gap after each stage, the misfits at every point, data and models by amplitude (display units).
"""

from __future__ import annotations

import numpy as np

from core.response import loss_factor, magnitude_residual_pct

from . import units
from .curves import amplitude_groups


def gap_stages(r) -> dict:
    """The gap after each stage of a diagnosis: the baseline, then each added effect; and the
    gap the noise alone gives (None if it could not be estimated)."""
    labels = ["baseline"] + [f"+ {s.effect}" for s in r.steps]
    gaps = [r.baseline.gap] + [s.gap_after for s in r.steps]
    return {"stage": labels, "gap": np.array(gaps), "noise": r.noise_gap}


def misfit_points(r, which: str) -> dict:
    """Model − data of a diagnosis' ``which`` model ("baseline" or "final") at every measured
    point: |K| in % and the loss factor, the amplitude in display units."""
    k = (r.baseline if which == "baseline" else r.final).stiffness
    d = r.data
    return {
        "frequency_hz": d.frequency_hz,
        "amplitude": units.display_amplitude(d.amplitude, r.final.design.mode),
        "magnitude_pct": magnitude_residual_pct(k, d.stiffness),
        "loss_factor": loss_factor(k) - d.loss_factor,
    }


def curve_groups(r, most: int = 5) -> list[dict]:
    """Data and both models of a diagnosis against frequency, one group per measured amplitude
    (the ``most`` most populated), in display units (:func:`amplitude_groups`)."""
    return amplitude_groups(r.data, r.final.design.mode,
                            {"baseline": r.baseline.stiffness, "final": r.final.stiffness}, most)
