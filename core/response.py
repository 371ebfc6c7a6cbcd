"""Complex stiffness as the model and the measurements give it: its magnitude and its loss
factor, the one η = Im K / Re K of the project (docs/model.md), and the misfit of |K|."""

from __future__ import annotations

import numpy as np


def loss_factor(k) -> np.ndarray:
    """η = Im K / Re K of complex stiffness (docs/model.md), with its sign: negative where
    Im K < 0 or Re K < 0; ±inf where Re K = 0 exactly (no warning)."""
    k = np.asarray(k)
    with np.errstate(divide="ignore", invalid="ignore"):
        return k.imag / k.real


def magnitude_residual_pct(k_model, k_data) -> np.ndarray:
    """|K| of a model against data, in % of the data's: 100 (|K_model| / |K_data| − 1)."""
    return 100.0 * (np.abs(k_model) / np.abs(k_data) - 1.0)


class ComplexStiffness:
    """Magnitude and loss factor of a ``stiffness`` attribute holding complex K."""

    stiffness: np.ndarray

    @property
    def magnitude(self) -> np.ndarray:
        return np.abs(self.stiffness)

    @property
    def loss_factor(self) -> np.ndarray:
        return loss_factor(self.stiffness)
