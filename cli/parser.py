"""The `bushing` command line's parser: its commands, their arguments, help and bounds (the
commands themselves are :mod:`cli.commands`)."""

from __future__ import annotations

import argparse
import math

from core.bushing import MAX_SLICES, ROUTES
from core.element import DEFAULT_BAND
from core.element.coefficients import MAX_SLICES as ELEMENT_SLICES
from core.element.prony import MAX_DECADES as MAX_BAND_DECADES
from core.io.export import FORMATS
from core.parameters import BRANCH_PARAMETERS, FREQUENCY_HZ, MODE, ROTATIONS, TRANSLATIONS
from core.rules import OVERFLOW, WHOLE, RuleError, decimal, excerpt

NUMBER_FORMAT = "{:.12g}"
# the largest sizes the command line computes (docs/files.md): a grid of at most a million
# points, a loop of at most a million samples
MAX_FREQUENCIES = 100_000
MAX_GRID = 1_000_000
# the work of a stiffness run, points × layers (slices, or the continuum's nodes): the closed
# form does millions a second, the thesis' time-domain simulation about thirty
MAX_SLICE_POINTS = {"analytic": 20_000_000, "time-domain": 600}
MAX_LOOP_POINTS = 1_000_000
# the FMU's band of the fractional derivative's exponentials (docs/element.md): at most 8 decades
FMU_BAND = DEFAULT_BAND
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


def _frequency(name):
    """A positive number of Hz within the frequencies any file may hold
    (:data:`core.parameters.FREQUENCY_HZ`): the range the model is meant for."""
    positive = _positive(name)

    def parse(text: str) -> float:
        value = positive(text)
        lo, hi = FREQUENCY_HZ
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"{name} must be within {lo:g}–{hi:g} Hz (a rubber bushing's "
                                             f"frequencies, as measured files hold), got {excerpt(repr(text))}")
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
    lp.add_argument("--freq", required=True, type=_frequency("--freq"), metavar="F", help="Hz")
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
    ft.add_argument("--free-bulk-modulus", action="store_true",
                    help="fit the bulk modulus K too (the design's, or 5000 µ, is the start): radial and conical "
                    "data of a thin wall determine it, axial and torsion do not; the report gives its interval "
                    "or names it undetermined")
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
        "at R rad, each with the design file's shape factor: the closed forms for axial and torsion "
        "unless the design's shape is 'finite', the finite-length table for radial and conical. "
        "Writes CSV with columns mode, amplitude (m or rad), stiffness_real, stiffness_imag, "
        "magnitude, loss_factor, shape_factor.",
    )
    cd.add_argument("design", metavar="DESIGN.json", help="design file (docs/files.md); its mode is not used")
    cd.add_argument("--freq", required=True, type=_frequency("--freq"), metavar="F", help="Hz")
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

    fm = sub.add_parser(
        "fmu",
        help="the bushing as a native FMI 2.0 co-simulation FMU (docs/fmu.md)",
        description="Write the bushing as an FMI 2.0 co-simulation FMU: inputs dx dy dz (m), rx ry rz (rad), "
        "outputs fx fy fz (N), mx my mz (N·m), the axis along z; the design's coefficients as parameters; "
        "the C sources in sources/ and, where a C compiler is found (cc or $CC), the binary for this "
        "platform (binaries/linux64). Without a compiler the FMU holds the sources only (docs/fmu.md).",
    )
    fm.add_argument("design", metavar="DESIGN.json", help="design file (docs/files.md); its mode is not used")
    fm.add_argument("-o", dest="output", required=True, metavar="BUSHING.fmu", help="the FMU to write")
    fm.add_argument("--slices", type=_count("--slices", maximum=ELEMENT_SLICES), default=1, metavar="N",
                    help=f"N slices in series in the axial and torsion channels (default 1, at most {ELEMENT_SLICES})")
    fm.add_argument("--band", nargs=2, type=_positive("--band"), default=FMU_BAND, metavar=("F1", "F2"),
                    help=f"the band in Hz the fractional derivative is fitted over (default {FMU_BAND[0]:g} "
                         f"{FMU_BAND[1]:g}, at most {MAX_BAND_DECADES} decades wide)")

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
