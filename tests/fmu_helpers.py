"""Test helpers for the FMU: the C kernel compiled alone and called through ctypes over
:func:`core.element.coefficients`, and the first harmonic of a settled drive."""

from __future__ import annotations

import ctypes
import subprocess
from pathlib import Path

import numpy as np

from core.element import CHANNEL_MODES
from fmu.build import KERNEL_SOURCES, c_sources, find_compiler
from fmu.description import parameters


class Sizes(ctypes.Structure):
    _fields_ = [("exponentials", ctypes.c_int), ("layers", ctypes.c_int * 6)]


def compile_kernel(directory: Path, extra: str = "", *, sources: Path | None = None, defines: tuple = (),
                   name: str = "kernel") -> Path:
    """The kernel (:data:`fmu.build.KERNEL_SOURCES` from ``sources``, the package's if None, plus
    C source ``extra``, with ``-D`` ``defines``) as a shared library ``name``.so in ``directory``:
    the one way the tests and benchmarks/fmu_speed.py build it."""
    src = Path(sources) if sources is not None else c_sources()
    out = Path(directory) / f"{name}.so"
    files = [str(src / f) for f in KERNEL_SOURCES if (src / f).exists()]
    if extra:
        (Path(directory) / f"{name}_extra.c").write_text(extra)
        files.append(str(Path(directory) / f"{name}_extra.c"))
    subprocess.run([find_compiler(), "-std=c99", "-O2", "-fPIC", "-shared", *(f"-D{d}" for d in defines),
                    "-I", str(src), *files, "-o", str(out), "-lm"], check=True, capture_output=True)
    return out


class Kernel:
    """The C kernel over one set of coefficients (:class:`core.element.Coefficients`, in the
    FMU's order, :func:`fmu.description.parameters`): advance / trial, the state readable."""

    def __init__(self, library: Path, coefficients):
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
    return strain / design.in_mode(CHANNEL_MODES[channel]).strain_factor
