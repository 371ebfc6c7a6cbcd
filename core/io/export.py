"""Files for multibody and finite-element tools: the design's stiffness in every direction over a
frequency × amplitude grid (docs/export.md).

The amplitudes are given in the design's mode (m or rad); every direction is evaluated at the
same equivalent strains ε = c_design · x̂, so its amplitude is ε / c_direction (a bushing driven
to the same strain level in each direction). Shape factors as the card's (:mod:`core.card`).

* neutral tables: CSV (one row per direction, amplitude and frequency; units in their own
  columns) and JSON (units in its header);
* Nastran bulk data (small-field, fixed 8-character fields): per amplitude one ``PBUSH`` (K1–K6
  and GE1–GE6 at the grid's first frequency) with a ``PBUSHT`` pointing to ``TABLED1`` entries of
  K(f) and GE(f) = loss factor; element x is the bushing axis (K1 axial, K2 = K3 radial, K4
  torsion, K5 = K6 conical);
* an Adams-style TeimOrbit bushing property file (``.bus``): ``[MDI_HEADER]``, ``[UNITS]``, force
  and torque curves linearised at the first amplitude and frequency (K′ through ±x̂) and the
  equivalent viscous damping c = K″/ω, per direction (z is the bushing axis).
"""

from __future__ import annotations

import json
import math

import numpy as np

from ..bushing import stiffness_points
from ..card import CARD_MODES, card_design
from ..design import Design
from ..parameters import MODE, ROTATIONS, TRANSLATIONS
from ..response import loss_factor
from .table import csv_text

MAX_EXPORT_POINTS = 100_000  # frequencies × amplitudes of one export


def direction_grid(design: Design, frequency_hz, amplitude) -> dict:
    """For each direction: its amplitudes (SI) and the complex K on amplitude × frequency."""
    f = np.atleast_1d(np.asarray(frequency_hz, dtype=float))
    x = np.atleast_1d(np.asarray(amplitude, dtype=float))
    if f.size * x.size > MAX_EXPORT_POINTS:
        raise ValueError(f"an export holds at most {MAX_EXPORT_POINTS} frequencies × amplitudes; asked "
                         f"{f.size} × {x.size}")
    own = card_design(design, design.mode)  # the design's direction keeps the given amplitudes exactly
    eps = own.strain(x)
    out = {"frequency_hz": f, "strain": eps}
    for mode in CARD_MODES:
        d = card_design(design, mode)
        amp = d.drive(eps)
        k = stiffness_points(d, f[None, :], amp[:, None])
        if not np.all(np.isfinite(k)):
            raise ValueError(f"the {mode} stiffness is not finite on this grid")
        out[mode] = {"amplitude": amp, "stiffness": k}
    return out


def table_csv(grid: dict) -> str:
    """The neutral table as CSV: mode, frequency_hz, amplitude, amplitude_unit, stiffness_real,
    stiffness_imag, magnitude, stiffness_unit, loss_factor."""
    cols = {k: [] for k in ("mode", "frequency_hz", "amplitude", "amplitude_unit", "stiffness_real",
                            "stiffness_imag", "magnitude", "stiffness_unit", "loss_factor")}
    for mode in CARD_MODES:
        k = grid[mode]["stiffness"]
        eta = loss_factor(k)
        for i, amp in enumerate(grid[mode]["amplitude"]):
            for j, f in enumerate(grid["frequency_hz"]):
                cols["mode"].append(mode)
                cols["frequency_hz"].append(f)
                cols["amplitude"].append(amp)
                cols["amplitude_unit"].append(MODE[mode].amplitude.si)
                cols["stiffness_real"].append(k[i, j].real)
                cols["stiffness_imag"].append(k[i, j].imag)
                cols["magnitude"].append(abs(k[i, j]))
                cols["stiffness_unit"].append(MODE[mode].stiffness.si)
                cols["loss_factor"].append(eta[i, j])
    return csv_text(cols)


def table_json(grid: dict, design: Design) -> str:
    """The neutral table as JSON: a header (design, units, layout) and per direction the
    amplitudes and the stiffness on amplitude × frequency."""
    out = {
        "header": {"design": design.to_dict(), "frequency_unit": "Hz",
                   "layout": "stiffness_real[i][j] etc. at amplitude[i] and frequency_hz[j]",
                   "equivalent_strain": grid["strain"].tolist()},
        "frequency_hz": grid["frequency_hz"].tolist(),
        "directions": {},
    }
    for mode in CARD_MODES:
        k = grid[mode]["stiffness"]
        out["directions"][mode] = {
            "amplitude_unit": MODE[mode].amplitude.si, "stiffness_unit": MODE[mode].stiffness.si,
            "amplitude": grid[mode]["amplitude"].tolist(), "stiffness_real": k.real.tolist(),
            "stiffness_imag": k.imag.tolist(), "magnitude": np.abs(k).tolist(), "loss_factor": loss_factor(k).tolist(),
        }
    return json.dumps(out, indent=1, allow_nan=False) + "\n"


# ---- Nastran -------------------------------------------------------------------------------------

# K1 … K6: the translations along x, y, z, then the rotations about them; element x is the
# bushing axis, so x takes the mode along (about) the axis, y and z the one across it
NASTRAN_DOF = tuple(m for group in (TRANSLATIONS, ROTATIONS)
                    for m in sorted(group, key=lambda m: not MODE[m].on_axis)
                    for _ in range(1 if MODE[m].on_axis else 2))


def _dof_words() -> str:
    """Which mode each of K1 … K6 holds, in words: ``K1 axial, K2 = K3 radial, …``."""
    return ", ".join(" = ".join(f"K{i + 1}" for i, d in enumerate(NASTRAN_DOF) if d == m) + f" {m}"
                     for m in dict.fromkeys(NASTRAN_DOF))


def nastran_real(value: float) -> str:
    """A real number in at most 8 characters, as many significant digits as fit (Nastran's
    short exponent form, 1.2345+6, where it needs one)."""
    v = float(value)
    if v == 0.0:
        return "0."
    for digits in range(7, 0, -1):
        text = f"{v:.{digits}g}"
        if "e" in text:
            mantissa, exponent = text.split("e")
            text = f"{mantissa if '.' in mantissa else mantissa + '.'}{int(exponent):+d}"
        elif "." not in text:
            text += "."
        if len(text) <= 8:
            return text
    raise ValueError(f"{v!r} does not fit a Nastran field")


def _card(name: str, fields: list[str]) -> list[str]:
    """Small-field fixed format: the name, then 8 data fields per line; continuation lines have a
    blank first field."""
    lines = []
    for start in range(0, max(len(fields), 1), 8):
        head = name if start == 0 else ""
        lines.append(f"{head:<8}" + "".join(f"{v:>8}" for v in fields[start:start + 8]))
    return lines


def nastran(grid: dict, design: Design, first_id: int = 1) -> str:
    """Bulk data: PBUSH, PBUSHT and TABLED1 per amplitude (PID first_id + i)."""
    f = grid["frequency_hz"]
    n_amp = grid[CARD_MODES[0]]["amplitude"].size
    lines = [f"$ Bushing Explorer: {design.name or 'design'}; element x along the bushing axis",
             f"$ {_dof_words()}; GE = loss factor; SI units (N, m, rad)"]
    for i in range(n_amp):
        pid = first_id + i
        k = {m: grid[m]["stiffness"][i] for m in CARD_MODES}
        amps = ", ".join(f"{m} {grid[m]['amplitude'][i]:.4g} {MODE[m].amplitude.si}" for m in CARD_MODES)
        lines.append(f"$ PID {pid}: equivalent strain {grid['strain'][i]:.4g} ({amps})")
        lines += _card("PBUSH", [str(pid), "K", *(nastran_real(k[m][0].real) for m in NASTRAN_DOF)])
        lines += _card("", ["", "GE", *(nastran_real(loss_factor(k[m][0])) for m in NASTRAN_DOF)])
        tk = [1000 * pid + 10 * (d + 1) + 1 for d in range(6)]
        tge = [1000 * pid + 10 * (d + 1) + 2 for d in range(6)]
        lines += _card("PBUSHT", [str(pid), "K", *(str(t) for t in tk)])
        lines += _card("", ["", "GE", *(str(t) for t in tge)])
        for d, mode in enumerate(NASTRAN_DOF):
            for tid, values in ((tk[d], k[mode].real), (tge[d], loss_factor(k[mode]))):
                pairs = [nastran_real(v) for xy in zip(f, values) for v in xy] + ["ENDT"]
                lines += _card("TABLED1", [str(tid), "LINEAR", "LINEAR"])
                lines += _card("", pairs)
    return "\n".join(lines) + "\n"


# ---- Adams ----------------------------------------------------------------------------------------


def adams_sections(mode: str) -> tuple[tuple[str, str], ...]:
    """The (curve, damping) sections of ``mode`` in a TeimOrbit file, whose z is the bushing
    axis: a mode along (about) the axis has z's, one across it x's and y's alike."""
    m = MODE[mode]
    what, damping = ("TORQUE", "R") if m.rotation else ("FORCE", "")
    axes = ("Z",) if m.on_axis else ("X", "Y")
    return tuple((f"{axis}_{what}_CURVE", f"{damping}{axis}_DAMPING") for axis in axes)


def adams(grid: dict, design: Design, points: int = 5) -> str:
    """TeimOrbit bushing property file linearised at the grid's first amplitude and frequency:
    force (torque) curves K′·x through ±x̂ and the equivalent viscous damping c = K″/(2πf)."""
    f0 = float(grid["frequency_hz"][0])
    omega = 2.0 * math.pi * f0
    lines = [
        "$---------------------------------------------------------------------MDI_HEADER",
        "[MDI_HEADER]", "FILE_TYPE = 'bus'", "FILE_VERSION = 4.0", "FILE_FORMAT = 'ASCII'",
        "(COMMENTS)", "{comment_string}",
        (f"'Bushing Explorer: {(design.name or 'design').replace(chr(39), '')}, linearised at {f0:.6g} Hz, "
         f"equivalent strain {grid['strain'][0]:.6g}; z along the bushing axis'"),
        "$--------------------------------------------------------------------------UNITS",
        "[UNITS]", "LENGTH = 'meter'", "ANGLE = 'radians'", "FORCE = 'newton'", "MASS = 'kg'", "TIME = 'second'",
    ]
    for mode in CARD_MODES:
        k = grid[mode]["stiffness"][0, 0]
        amp = float(grid[mode]["amplitude"][0])
        x = np.linspace(-amp, amp, points)
        for curve, damping in adams_sections(mode):
            what = "torque" if "TORQUE" in curve else "force"
            lines += [f"$ {mode}: K' = {k.real:.8g} {MODE[mode].stiffness.si}, loss factor {loss_factor(k):.6g}",
                      f"[{curve}]", f"{{ {'rot' if what == 'torque' else 'disp'} {what} }}"]
            lines += [f"{xi:.10g} {k.real * xi:.10g}" for xi in x]
            lines += [f"[{damping}]", f"DAMPING = {k.imag / omega:.10g}"]
    return "\n".join(lines) + "\n"


FORMATS = ("table", "nastran", "adams")


def export(design: Design, fmt: str, frequency_hz, amplitude, *, as_json: bool = False) -> str:
    """The text of one export format: ``table`` (CSV, or JSON with ``as_json``), ``nastran``
    or ``adams``."""
    grid = direction_grid(design, frequency_hz, amplitude)
    if fmt == "table":
        return table_json(grid, design) if as_json else table_csv(grid)
    if fmt == "nastran":
        return nastran(grid, design)
    if fmt == "adams":
        return adams(grid, design)
    raise ValueError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r}")
