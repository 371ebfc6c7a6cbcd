"""The FMU's C kernel alone (fmu/c/bushing_kernel.c, through ctypes) against a NumPy/SciPy
reference written here from docs/element.md: the held-input step, the exact exponential update,
the series layers with a bulk spring, Berg friction with its reversal memory; and its cost per
step, which does not grow with the history."""

from __future__ import annotations

import dataclasses
import shutil

import numpy as np
import pytest
from scipy.optimize import brentq

from core import PAPER_B
from core.element import CHANNELS, coefficients
from tests.fmu_helpers import Kernel, compile_kernel

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler (README's test command)")


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    return compile_kernel(tmp_path_factory.mktemp("kernel"))


@pytest.fixture(scope="module")
def nested_library(tmp_path_factory):
    """The kernel with its fallback series solve alone (the nested, bracketed Newton)."""
    return compile_kernel(tmp_path_factory.mktemp("nested"), defines=("BK_SERIES_NESTED_ONLY",), name="nested")


EFFECTS = {"strain_stiffening": {"stiffening": 40.0}, "viscous": {"viscosity": 30.0}}
# every term at work between them, with strain stiffening and viscosity in both: 2 slices axially
# and in torsion (long shape factors); a bulk spring in series in five channels (finite shape)
RICH = {"2 slices": (PAPER_B.replace(effects=EFFECTS), 2),
        "a bulk spring": (PAPER_B.replace(shape="finite", bulk_modulus=2.0e8, effects=EFFECTS), 1),
        "layers and a spring": (PAPER_B.replace(effects=EFFECTS), 2)}


def with_channel(co, name: str, **changes):
    """``co`` with channel ``name``'s fields changed: combinations no design makes today (layers
    and a bulk spring in one channel), which the kernel solves all the same."""
    return dataclasses.replace(co, channels={**co.channels, name: dataclasses.replace(co.channels[name], **changes)})


def rich_coefficients(name="2 slices"):
    design, slices = RICH[name]
    co = coefficients(design, slices)
    if name == "layers and a spring":  # 2 layers and a spring axially: the old hand-made case
        return with_channel(co, "dz", compliance=0.3 / (PAPER_B.shape_factor * PAPER_B.material.shear_modulus))
    layered = [ch for ch, c in co.channels.items() if len(c.S) > 1]
    springs = [ch for ch, c in co.channels.items() if c.compliance > 0]
    assert co.beta > 0 and co.viscosity > 0 and co.rate
    assert layered == ["dz", "rz"] if slices > 1 else len(springs) == 5
    return co


class Layer:
    """One layer of the reference: its committed strain, friction memory and exponentials."""

    def __init__(self, count):
        self.eps, self.eps_s, self.sig_s, self.dir, self.sig_f = 0.0, 0.0, 0.0, 0.0, 0.0
        self.z = np.zeros(count)


class Reference:
    """docs/element.md stepped in plain Python: each layer's strain by Brent's method, the
    channel's load by Brent's method on the sum of the layers' displacements."""

    def __init__(self, co):
        self.co = co
        self.rate, self.weight = np.array(co.rate), np.array(co.weight)
        self.layers = {ch: [Layer(self.rate.size) for _ in co.channels[ch].S] for ch in CHANNELS}

    def friction(self, layer, e):
        co = self.co
        smax, half = co.sigma_f_max, co.eps_half
        if e == layer.eps:
            return layer.sig_f, layer.dir, layer.eps_s, layer.sig_s
        s = 1.0 if e > layer.eps else -1.0
        # on along the direction of motion from the last reversal, or a reversal here
        er, sr = (layer.eps_s, layer.sig_s) if s == layer.dir else (layer.eps, layer.sig_f)
        u = e - er
        return sr + u * (smax - s * sr) / (half * (1 - s * sr / smax) + s * u), s, er, sr

    def stress(self, layer, e, h):
        co = self.co
        z = np.exp(-self.rate * h) * (layer.z + e - layer.eps)
        return (2 * co.mu * e * (1 + co.beta * e * e) + co.m * np.dot(self.weight, z)
                + co.viscosity * (e - layer.eps) / h + self.friction(layer, e)[0])

    def strain(self, layer, target, h):
        def f(e):
            return self.stress(layer, e, h) - target

        width = 1e-12 + abs(layer.eps)
        while f(layer.eps - width) > 0 or f(layer.eps + width) < 0:
            width *= 4
        return brentq(f, layer.eps - width, layer.eps + width, xtol=1e-300, rtol=1e-15)

    def step(self, x, h):
        out = []
        for ch, xc in zip(CHANNELS, x, strict=True):
            layers, s, c = self.layers[ch], self.co.channels[ch].S, self.co.channels[ch].c
            cb = self.co.channels[ch].compliance
            if len(layers) == 1 and cb == 0:
                strains = [c[0] * xc]
                load = self.stress(layers[0], strains[0], h) * s[0] / (2 * c[0])
            else:
                def g(F, layers=layers, s=s, c=c, cb=cb, xc=xc):
                    return sum(self.strain(ly, 2 * ck / sk * F, h) / ck
                               for ly, sk, ck in zip(layers, s, c, strict=True)) + cb * F - xc
                span = 1.0
                while g(-span) > 0 or g(span) < 0:
                    span *= 4
                load = brentq(g, -span, span, xtol=1e-300, rtol=1e-15)
                strains = [self.strain(ly, 2 * ck / sk * load, h) for ly, sk, ck in zip(layers, s, c, strict=True)]
            for ly, e in zip(layers, strains, strict=True):
                sig_f, s_new, er, sr = self.friction(ly, e)
                ly.z = np.exp(-self.rate * h) * (ly.z + e - ly.eps)
                if e != ly.eps:
                    ly.dir, ly.eps_s, ly.sig_s = s_new, er, sr
                ly.eps, ly.sig_f = e, sig_f
            out.append(load)
        return np.array(out)


def history(n, seed=3):
    """A band-limited random drive with reversals of every size, and variable step sizes."""
    rng = np.random.default_rng(seed)
    scale = np.array([3e-4, 3e-4, 1e-4, 5e-3, 5e-3, 5e-3])
    t = np.cumsum(rng.uniform(2e-4, 2e-3, n))
    x = np.zeros((n, 6))
    for k in range(4):
        f = rng.uniform(1, 40, 6)
        x += scale * np.sin(2 * np.pi * f * t[:, None] + rng.uniform(0, 6, 6)) / (k + 1)
    return np.diff(np.concatenate(([0.0], t))), x


@pytest.mark.parametrize("solve", ["one-level Newton", "nested fallback"])
@pytest.mark.parametrize("name", RICH)
def test_the_kernel_matches_the_reference_of_the_spec_along_one_history(library, nested_library, name, solve):
    co = rich_coefficients(name)
    kernel, reference = Kernel(library if solve == "one-level Newton" else nested_library, co), Reference(co)
    steps, drive = history(120)
    worst = 0.0
    for h, x in zip(steps, drive, strict=True):
        fk, fr = kernel.step(x, h), reference.step(x, h)
        worst = max(worst, float(np.max(np.abs(fk - fr) / np.maximum(np.abs(fr), 1e-3 * np.abs(fr).max()))))
    assert worst < 1e-9
    # the friction memory was exercised: some layer has reversed
    assert any(ly.dir != 0 and ly.eps_s != 0 for lys in reference.layers.values() for ly in lys)


def hard_history(n, seed=5):
    """Steps that trouble a Newton: held inputs (the layers move by relaxation alone), jumps many
    times the last step (no extrapolation), dithers of 1e-6 of the amplitude about a reversal
    (friction's kink), returns to rest, and a run of 3 slices' worth of smooth steps between."""
    steps, drive = history(n, seed)
    rng = np.random.default_rng(seed)
    for i in range(8, n - 6, 12):
        kind = rng.integers(4)
        if kind == 0:
            drive[i:i + 4] = drive[i - 1]
        elif kind == 1:
            drive[i] = -3.0 * drive[i - 1]
        elif kind == 2:
            drive[i:i + 5] = drive[i - 1] * (1.0 + 1e-6 * np.array([1, -1, 1, -1, 1]))[:, None]
        else:
            drive[i:i + 2] = 0.0
    return steps, drive


def test_the_one_level_newton_and_the_nested_solve_agree_on_hard_steps(library, nested_library):
    """The fast series solve (one Newton over the layers' strains and the load, from an
    extrapolated guess) and the fallback (Newton on the load, each layer bracketed) reach the
    same solution, step after step, where the guess is poor or the kink is in the way."""
    co = rich_coefficients("layers and a spring")
    co = with_channel(co, "dz", S=co.channels["dz"].S * 2, c=co.channels["dz"].c * 2)  # 4 layers and a spring
    fast, nested = Kernel(library, co), Kernel(nested_library, co)
    steps, drive = hard_history(240)
    worst = 0.0
    for h, x in zip(steps, drive, strict=True):
        ff, fn = fast.step(x, h), nested.step(x, h)
        worst = max(worst, float(np.max(np.abs(ff - fn) / np.maximum(np.abs(fn), 1e-6 * np.abs(fn).max() + 1e-300))))
    assert worst < 1e-11, f"largest relative difference {worst:.2e}"
    assert fast.evaluations.value < nested.evaluations.value  # the fast solve did its own work


def test_a_trial_leaves_the_state_and_gives_what_the_commit_gives(library):
    kernel = Kernel(library, rich_coefficients())
    steps, drive = history(40)
    for h, x in zip(steps[:-1], drive[:-1], strict=True):
        kernel.step(x, h)
    before = kernel.state.copy()
    trial = kernel.step(drive[-1] * 1.7, steps[-1], commit=False)
    assert np.array_equal(kernel.state, before)
    again = kernel.step(drive[-1] * 1.7, steps[-1], commit=False)
    assert np.array_equal(trial, again)
    assert np.array_equal(kernel.step(drive[-1] * 1.7, steps[-1]), trial)


def test_the_work_per_step_does_not_grow_with_the_history(library):
    """Layer-law evaluations per step (a count, not a time) early and late in a long
    stationary drive; the state's size is fixed by construction."""
    kernel = Kernel(library, coefficients(PAPER_B, 3))
    n, block = 20_000, 2_000
    t = np.arange(1, n + 1) * 2e-4
    amp = np.array([2e-4, 2e-4, 1e-4, 4e-3, 4e-3, 4e-3])
    counts = np.empty(n)
    size = kernel.state.size
    for i in range(n):
        before = kernel.evaluations.value
        kernel.step(amp * np.sin(2 * np.pi * 7.0 * t[i] + np.arange(6)), 2e-4)
        counts[i] = kernel.evaluations.value - before
    assert kernel.state.size == size
    early, late = counts[block:2 * block], counts[-block:]
    assert late.mean() <= 1.1 * early.mean() and late.max() <= early.max() + 4


def test_a_nan_input_is_an_error_with_a_sentence_not_a_number(library):
    kernel = Kernel(library, coefficients(PAPER_B, 1))
    with pytest.raises(RuntimeError, match="input rx = nan: must be a finite number"):
        kernel.step([0, 0, 0, np.nan, 0, 0], 1e-4)
