"""Test helpers for the FMU: a coefficients mapping of docs/element.md's shape built from core's
shape factors (a stand-in for ``core.element.coefficients`` until that exists), the C kernel
compiled alone and called through ctypes, and an FMU written once per session."""

from __future__ import annotations

import ctypes
import math
import subprocess
from pathlib import Path

import numpy as np
from scipy.optimize import nnls

from core.slices import slice_nodes
from fmu.build import c_sources, find_compiler
from fmu.description import CHANNELS, DIRECTIONS

MODES_OF_CHANNELS = dict(zip(CHANNELS, DIRECTIONS, strict=True))


def fit_exponentials(alpha: float, band=(0.1, 2000.0), count: int = 16):
    """(rates λ_j in 1/s, weights g_j ≥ 0) with (iω)^α ≈ Σ g_j iω/(iω + λ_j) over the band:
    log-spaced rates from two decades below the band to one above, non-negative least squares on the relative error."""
    w = 2 * np.pi * np.geomspace(band[0], band[1], 400)
    rates = 2 * np.pi * np.geomspace(band[0] / 100, band[1] * 10, count)
    basis = (1j * w[:, None]) / (1j * w[:, None] + rates[None, :]) / (1j * w[:, None]) ** alpha
    a = np.vstack([basis.real, basis.imag])
    b = np.concatenate([np.ones(w.size), np.zeros(w.size)])
    weights, _ = nnls(a, b)
    return rates, weights


def fit_error(alpha, rates, weights, band=(0.1, 2000.0)):
    """Largest relative magnitude error and phase error (rad) of the fit inside the band."""
    w = 2 * np.pi * np.geomspace(band[0], band[1], 2000)
    ratio = np.sum(weights * (1j * w[:, None]) / (1j * w[:, None] + rates), axis=1) / (1j * w) ** alpha
    return float(np.max(np.abs(np.abs(ratio) - 1))), float(np.max(np.abs(np.angle(ratio))))


def layers(design, channel: str, slices: int = 1):
    """(S, c) lists of a channel's layers: the design turned to its direction; N slices of equal
    radial thickness for the axial and torsion channels (core.slices' rule), one layer else."""
    mode = MODES_OF_CHANNELS[channel]
    d = design.in_mode(mode)
    if slices == 1 or mode not in ("axial", "torsion"):
        return [d.shape_factor], [d.strain_factor]
    nodes = slice_nodes(d.geometry, mode, slices)  # p = 2c/S, q = 1/S per slice
    return (1.0 / nodes.q).tolist(), (nodes.p / (2.0 * nodes.q)).tolist()


def coefficients_of(design, slices: int = 1, band=(0.1, 2000.0), count: int = 16, **extra):
    """A coefficients mapping of docs/element.md's shape for ``design`` (no bulk spring)."""
    m = design.material
    rates, weights = fit_exponentials(m.fractional_order, band, count)
    out = {"mu": m.shear_modulus, "m": m.fractional_coefficient, "alpha": m.fractional_order,
           "sigma_f_max": m.friction_stress_max, "eps_half": m.friction_strain_half,
           "beta": 0.0, "viscosity": 0.0, "rate": rates.tolist(), "weight": weights.tolist()}
    for ch in CHANNELS:
        s, c = layers(design, ch, slices)
        out[ch] = {"S": s, "c": c, "compliance": 0.0}
    out.update(extra)
    return out


# --------------------------------------------------------------------------------------------
# the kernel alone, through ctypes


class Sizes(ctypes.Structure):
    _fields_ = [("exponentials", ctypes.c_int), ("layers", ctypes.c_int * 6)]


def compile_kernel(directory: Path, extra: str = "") -> Path:
    """The kernel (bushing_kernel.c and bushing_series.c, plus C source ``extra``) as a shared library."""
    src = c_sources()
    out = Path(directory) / "kernel.so"
    files = [str(src / "bushing_kernel.c"), str(src / "bushing_series.c")]
    if extra:
        (Path(directory) / "extra.c").write_text(extra)
        files.append(str(Path(directory) / "extra.c"))
    subprocess.run([find_compiler(), "-std=c99", "-O2", "-fPIC", "-shared", "-I", str(src), *files,
                    "-o", str(out), "-lm"], check=True, capture_output=True)
    return out


class Kernel:
    """The C kernel over one set of coefficients: advance / trial, the state readable."""

    def __init__(self, library: Path, coefficients):
        from fmu.description import parameters

        self.lib = ctypes.CDLL(str(library))
        params, (j, counts) = parameters(coefficients)
        self.sizes = Sizes(j, (ctypes.c_int * 6)(*counts))
        self.p = np.array([p.value for p in params], dtype=float)
        n_state = self.lib.bk_state_count(ctypes.byref(self.sizes))
        self.state = np.zeros(n_state)
        self.work = np.zeros(self.lib.bk_work_count(ctypes.byref(self.sizes)))
        self.lib.bk_work_reset(ctypes.byref(self.sizes), _ptr(self.work))
        self.message = ctypes.create_string_buffer(256)
        self.evaluations = ctypes.c_long(0)
        for name in ("bk_state_count", "bk_work_count", "bk_parameter_count"):
            getattr(self.lib, name).restype = ctypes.c_size_t
        assert self.lib.bk_parameter_count(ctypes.byref(self.sizes)) == self.p.size
        assert self.lib.bk_check_parameters(ctypes.byref(self.sizes), _ptr(self.p), self.message, 256) == 0, \
            self.message.value

    def step(self, x, h, commit=True):
        """Forces (6,) for the inputs x (6,) held over a step h; the state advances if commit."""
        x = np.ascontiguousarray(x, dtype=float)
        f = np.zeros(6)
        nxt = self.state if commit else self.state.copy()
        rc = self.lib.bk_advance(ctypes.byref(self.sizes), _ptr(self.p), _ptr(self.state), _ptr(nxt),
                                 _ptr(x), ctypes.c_double(h), _ptr(f), _ptr(self.work),
                                 ctypes.byref(self.evaluations), self.message, 256)
        if rc:
            raise RuntimeError(self.message.value.decode())
        return f


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def first_harmonic(signal, phase):
    """The complex first harmonic, signal ≈ Im(A e^{iθ}), over whole periods of θ."""
    return 2.0 * np.mean(np.asarray(signal) * np.exp(-1j * np.asarray(phase))) * 1j


def equivalent_amplitude(design, channel, strain):
    """The drive amplitude of a channel for an equivalent strain amplitude."""
    return strain / design.in_mode(MODES_OF_CHANNELS[channel]).strain_factor


__all__ = ["Kernel", "coefficients_of", "compile_kernel", "equivalent_amplitude", "first_harmonic", "fit_error",
           "fit_exponentials", "layers", "math"]
