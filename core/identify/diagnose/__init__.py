"""The discrepancy workflow: where model and measurement disagree, which effect of the
library is missing, and the gap shrinking as it is added.

1. Fit the baseline (the design's geometry is known; the parameters of its branches and of any
   effects it already carries are fitted).
2. Describe the misfit over the (frequency, amplitude) plane in plain words (:func:`describe`).
3. Fit every candidate extension (an effect of :data:`core.effects.EFFECTS` not yet in the model,
   or a branch the baseline lacks) and rank them by the Bayesian information criterion
   BIC = N ln(RSS/N) + k ln N over the N real residuals (real and imaginary parts of the relative
   complex misfit, the gap's own terms). The best candidate is added when
   * its BIC drop exceeds :data:`BIC_THRESHOLD` (10: "very strong" evidence on Kass and
     Raftery's scale; a parameter fitted to pure noise gains about 1 against a ln N ≈ 6 penalty),
   * and it explains the misfit: it leaves at most a fifth of the misfit above the noise
     (:data:`EXPLAINED_FRACTION`), or no more than the noise estimate's own spread
     (:data:`NOISE_TOLERANCE`). An effect that only leans against a misfit of another shape
     (one outside the library) lowers the BIC too, but leaves most of it: it is not named.
   If no single candidate explains the misfit, pairs of candidates are fitted together (two
   effects hidden at once interact through the refitted baseline, so neither alone need explain
   much); a pair is added when it explains the misfit and each member is needed.
4. Repeat until nothing passes. If the misfit left is still above the noise
   (:data:`NOISE_RATIO`), it is reported as unexplained, with where it is.

The noise is estimated from the data, model-free in the sense that only the roughness of the
residuals counts: at each point inside a run of three (same amplitude along ln f, or same
frequency along ln amplitude) the residual minus the linear interpolation of its neighbours has,
for white noise of complex variance s², variance s² (1 + w₀² + w₂²). A smooth model misfit drops
out to first order, and the smallest estimate over the models fitted is kept.

A branch the baseline lacks is held at a value with no effect on any stiffness (:data:`OFF`).

Modules by responsibility: :mod:`.model` (the models fitted), :mod:`.statistics` (BIC, the
noise, "explains"), :mod:`.words` (where, in plain words), :mod:`.report` (the result types, the
report and its summary), :mod:`.search` (the workflow). ``docs/diagnosis.md`` says it for users.
"""

from .model import BRANCH_PARAMETERS, BRANCHES, OFF, Model, baseline_model, candidates
from .report import Diagnosis, Fitted, Step, summary
from .search import diagnose
from .statistics import (
    BIC_THRESHOLD,
    EXPLAINED_FRACTION,
    NOISE_RATIO,
    NOISE_TOLERANCE,
    PRECISION,
    bic,
    noise_variance,
)
from .words import describe

__all__ = [
    "BIC_THRESHOLD", "BRANCHES", "BRANCH_PARAMETERS", "EXPLAINED_FRACTION", "NOISE_RATIO", "NOISE_TOLERANCE", "OFF",
    "PRECISION", "Diagnosis", "Fitted", "Model", "Step", "baseline_model", "bic", "candidates", "describe",
    "diagnose", "noise_variance", "summary",
]
