"""The one way a number is written for people, and the one way a typed number is read.

Writing (:func:`format_number`, :func:`format_value`): a value is rounded to the significant
digits of its quantity (:data:`DIGITS`: 4 for stiffnesses, forces, sizes, moduli and frequencies,
3 for loss factors, ratios, gaps, per cents and drive amplitudes) and written in plain positional
notation when its magnitude lies in [:data:`PLAIN_LOW`, :data:`PLAIN_HIGH`) (``0.0005``,
``35730``, trailing zeros dropped), else in engineering notation, the mantissa from 1 to 999 and
the exponent a multiple of 3 (``15×10⁻⁶``). Never ``1e+03``. The unit follows after a space, as
the table of :mod:`core.parameters` names it. The browser's tick labels use the same rule, in
JavaScript (:data:`TICK_JS`). A link writes :data:`LINK_DIGITS` digits, positionally always
(:func:`link_number`): a shared link reproduces the numbers shown.

Reading (:func:`parse_number`): surrounding blanks aside, a decimal number as
:func:`core.rules.decimal` takes it, or one as :func:`format_number` writes it (``15×10⁻⁶``); a
comma, a letter, a unit or anything else is refused with words that name what was typed: a typo
never becomes a different number. :func:`range_problem` words a value outside its field's bounds,
in the field's unit.
"""

from __future__ import annotations

import math
from decimal import Decimal

from .rules import RuleError, decimal, excerpt

# significant digits by quantity (the words the callers use)
DIGITS = {
    "stiffness": 4, "force": 4, "size": 4, "modulus": 4, "frequency": 4, "parameter": 4,
    "amplitude": 3, "loss_factor": 3, "ratio": 3, "gap": 3, "percent": 3, "error": 2,
}
DEFAULT_DIGITS = 4
# magnitudes written positionally: from 0.0001 up to (not including) ten million
PLAIN_LOW, PLAIN_HIGH = 1e-4, 1e7
# the digits of a number in a link: more than any field shows, and enough that the design a link
# gives shows the same numbers as the design it was written from (a found design's |K| moves by
# 1.3e-4 when its fields are rounded to 6 digits: the thin rubber layer amplifies)
LINK_DIGITS = 9
_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
_FROM_SUPERSCRIPT = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")
MINUS = "−"  # a negative number's sign as people read it (U+2212), not the hyphen-minus


def digits_of(quantity: str | int | None) -> int:
    """The significant digits of ``quantity`` (a key of :data:`DIGITS`, or a number of digits)."""
    if isinstance(quantity, int):
        return quantity
    return DIGITS.get(quantity, DEFAULT_DIGITS) if quantity else DEFAULT_DIGITS


def rounded(value: float, digits: int = LINK_DIGITS) -> float:
    """``value`` rounded to ``digits`` significant digits (a float; non-finite values as they are)."""
    value = float(value)
    return float(f"{value:.{digits}g}") if math.isfinite(value) else value


def _positional(value: float, digits: int) -> str:
    text = format(Decimal(f"{value:.{digits}g}"), "f")
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def format_number(value, quantity: str | int | None = None) -> str:
    """``value`` (a real number in its unit) as people read it: the significant digits of
    ``quantity`` (:data:`DIGITS`, or a number of digits), positional in [1e-4, 1e7), else
    engineering notation (``15×10⁻⁶``), a negative number with a true minus sign (``−0.5``);
    ``–`` for None, NaN or an infinity."""
    if value is None:
        return "–"
    value = float(value)
    if not math.isfinite(value):
        return "–"
    digits = digits_of(quantity)
    value = rounded(value, digits)
    if value == 0.0 or PLAIN_LOW <= abs(value) < PLAIN_HIGH:
        return _positional(value, digits).replace("-", MINUS)
    exponent = 3 * math.floor(math.log10(abs(value)) / 3)
    mantissa = rounded(value / 10.0 ** exponent, digits)
    if abs(mantissa) >= 1000:  # rounding carried it over: 999.95×10³ → 1×10⁶
        mantissa, exponent = rounded(mantissa / 1000, digits), exponent + 3
    return f"{_positional(mantissa, digits).replace('-', MINUS)}×10{str(exponent).translate(_SUPERSCRIPT)}"


def format_outside(value, low: float, high: float, quantity: str | int | None = None) -> str:
    """:func:`format_number` of a value outside [``low``, ``high``], with as many more digits as
    keep it outside: a message never says "0.0001 Hz must be within 0.0001–100000 Hz" of a
    value just below its bound (a value inside is written as :func:`format_number` writes it)."""
    digits = digits_of(quantity)
    value = float(value)
    if math.isfinite(value) and not low <= value <= high:
        while digits < 17 and low <= rounded(value, digits) <= high:
            digits += 1
    return format_number(value, digits)


def format_value(value, unit: str = "", quantity: str | int | None = None) -> str:
    """:func:`format_number` followed by ``unit`` (none for ``""`` or ``–``): ``35.73 kN/mm``."""
    text = format_number(value, quantity)
    return text if not unit or unit == "–" or text == "–" else f"{text} {unit}"


def format_signed(value: float, decimals: int = 2) -> str:
    """A signed number to ``decimals`` decimals with a true minus sign (``+0.41``, ``−0.99``),
    zero unsigned (never ``-0.00``); ``–`` for None, NaN or an infinity."""
    if value is None or not math.isfinite(float(value)):
        return "–"
    text = f"{float(value):+.{decimals}f}"
    return text[1:] if float(text) == 0 else text.replace("-", MINUS)


def format_signed_number(value: float, quantity: str | int | None = None) -> str:
    """:func:`format_number` with a sign, a true minus sign (``+0.52``, ``−0.0012``), zero
    unsigned; ``–`` for None, NaN or an infinity."""
    text = format_number(None if value is None else abs(float(value)), quantity)
    if text == "–" or float(value) == 0.0:
        return text
    return (MINUS if float(value) < 0 else "+") + text


def format_change(fraction: float) -> str:
    """A relative change as people read it: signed percent to 3 significant digits (``−1.48 %``,
    ``+0.512 %``), ``0 %`` below 0.001 %."""
    pct = 100.0 * float(fraction)
    if abs(pct) < 1e-3:
        return "0 %"
    return format_signed_number(pct, 3) + " %"


def link_number(value) -> str:
    """A number as a link writes it, positional (never ``1e-07``): the shortest decimal that lies
    as near the value as its rounding to :data:`LINK_DIGITS` significant digits may (half a unit
    of that digit), so float noise goes (``0.1`` for ``0.09999999973330827``, as 9 digits alone
    would keep ``0.0999999997``) and the value reads back to the same 9 digits' precision."""
    value = float(value)
    if not math.isfinite(value) or value == 0.0:
        return _positional(value, LINK_DIGITS)
    allowed = 0.5 * 10.0 ** (math.floor(math.log10(abs(value))) - LINK_DIGITS + 1)
    for digits in range(1, LINK_DIGITS):
        if abs(rounded(value, digits) - value) <= allowed:
            return _positional(value, digits)
    return _positional(value, LINK_DIGITS)


def parse_number(text, what: str = "") -> float:
    """The number a typed text gives; RuleError whose words name the text otherwise. Takes what
    :func:`core.rules.decimal` takes, and engineering notation as :func:`format_number` writes it
    (``15×10⁻⁶``, or ``15x10^-6``), with a true minus sign or a hyphen."""
    raw = str(text).strip()
    plain = raw.replace(MINUS, "-")
    for sep in ("×10", "x10", "X10", "*10"):
        if sep in plain:
            mantissa, _, exponent = plain.partition(sep)
            exponent = exponent.removeprefix("^").translate(_FROM_SUPERSCRIPT)
            plain = f"{mantissa}e{exponent}" if mantissa and exponent.lstrip("+-").isdigit() else "?"
            break
    try:
        return decimal(plain, what)
    except RuleError as exc:
        if raw == "":
            raise RuleError(what, "is empty: enter a number", exc.code) from None
        raise RuleError(what, f"“{excerpt(raw)}” is not a number", exc.code) from None


def range_problem(value: float, low: float | None, high: float | None, unit: str = "",
                  quantity: str | int | None = None, *, low_open: bool = False) -> str | None:
    """What is wrong with ``value`` for a field from ``low`` to ``high`` (None: no bound; both in
    the field's unit ``unit``), in the field's unit (a clause, no full stop), or None when it is inside."""
    def txt(v):
        return format_value(v, unit, max(digits_of(quantity), 6))
    below = low is not None and (value <= low if low_open else value < low)
    above = high is not None and value > high
    if not (below or above):
        return None
    if low is not None and high is not None:
        lo = f"above {txt(low)}" if low_open else f"from {txt(low)}"
        return f"{format_value(value, unit, quantity)} is out of range: give a value {lo} to {txt(high)}"
    if below:
        return f"{format_value(value, unit, quantity)} is too small: give {'more than' if low_open else 'at least'} {txt(low)}"
    return f"{format_value(value, unit, quantity)} is too large: give at most {txt(high)}"


# the same rule for a Bokeh tick (a CustomJSTickFormatter's code: ``tick`` in, text out)
TICK_JS = """
const digits = 4;
if (!isFinite(tick)) { return ""; }
if (tick === 0) { return "0"; }
const sup = {"-": "⁻", "0": "⁰", "1": "¹", "2": "²", "3": "³", "4": "⁴", "5": "⁵", "6": "⁶", "7": "⁷", "8": "⁸", "9": "⁹"};
const plain = (v) => {
  let t = Number(v.toPrecision(digits)).toFixed(Math.max(0, digits - 1 - Math.floor(Math.log10(Math.abs(v)))));
  if (t.indexOf(".") >= 0) { t = t.replace(/0+$/, "").replace(/\\.$/, ""); }
  return t;
};
const v = Number(tick.toPrecision(digits));
const a = Math.abs(v);
if (a >= PLAIN_LOW && a < PLAIN_HIGH) { return plain(v); }
let e = 3 * Math.floor(Math.log10(a) / 3);
let m = Number((v / Math.pow(10, e)).toPrecision(digits));
if (Math.abs(m) >= 1000) { m = Number((m / 1000).toPrecision(digits)); e += 3; }
return plain(m) + "×10" + String(e).split("").map((c) => sup[c]).join("");
""".replace("PLAIN_LOW", repr(PLAIN_LOW)).replace("PLAIN_HIGH", repr(PLAIN_HIGH))
# … a negative tick with a true minus sign, as format_number writes it
TICK_JS = f"const text = (() => {{ {TICK_JS} }})();\nreturn text.replace(/^-/, \"{MINUS}\");\n"
