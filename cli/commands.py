"""The ``bushing`` command line (docs/files.md): a thin shell over the core.

Bad input exits with status 2 and one readable line on standard error; a computation that
cannot converge exits with status 1 and one line; no traceback is ever printed.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from core.bushing import MAX_SLICES, ROUTES, slice_count, stiffness
from core.data import DataError
from core.io.design_file import read_design, read_design_file
from core.io.export import FORMATS, export
from core.io.measured import MAX_ROWS, combined, read_loop, read_stiffness
from core.io.table import csv_text
from core.loops import loop
from core.material import ConvergenceError
from core.parameters import BRANCH_PARAMETERS, MODE, ROTATIONS, TRANSLATIONS
from core.plausibility import loop_verdict, stiffness_column, stiffness_verdict
from core.rules import DECIMAL, OVERFLOW, WHOLE, DesignError, RuleError, decimal

NUMBER_FORMAT = "{:.12g}"
# the largest sizes the command line computes (docs/files.md): a grid of at most a million
# points, a loop of at most a million samples
MAX_FREQUENCIES = 100_000
MAX_GRID = 1_000_000
# the work of a stiffness run, points × layers (slices, or the continuum's nodes): the closed
# form does millions a second, the thesis' time-domain simulation about thirty
MAX_SLICE_POINTS = {"analytic": 20_000_000, "time-domain": 600}
MAX_LOOP_POINTS = 1_000_000
CARD_DISPLACEMENT = MODE[TRANSLATIONS[0]].amplitude  # the card's displacements: in mm, as people read them


class InputError(Exception):
    """Bad input from the command line: exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, status 2 (argparse would print the usage too)
        raise InputError(f"{self.prog}: {message} (see {self.prog} --help)")


def _positive(name):
    def parse(text: str) -> float:
        try:  # the data files' rule: Python's float() also takes "1_000", "nan", "inf"
            value = decimal(text)
        except RuleError as exc:
            if exc.code != OVERFLOW:
                raise argparse.ArgumentTypeError(f"{name} must be a number, got {text!r}") from None
            value = math.inf
        if not math.isfinite(value) or value <= 0:
            raise argparse.ArgumentTypeError(f"{name} must be a positive finite number, got {text!r}")
        return value

    return parse


def _count(name, minimum=1, maximum=None):
    def parse(text: str) -> int:
        if not WHOLE.fullmatch(str(text).strip()):
            raise argparse.ArgumentTypeError(f"{name} must be a whole number, got {text!r}")
        value = int(text)
        if value < minimum:
            raise argparse.ArgumentTypeError(f"{name} must be at least {minimum}, got {text!r}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"{name} must be at most {maximum}, got {text!r}")
        return value

    return parse


def subcommands(parser: argparse.ArgumentParser):
    """The sub-parser action of :func:`build_parser`'s parser (to add commands to)."""
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="bushing",
        description="Dynamic stiffness of filled-rubber bushings (torsion and axial) with the "
        "Fletcher–Gent amplitude dependence. All numbers SI: m, rad, Pa, Hz, N.",
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    st = sub.add_parser(
        "stiffness",
        help="dynamic stiffness on a frequency × amplitude grid (CSV)",
        description="Dynamic stiffness on a grid. Writes CSV with columns frequency_hz, "
        "amplitude, stiffness_real, stiffness_imag, magnitude, loss_factor (one row per "
        "amplitude and frequency; N/m axially, N·m/rad in torsion).",
    )
    _grid_arguments(st, f"peak amplitudes: displacement in m ({', '.join(TRANSLATIONS)}) or angle in rad "
                        f"({', '.join(ROTATIONS)})")
    group = st.add_mutually_exclusive_group()
    group.add_argument(
        "--slices",
        type=_count("--slices", maximum=MAX_SLICES),
        default=1,
        metavar="N",
        help=f"N concentric slices of equal thickness in series (default 1: eqs 17/18; at most {MAX_SLICES})",
    )
    group.add_argument(
        "--continuum", action="store_true", help="the continuum limit of infinitely many slices"
    )
    st.add_argument(
        "--route",
        choices=ROUTES,
        default="analytic",
        help="analytic steady state (default, fast) or the thesis' time-domain simulation",
    )
    st.add_argument("--tolerance", metavar="TOLERANCES.json",
                    help="add percentile columns of |K| and the loss factor under these tolerances "
                         "(a Monte Carlo with a stated seed; docs/files.md)")
    st.add_argument("-o", dest="output", metavar="OUT.csv", help="write here, not to stdout")

    lp = sub.add_parser(
        "loop",
        help="one steady period of the hysteresis loop (CSV)",
        description="One steady period of the hysteresis loop, drive x̂ sin(2πk/N), k = 0 … N−1. "
        "Writes CSV with columns displacement, force, force_elastic, force_viscoelastic, "
        "force_friction (m or rad; N or N·m).",
    )
    lp.add_argument("design", metavar="DESIGN.json", help="design file (docs/files.md)")
    lp.add_argument("--freq", required=True, type=_positive("--freq"), metavar="F", help="Hz")
    lp.add_argument(
        "--amp", required=True, type=_positive("--amp"), metavar="A", help="peak, m or rad"
    )
    lp.add_argument(
        "--points", type=_count("--points", 4, MAX_LOOP_POINTS), default=256, metavar="N",
        help=f"default 256, at most {MAX_LOOP_POINTS}"
    )
    lp.add_argument("-o", dest="output", metavar="OUT.csv", help="write here, not to stdout")
    ft = sub.add_parser(
        "fit",
        help="identify the five material parameters from measured data",
        description="Fit µ, m, α, σ_fmax and ε½ to measured dynamic stiffness (and a measured "
        "loop) from several starting points; the design's material is the first. Writes the "
        "design file with the fitted material and a `fit` object: standard_errors, "
        "correlation, gap.",
    )
    _measured_arguments(ft, "geometry, mode and starting material")
    ft.add_argument("--loop", metavar="LOOP.csv", help="a measured steady loop (time_s, displacement, force)")
    ft.add_argument("--fit-on", metavar="SELECTION",
                    help="fit only these rows, predict the rest (the report's `prediction`): "
                    "mode=NAME[+NAME…] and/or amplitude=VALUE[+VALUE…], comma-separated, e.g. "
                    "mode=axial,amplitude=1e-4")
    ft.add_argument("-o", dest="output", metavar="FITTED.json", help="write here, not to stdout")

    dg = sub.add_parser(
        "diagnose",
        help="find the effect the model is missing: where it disagrees, what is missing, the gap shrinking",
        description="The discrepancy workflow: fit the baseline model, describe where it "
        "disagrees with the measurement, name the missing effects of the library one by one "
        "(ranked by BIC, with a threshold that does not add effects to fit noise), refit, and "
        "report the gap before and after each step and on held-out data. The report (JSON) goes "
        "to standard output, or to --json with a summary in plain words on standard output.",
    )
    _measured_arguments(dg, "geometry (known), mode and starting parameters")
    dg.add_argument("--baseline", default=",".join(BRANCH_PARAMETERS), metavar="IDS",
                    help="the branches the starting model has, comma-separated from "
                    f"{','.join(BRANCH_PARAMETERS)} (default: all three)")
    dg.add_argument("--json", dest="report", metavar="REPORT.json", help="write the report here")
    dg.add_argument("--predictions", metavar="PRED.csv",
                    help="write, per data row, the baseline's and the final model's |K| and loss factor")

    cd = sub.add_parser(
        "card",
        help=f"every direction at one operating point: {', '.join(TRANSLATIONS + ROTATIONS)} (CSV)",
        description="The bushing card: the dynamic stiffness in the four directions at one "
        f"frequency, {' and '.join(TRANSLATIONS)} at D {CARD_DISPLACEMENT.display}, {' and '.join(ROTATIONS)} "
        "at R rad, with finite-length "
        "shape factors (the design's shape 'long' keeps the closed forms for axial and torsion). "
        "Writes CSV with columns mode, amplitude (m or rad), stiffness_real, stiffness_imag, "
        "magnitude, loss_factor, shape_factor.",
    )
    cd.add_argument("design", metavar="DESIGN.json", help="design file (docs/files.md); its mode is not used")
    cd.add_argument("--freq", required=True, type=_positive("--freq"), metavar="F", help="Hz")
    cd.add_argument("--amp-mm", required=True, type=_positive("--amp-mm"), metavar="D",
                    help=f"peak displacement of the {' and '.join(TRANSLATIONS)} directions, "
                    f"{CARD_DISPLACEMENT.display}")
    cd.add_argument("--amp-rad", required=True, type=_positive("--amp-rad"), metavar="R",
                    help=f"peak angle of the {' and '.join(ROTATIONS)} directions, rad")
    cd.add_argument("-o", dest="output", metavar="CARD.csv", help="write here, not to stdout")

    ex = sub.add_parser(
        "export",
        help="files for multibody and FE tools: neutral tables, Nastran PBUSH/PBUSHT/TABLED1, Adams .bus",
        description="The design's stiffness in every direction over a frequency × amplitude grid, as a neutral "
        "table (CSV, or JSON when OUT ends in .json), Nastran bulk data or an Adams TeimOrbit bushing file "
        "(linearised at the first amplitude and frequency). Amplitudes are in the design's mode (m or rad); "
        "every direction is taken at the same equivalent strains (docs/export.md).",
    )
    _grid_arguments(ex, "amplitudes in the design's mode, m or rad")
    ex.add_argument("--format", required=True, choices=FORMATS, help="the file to write")
    ex.add_argument("-o", dest="output", metavar="OUT", help="write here, not to stdout")

    dz = sub.add_parser(
        "design",
        help="geometries (and compounds within ranges) that meet target stiffnesses",
        description="Searches a, b, L (and the material parameters the file frees) for the designs nearest the "
        "file's starting design that meet its targets on |K|, the loss factor or the ratio of two directions, "
        "within its limits; or says why they cannot be met (docs/files.md).",
    )
    dz.add_argument("targets", metavar="TARGETS.json", help="targets file (docs/files.md)")
    dz.add_argument("-o", dest="output", metavar="DESIGNS.json",
                    help="write the report here (the statement goes to stdout), not to stdout")

    return parser


def _grid_arguments(parser: argparse.ArgumentParser, amp_help: str) -> None:
    """DESIGN.json --freq F1 F2 N [--log] --amp A1 [A2 …]: what `stiffness` and `export` take."""
    parser.add_argument("design", metavar="DESIGN.json", help="design file (docs/files.md)")
    parser.add_argument("--freq", nargs=3, required=True, metavar=("F1", "F2", "N"),
                        help="N frequencies from F1 to F2 in Hz (linear unless --log)")
    parser.add_argument("--log", action="store_true", help="space the frequencies logarithmically")
    parser.add_argument("--amp", nargs="+", required=True, type=_positive("--amp"), metavar="A", help=amp_help)


def _measured_arguments(parser: argparse.ArgumentParser, design_help: str) -> None:
    """MEASURED.csv … --design DESIGN.json: what `fit` and `diagnose` both take."""
    parser.add_argument("measured", metavar="MEASURED.csv", nargs="+",
                        help="measured stiffness (docs/files.md); several files are read as one (a file "
                        "with a mode column may hold several directions; one without is in the design's mode)")
    parser.add_argument("--design", required=True, metavar="DESIGN.json", help=design_help)


def _frequencies(args) -> np.ndarray:
    f1 = _positive("--freq F1")(args.freq[0])
    f2 = _positive("--freq F2")(args.freq[1])
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

    design = read_design(args.design)
    data = _read_measured(args.measured, design)
    loop_data = read_loop(args.loop) if args.loop else None
    if loop_data is not None:
        _judged(loop_verdict(design, loop_data, Path(args.loop).name))
    if args.fit_on is None:
        result = fit_global(design, data, loop_data)
    else:
        chosen = selection(data, design.mode, args.fit_on)
        result = fit_global(design, data.select(chosen), loop_data)
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


COMMANDS = {"stiffness": _cmd_stiffness, "loop": _cmd_loop, "fit": _cmd_fit, "diagnose": _cmd_diagnose,
            "card": _cmd_card, "export": _cmd_export, "design": _cmd_design}


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
