"""The ``bushing`` command line (docs/files.md): a thin shell over the core.

Bad input exits with status 2 and one readable line on standard error; a computation that
cannot converge exits with status 1 and one line; no traceback is ever printed.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from core.bushing import slice_count, stiffness
from core.data import DataError
from core.io.design_file import read_design, read_design_file
from core.io.export import export
from core.io.measured import MAX_ROWS, combined, read_loop, read_stiffness
from core.io.table import csv_text
from core.loops import loop
from core.material import ConvergenceError
from core.plausibility import loop_verdict, stiffness_column, stiffness_verdict
from core.rules import DECIMAL, DesignError

from .parser import (  # the command line's words and bounds
    CARD_DISPLACEMENT,
    MAX_FREQUENCIES,
    MAX_GRID,
    MAX_SLICE_POINTS,
    NUMBER_FORMAT,
    InputError,
    _count,
    _frequency,
    build_parser,
)


def _frequencies(args) -> np.ndarray:
    f1 = _frequency("--freq F1")(args.freq[0])
    f2 = _frequency("--freq F2")(args.freq[1])
    n = _count("--freq N", 1, MAX_FREQUENCIES)(args.freq[2])
    if n == 1 and f1 != f2:
        raise InputError("bushing stiffness: --freq with N = 1 needs F1 = F2")
    return np.geomspace(f1, f2, n) if args.log else np.linspace(f1, f2, n)


def _finite(columns: dict) -> dict:
    """``columns`` if every number is finite; else say so (a design or drive outside what the
    formulas can represent, never a column of NaN)."""
    for name, values in columns.items():
        if not np.all(np.isfinite(np.asarray(values, dtype=float))):
            raise ComputationError(f"the {name} is not a finite number for this design and drive "
                                   "(outside what the formulas can represent)")
    return columns


class ComputationError(Exception):
    """A result that cannot be given: exit status 1."""


def _write_text(text: str, output: str | None) -> None:
    if output is None:
        try:
            sys.stdout.write(text)
            sys.stdout.flush()
        except OSError as exc:
            raise InputError(f"bushing: cannot write to standard output: {exc.strerror}")
        return
    try:
        with open(output, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
    except OSError as exc:
        raise InputError(f"bushing: cannot write {output!r}: {exc.strerror}")


def _write_csv(columns: dict[str, np.ndarray], output: str | None) -> None:
    _write_text(csv_text(columns, NUMBER_FORMAT), output)


def _cmd_stiffness(args) -> None:
    try:
        freqs = _frequencies(args)
    except argparse.ArgumentTypeError as exc:
        raise InputError(f"bushing stiffness: {exc}")
    if freqs.size * len(args.amp) > MAX_GRID:
        raise InputError(f"bushing stiffness: {freqs.size} frequencies × {len(args.amp)} amplitudes is more "
                         f"than {MAX_GRID} points; ask for fewer")
    design, fit_report = read_design_file(args.design)
    slices = "continuum" if args.continuum else args.slices
    layers = slice_count(design, slices)
    work, limit = freqs.size * len(args.amp) * layers, MAX_SLICE_POINTS[args.route]
    if work > limit:
        what = f"{layers} layers" if layers > 1 else "1 layer"
        raise InputError(f"bushing stiffness: {freqs.size * len(args.amp)} points × {what} "
                         f"({'the continuum' if slices == 'continuum' else 'slices'}) is more than {limit} "
                         f"point-layers for the {args.route} route; ask for fewer points or slices"
                         + (" (or the analytic route)" if args.route == "time-domain" else ""))
    result = stiffness(design, freqs, args.amp, slices=slices, route=args.route)
    table = result.table()
    if args.tolerance:
        from core.io.tolerances import read_tolerances
        from core.whatif.tolerance import band, band_columns

        # the design file's fit report, for a tolerance file that asks for the fit's covariance
        tolerances = read_tolerances(args.tolerance, fit_report)
        if work * tolerances.samples > limit:
            raise InputError(f"bushing stiffness: {tolerances.samples} samples × {work} point-layers is more than "
                             f"{limit} for the {args.route} route; ask for fewer samples or points")
        table.update(band_columns(band(design, freqs[None, :], np.asarray(args.amp)[:, None], tolerances,
                                       slices=slices, route=args.route)))
    _write_csv(_finite(table), args.output)


def _cmd_design(args) -> None:
    from core.io.targets import read_problem
    from core.whatif.target import solve

    found = solve(read_problem(args.targets))
    _write_text(found.to_json(), args.output)
    if args.output:
        sys.stdout.write(found.statement + "\n")


def _cmd_loop(args) -> None:
    design = read_design(args.design)
    result = loop(design, args.freq, args.amp, args.points)
    _write_csv(_finite(result.table()), args.output)


@contextmanager
def _one_line_errors():
    """Map every failure to one line on stderr and an exit status; never a traceback."""
    try:
        yield
    except InputError as exc:
        _fail(str(exc), 2)
    except (DesignError, DataError, ValueError) as exc:
        _fail(f"bushing: {exc}", 2)
    except (ConvergenceError, ComputationError) as exc:
        _fail(f"bushing: {exc}", 1)
    except KeyboardInterrupt:
        _fail("bushing: interrupted", 130)
    except Exception as exc:  # noqa: BLE001 - the last guard: one line, never a traceback
        _fail(f"bushing: internal error ({type(exc).__name__}: {exc})", 1)


_open_line = False  # a progress line is on the terminal without its newline


def _fail(message: str, status: int):
    sys.stderr.write(("\n" if _open_line else "") + " ".join(message.split()) + "\n")
    raise SystemExit(status)


MAX_MEASURED_FILES = 20


def _head(path) -> bytes:
    """A file's first bytes (its header)."""
    with open(path, "rb") as f:
        return f.read(4096)


def _judged(verdict) -> None:
    """A file's units judged for the bushing (:mod:`core.plausibility`), as the explorer judges
    them: refused (status 2), or a warning on stderr."""
    if verdict.refused:
        raise InputError(f"bushing: {verdict.message}")
    if verdict.warning:
        sys.stderr.write(f"bushing: warning: {verdict.warning}\n")


def _read_measured(paths: list[str], design):
    """The measured files as one table (rows without a mode in the design's mode), each judged
    for the design's bushing (:func:`_judged`)."""
    if len(paths) > MAX_MEASURED_FILES:
        raise InputError(f"bushing: at most {MAX_MEASURED_FILES} measured files, got {len(paths)}")
    parts, rows = [], 0
    for path in paths:
        parts.append(read_stiffness(path))
        _judged(stiffness_verdict(design, parts[-1], Path(path).name, stiffness_column(_head(path))))
        rows += len(parts[-1])
        if rows > MAX_ROWS:
            raise InputError(f"bushing: the measured files hold more than {MAX_ROWS} rows together")
    return combined(parts, design.mode)


def _cmd_fit(args) -> None:
    from core.identify.fit import fit_global, predicted, selection
    from core.parameters import MATERIAL
    from core.shape import BULK_RATIO

    design = read_design(args.design)
    data = _read_measured(args.measured, design)
    loop_data = read_loop(args.loop) if args.loop else None
    if loop_data is not None:
        _judged(loop_verdict(design, loop_data, Path(args.loop).name))
    free = MATERIAL
    if args.free_bulk_modulus:
        free = MATERIAL + ("bulk_modulus",)
        if design.material.bulk_modulus is None:
            design = design.replace(bulk_modulus=BULK_RATIO * design.material.shear_modulus)
    if args.fit_on is None:
        result = fit_global(design, data, loop_data, free=free)
    else:
        chosen = selection(data, design.mode, args.fit_on)
        result = fit_global(design, data.select(chosen), loop_data, free=free)
        result = dataclasses.replace(result, prediction=predicted(result, data, chosen, args.fit_on))
    _write_text(result.to_json(), args.output)
    for line in result.warnings:  # the fit succeeded; what the user must know, one line each
        sys.stderr.write(f"bushing fit: warning: {line}\n")


class Progress:
    """Progress of a long run on a terminal: one line rewritten in place, shown only once the
    run has taken ``after`` seconds (short runs stay silent) and never when ``stream`` is not a
    terminal (a script reading standard error sees only errors and warnings)."""

    def __init__(self, stream, after: float = 1.0):
        self.stream, self.after, self.start = stream, after, time.monotonic()
        try:
            self.live = stream.isatty()
        except (AttributeError, ValueError, OSError):
            self.live = False

    def __call__(self, fraction: float, message: str) -> None:
        if not self.live or time.monotonic() - self.start < self.after:
            return
        global _open_line
        try:
            self.stream.write(f"\r\033[Kbushing: {fraction:4.0%} {message}" + ("\n" if fraction >= 1 else ""))
            self.stream.flush()
            _open_line = fraction < 1
        except OSError:
            self.live = False


def _cmd_diagnose(args) -> None:
    from core.identify.diagnose import BRANCHES, diagnose, summary

    baseline = [b.strip() for b in args.baseline.split(",") if b.strip()]
    wrong = [b for b in baseline if b not in BRANCHES]
    if wrong or not baseline:
        raise InputError(f"bushing diagnose: --baseline takes branches from {','.join(BRANCHES)}, "
                         f"got {args.baseline!r}")
    design = read_design(args.design)
    data = _read_measured(args.measured, design)
    if data.mode is not None and len(set(data.mode)) == 1:  # one direction: the design in it
        design = design.in_mode(data.mode[0])
        data = data.of_mode(design.mode)
    result = diagnose(design, data, baseline=baseline, progress=Progress(sys.stderr))
    report = result.to_json()
    if args.predictions:
        _write_csv(result.predictions(), args.predictions)
    _write_text(report, args.report)
    if args.report:
        sys.stdout.write(summary(result))


def _cmd_card(args) -> None:
    from core.card import card

    design = read_design(args.design)
    rows = card(design, args.freq, float(CARD_DISPLACEMENT.to_si(args.amp_mm)), args.amp_rad)
    numbers = _finite({k: np.array([r[k] for r in rows]) for k in rows[0] if k != "mode"})
    _write_csv({"mode": [r["mode"] for r in rows], **numbers}, args.output)


def _cmd_export(args) -> None:

    try:
        freqs = _frequencies(args)
    except argparse.ArgumentTypeError as exc:
        raise InputError(f"bushing export: {exc}")
    design = read_design(args.design)
    as_json = args.format == "table" and bool(args.output) and args.output.lower().endswith(".json")
    _write_text(export(design, args.format, freqs, args.amp, as_json=as_json), args.output)


def _cmd_fmu(args) -> None:
    from core.element import (
        check_band,
        coefficients,  # docs/element.md
    )
    from fmu import FmuError, write_fmu

    try:
        f1, f2 = check_band(args.band)  # the element's rule, one implementation
    except ValueError as exc:
        raise InputError(f"bushing fmu: --{exc}")
    out = Path(args.output)
    if out.suffix.lower() != ".fmu":
        raise InputError(f"bushing fmu: -o {args.output!r}: the file name must end in .fmu")
    if out.is_dir() or not out.parent.is_dir():
        raise InputError(f"bushing fmu: cannot write {args.output!r}: "
                         + ("it is a directory" if out.is_dir() else "its directory does not exist"))
    design = read_design(args.design)
    try:
        co = coefficients(design, slices=args.slices, band=(f1, f2))  # the element's rules: slices, effects
        result = write_fmu(co, out, model_name=design.name or out.stem)
    except (FmuError, ValueError) as exc:
        raise InputError(f"bushing fmu: {exc}")
    if result.note:
        sys.stderr.write(f"bushing fmu: {result.note}\n")


COMMANDS = {"stiffness": _cmd_stiffness, "loop": _cmd_loop, "fit": _cmd_fit, "diagnose": _cmd_diagnose,
            "card": _cmd_card, "export": _cmd_export, "design": _cmd_design, "fmu": _cmd_fmu}


def main(argv: list[str] | None = None, parser: argparse.ArgumentParser | None = None,
         commands: dict | None = None) -> int:
    """Run one command. ``parser`` and ``commands`` extend the core's (``cli.main`` adds ``serve``:
    the command line's core knows nothing of the browser app)."""
    argv = sys.argv[1:] if argv is None else [str(a) for a in argv]
    with _one_line_errors(), warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")  # numerical warnings never reach users: results are checked
        option = ""
        for token in argv:
            if token.startswith("-") and DECIMAL.fullmatch(token):
                raise InputError(f"bushing: {option} {token}: every number on the command line is positive "
                                 "(amplitudes, frequencies, counts)")
            if token.startswith("-"):
                option = token
        args = (parser or build_parser()).parse_args(argv)
        (commands or COMMANDS)[args.command](args)
        try:
            sys.stdout.flush()
        except OSError as exc:
            raise InputError(f"bushing: cannot write to standard output: {exc.strerror}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
