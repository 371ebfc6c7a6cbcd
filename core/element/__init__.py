"""The bushing as a time-domain element for multibody and finite-element simulations
(docs/element.md): six uncoupled channels at the bushing's centre, the fractional derivative as
a sum of exponentials over a stated band, friction with its reversal memory, one step at a time
with O(1) work and memory per step.

* :func:`coefficients` — a design's coefficients (what the FMU carries as parameters);
* :class:`Element` — the stateful element: ``trial``, ``commit``, ``state``, ``restore``;
* :func:`fit_power` — the sum of exponentials for (iω)^α over a band.
"""

from .coefficients import (
    CHANNEL_MODES,
    CHANNELS,
    OUTPUTS,
    ChannelCoefficients,
    Coefficients,
    Parameter,
    coefficients,
)
from .element import Element, ElementWarning
from .prony import DEFAULT_BAND, PronyFit, check_band, fit_power

__all__ = [
    "CHANNELS",
    "CHANNEL_MODES",
    "DEFAULT_BAND",
    "OUTPUTS",
    "ChannelCoefficients",
    "Coefficients",
    "Element",
    "ElementWarning",
    "Parameter",
    "PronyFit",
    "check_band",
    "coefficients",
    "fit_power",
]
