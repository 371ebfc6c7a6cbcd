"""Synthetic measurements made from the model with stated noise: for examples, demos and tests.

Noise model: each complex stiffness is multiplied by (1 + n), n complex Gaussian with standard
deviation ``noise`` in its real and imaginary parts; a loop's force gets Gaussian noise of
``noise`` times its peak. Seeded, so the same call gives the same data.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bushing import stiffness_points
from .data import MeasuredLoop, MeasuredStiffness
from .design import PAPER_B, TABLE_1, Design
from .loops import steady_loop_force


def synthetic_stiffness(design: Design, frequency_hz, amplitude, *, noise: float = 0.005,
                        seed: int = 0) -> MeasuredStiffness:
    """Stiffness on the grid amplitude × frequency, with relative complex noise."""
    rng = np.random.default_rng(seed)
    ff, xx = np.meshgrid(np.asarray(frequency_hz, float), np.asarray(amplitude, float))
    k = stiffness_points(design, ff.ravel(), xx.ravel())
    k = k * (1 + noise * (rng.standard_normal(k.size) + 1j * rng.standard_normal(k.size)))
    return MeasuredStiffness(ff.ravel(), xx.ravel(), k)


def synthetic_loop(design: Design, frequency_hz: float, amplitude: float, *, periods: int = 2,
                   per_period: int = 200, phase: float = 0.0, noise: float = 0.005,
                   seed: int = 0) -> MeasuredLoop:
    """A steady harmonic test x = x̂ sin(ωt + phase), with noise on the force."""
    rng = np.random.default_rng(seed)
    t = np.arange(periods * per_period) / (per_period * frequency_hz)
    theta = 2 * np.pi * frequency_hz * t + phase
    force = sum(steady_loop_force(design, frequency_hz, amplitude, theta))
    force = force + noise * np.max(np.abs(force)) * rng.standard_normal(t.size)
    return MeasuredLoop(t, amplitude * np.sin(theta), force)


# The example sets of examples/ (and of the explorer's demo button), with their stated seeds.
PAPER_B_AMPLITUDES = (0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3)


def paper_b_example(design: Design):
    """The Paper B example: 150 stiffness points and the 0.1 Hz, 1 mm loop."""
    data = synthetic_stiffness(design, np.linspace(1, 100, 30), PAPER_B_AMPLITUDES, seed=12345)
    loop = synthetic_loop(design, 0.1, 1e-3, seed=12346)
    return data, loop


@dataclass(frozen=True)
class Mystery:
    """Data with a hidden effect for the discrepancy workflow's demo: the truth is ``hidden``
    (effect id → parameters; {} for none) and, for a baseline without a branch, ``baseline``."""

    design: Design  # the bushing as the user gets it: geometry and starting material, no effects
    hidden: dict
    baseline: tuple[str, ...]
    frequency_hz: tuple[float, ...]
    amplitude: tuple[float, ...]
    seed: int

    @property
    def missing(self) -> list[str]:
        """What the baseline lacks: the branches it leaves out, then the hidden effects."""
        return [b for b in ("elastic", "fractional", "friction") if b not in self.baseline] + list(self.hidden)

    def data(self) -> MeasuredStiffness:
        return synthetic_stiffness(self.design.replace(effects=self.hidden), self.frequency_hz, self.amplitude,
                                   noise=0.005, seed=self.seed)


_SWEEP = tuple(np.linspace(1.0, 100.0, 30))
_ALL = ("elastic", "fractional", "friction")
MYSTERIES = (
    Mystery(PAPER_B, {"inertia": {"mass": 0.5}}, _ALL, _SWEEP, PAPER_B_AMPLITUDES, 101),
    Mystery(PAPER_B, {}, ("elastic", "fractional"), _SWEEP, PAPER_B_AMPLITUDES, 102),
    Mystery(PAPER_B, {"rate_amplitude_coupling": {"rate_exponent": 0.05}}, _ALL, _SWEEP, PAPER_B_AMPLITUDES, 103),
    Mystery(PAPER_B, {"wave_effects": {"density": 1150.0}}, _ALL, tuple(np.geomspace(10, 1000, 30)),
            PAPER_B_AMPLITUDES, 104),
    Mystery(PAPER_B, {"viscous": {"viscosity": 1000.0}, "strain_stiffening": {"stiffening": 10.0}}, _ALL,
            _SWEEP, tuple(np.geomspace(0.05e-3, 2e-3, 5)), 105),
    Mystery(TABLE_1, {"viscous": {"viscosity": 1000.0}}, _ALL, tuple(np.linspace(10, 100, 30)),
            tuple(np.geomspace(1e-4, 1e-1, 5)), 106),
    Mystery(PAPER_B, {}, _ALL, _SWEEP, PAPER_B_AMPLITUDES, 107),
)
