"""The input rules, once: a finite number, a positive number, the decimal text of a CSV cell or a
command-line number, strict JSON, and a small UTF-8 file within a size limit; and the errors
that carry which rule an input broke.

Every refusal of the core's inputs (a design, a measured-data file, a tolerance file, a targets
file) is a :class:`RuleError`: ``key`` names where (``geometry.outer_radius``, ``line 6``,
``targets[0].frequency_hz``; empty for the whole input), ``rule`` says what in plain words, and
``code`` says which rule, for a program (the app words its messages by it). The codes:

==================== ==========================================================================
code                 the input
==================== ==========================================================================
``not_a_number``     is not a number: a JSON value that is no integer or float (text, true,
                     null, a list), or a text that is no plain ASCII decimal (``1_000``, ``0x10``)
``not_finite``       is NaN or an infinity (``NaN``, ``inf``); a fit report's standard error or
                     correlation that the fit does not determine
``overflow``         is a number beyond the largest float (an integer past 1e308, ``1e999``)
``not_positive``     is zero or negative where a positive number is needed
``negative``         is negative where zero or more is needed (an effect's parameter, a tolerance)
``out_of_range``     lies outside a stated range (sizes 1 µm – 1 km, moduli at most 1 TPa, ε½,
                     measured frequencies and |K|, a phase, counts, percentiles, a tolerance
                     that takes a part, or a band's sample, outside what the model takes, a
                     drive beyond the strain the model takes)
``outer_not_larger`` makes the outer radius b no larger than the inner radius a (b ≤ a)
``order_range``      is a fractional order α outside (0, 1]
``unknown_key``      is a key, column, parameter or effect the format does not know
``missing_key``      leaves out a required key, column or cell
``duplicate_key``    gives a key twice (in JSON, or in two forms: relative and absolute)
``bad_choice``       is not one of the words allowed (a mode, shape, distribution, the mode
                     after an effect's @), or a combination the rules refuse (conical with the
                     long shape, one mode as a ratio, a rubber effect tied to a mode, a branch
                     of the material model given as an effect)
``bad_type``         is the wrong kind of value: an object, list, text or true/false expected
``conflict``         says two things that exclude each other (two forms of the stiffness, min
                     above max, mode and ratio together)
``empty``            holds nothing to use: an empty file, a header without rows, nothing varied
``bad_json``         is not valid JSON, or nested too deeply
``bad_table``        is not a CSV table (a row longer than the header)
``bad_signal``       is a loop that is no steady harmonic test (time not increasing, a channel
                     that never moves, under one period or 16 rows, not a sine)
``too_large``        is over its size limit (a file's bytes, a text's characters, a table's
                     rows, a band's evaluations)
``not_utf8``         is a file that is not UTF-8 text
``unreadable``       is a file that cannot be read (missing, a folder, no permission)
``invalid``          breaks a rule not listed (an error made outside the core's readers)
==================== ==========================================================================
"""

from __future__ import annotations

import json
import math
import re
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

NOT_A_NUMBER = "not_a_number"
NOT_FINITE = "not_finite"
OVERFLOW = "overflow"
NOT_POSITIVE = "not_positive"
NEGATIVE = "negative"
OUT_OF_RANGE = "out_of_range"
OUTER_NOT_LARGER = "outer_not_larger"
ORDER_RANGE = "order_range"
UNKNOWN_KEY = "unknown_key"
MISSING_KEY = "missing_key"
DUPLICATE_KEY = "duplicate_key"
BAD_CHOICE = "bad_choice"
BAD_TYPE = "bad_type"
CONFLICT = "conflict"
EMPTY = "empty"
BAD_JSON = "bad_json"
BAD_TABLE = "bad_table"
BAD_SIGNAL = "bad_signal"
TOO_LARGE = "too_large"
NOT_UTF8 = "not_utf8"
UNREADABLE = "unreadable"
INVALID = "invalid"
CODES = (NOT_A_NUMBER, NOT_FINITE, OVERFLOW, NOT_POSITIVE, NEGATIVE, OUT_OF_RANGE, OUTER_NOT_LARGER,
         ORDER_RANGE, UNKNOWN_KEY, MISSING_KEY, DUPLICATE_KEY, BAD_CHOICE, BAD_TYPE, CONFLICT, EMPTY,
         BAD_JSON, BAD_TABLE, BAD_SIGNAL, TOO_LARGE, NOT_UTF8, UNREADABLE, INVALID)

# a number written as text (a CSV cell, a command-line number): plain ASCII decimal notation; no
# 1_000, no non-ASCII digits, no hex, no nan or inf (all of which Python's float() forgives)
DECIMAL = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
WHOLE = re.compile(r"[+-]?\d+", re.ASCII)  # a whole number's text: ASCII digits, as DECIMAL's
_NOT_FINITE_WORDS = ("nan", "inf", "infinity")
# the characters of an input's value a message quotes (a cell, a column name, a typed text):
# enough to recognise it, never the megabytes a hostile file may hold
EXCERPT_CHARS = 40
KEY_CHARS = 80  # a key (dotted path) as a message names it: longer ones are cut


class RuleError(ValueError):
    """An input that breaks a rule: where, what in plain words, and which rule.

    The message is ``key: rule``, or ``rule`` alone without a key; given one argument, that is
    the whole message (no key).

    Parameters
    ----------
    key : str
        Where the input breaks the rule (``geometry.outer_radius``, ``line 6``); "" for the
        whole input. Given alone, it is the rule and the key is "".
    rule : str or None, optional
        What is wrong, in plain words.
    code : str, optional
        Which rule, one of :data:`CODES` (``invalid`` by default).

    Attributes
    ----------
    key : str
        Where, as given ("" for the whole input).
    rule : str
        What, in plain words.
    code : str
        Which rule, one of :data:`CODES`, for a program to word its own message by.

    Raises
    ------
    ValueError
        If ``code`` is not one of :data:`CODES`.
    """

    def __init__(self, key: str, rule: str | None = None, code: str = INVALID):
        if rule is None:
            key, rule = "", key
        if code not in CODES:
            raise ValueError(f"unknown rule code {code!r}")
        self.key, self.rule, self.code = key, rule, code
        super().__init__(f"{excerpt(key, KEY_CHARS)}: {rule}" if key else rule)  # a file's key may be long


class DesignError(RuleError):
    """A design value or a design file that breaks a rule, naming the offending key.

    Raised by :class:`core.design.Design` and its parts for a value off its rule, and by the
    readers of :mod:`core.io.design_file` for a file that is no design file. The message is
    ``key: rule`` (``rule`` alone for the whole file), as of :class:`RuleError`.

    Parameters
    ----------
    key : str
        The design file's key that breaks the rule, dotted (``geometry.outer_radius``,
        ``effects.inertia.mass``); "" for the whole file (too large, not UTF-8, not JSON).
    rule : str or None, optional
        What is wrong, in plain words (a value's unit is the design file's, SI).
    code : str, optional
        Which rule, one of :data:`CODES` (``outer_not_larger``, ``order_range``, ``bad_json``…).

    Attributes
    ----------
    key : str
        The offending key, dotted; "" for the whole file.
    rule : str
        What is wrong, in plain words.
    code : str
        Which rule, one of :data:`CODES`.
    """


def excerpt(value: Any, limit: int = EXCERPT_CHARS) -> str:
    """An untrusted value as a message may quote it: its text, cut to ``limit`` characters and
    ``…`` when longer, so that one message line stays short whatever the input holds."""
    text = str(value)
    return text if len(text) <= limit else text[:limit] + "…"


# ---- numbers ----------------------------------------------------------------------------------


def number(key: str, value: Any, error: type[RuleError] = DesignError) -> float:
    """``value`` (a JSON value) as a finite float, or ``error`` naming ``key``: not an int or a
    float (a bool is no number), NaN or an infinity, an integer too large for a float. A
    design's rule (:class:`DesignError`) unless ``error`` says otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise error(key, f"must be a number, got {excerpt(repr(value))}", NOT_A_NUMBER)
    try:
        finite = float(value)
    except OverflowError:  # an integer too large for a float
        raise error(key, "must be a finite number, got an integer too large for a float", OVERFLOW) from None
    if not math.isfinite(finite):
        raise error(key, f"must be a finite number, got {excerpt(repr(value))}", NOT_FINITE)
    return finite


def positive(key: str, value: Any, error: type[RuleError] = DesignError) -> float:
    """:func:`number`, and above zero."""
    finite = number(key, value, error)
    if finite <= 0.0:
        raise error(key, f"must be positive, got {finite!r}", NOT_POSITIVE)
    return finite


def within(key: str, value: Any, low: float, high: float, unit: str = "",
           error: type[RuleError] = DesignError) -> float:
    """:func:`positive`, and from ``low`` to ``high`` inclusive (``unit`` named in the words);
    else ``error`` with the code ``out_of_range``."""
    finite = positive(key, value, error)
    if not low <= finite <= high:
        raise error(key, f"must lie between {low:g} and {high:g}{' ' + unit if unit else ''}, got {finite!r}",
                    OUT_OF_RANGE)
    return finite


def is_number(value: Any) -> bool:
    """Whether :func:`number` takes ``value``."""
    try:
        number("", value, RuleError)
    except RuleError:
        return False
    return True


def whole_number(value: Any, low: int, high: int) -> str | None:
    """None if ``value`` is a whole number (an int, not a bool) from ``low`` to ``high``; else
    the code of the rule it breaks: ``not_a_number`` or ``out_of_range``."""
    if isinstance(value, bool) or not isinstance(value, int):
        return NOT_A_NUMBER
    return None if low <= value <= high else OUT_OF_RANGE


def decimal(text: str, key: str = "", error: type[RuleError] = RuleError) -> float:
    """The number a text (a CSV cell, a command-line number) writes, surrounding blanks aside,
    as a finite float; else ``error`` with the code: ``missing_key`` (blank), ``not_finite``
    (nan, inf, infinity), ``not_a_number`` (not :data:`DECIMAL`), ``overflow`` (beyond a float,
    ``1e999``)."""
    text = str(text).strip()
    if text == "":
        raise error(key, "is missing", MISSING_KEY)
    if text.lower().lstrip("+-") in _NOT_FINITE_WORDS:
        raise error(key, f"is not finite ({excerpt(text)!r})", NOT_FINITE)
    if not DECIMAL.fullmatch(text):
        raise error(key, f"is not a number ({excerpt(text)!r})", NOT_A_NUMBER)
    value = float(text)
    if not math.isfinite(value):
        raise error(key, f"is too large for a number ({excerpt(text)!r})", OVERFLOW)
    return value


# ---- files and JSON ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Words:
    """How one kind of input words the refusals of :func:`read_text`, :func:`decoded` and
    :func:`strict_json`: ``str.format`` templates, each with the fields named here.
    ``key_twice``: a key given twice becomes the error's key (else it is named in the words)."""

    too_large: str = ""  # the file (bytes): {path} {size} {limit}
    unreadable: str = ""  # {path} {reason}
    not_utf8: str = ""  # {path}
    too_long: str = ""  # the text (characters): {size} {limit}
    twice: str = ""  # {key}
    bad_json: str = ""  # {msg} {line} {column}
    too_deep: str = ""
    key_twice: bool = False


def input_file_words(name: str) -> Words:
    """The words of a JSON input file called ``the {name} file`` (a tolerance or targets file)."""
    what = f"the {name} file"
    return Words(too_large=what + " {path!r} is larger than {limit} bytes",
                 unreadable="cannot read " + what + " {path!r}: {reason}",
                 not_utf8=what + " {path!r} is not UTF-8 text",
                 too_long=what + " is larger than {limit} characters ({size})",
                 twice=what + ": {key} given twice (name each key once)",
                 bad_json=what + " is not valid JSON: {msg} at line {line} column {column}",
                 too_deep=what + " is nested too deeply")


def read_text(path: str | Path, limit: int, words: Words, error: type[RuleError]) -> str:
    """The text of a file of at most ``limit`` bytes, UTF-8 (a byte-order mark, as spreadsheets
    write, is not part of the text); else ``error`` (``too_large``, ``unreadable``,
    ``not_utf8``), worded by ``words`` with ``path`` as given."""
    shown = str(path)
    try:
        size = Path(path).stat().st_size
        if size > limit:
            raise error("", words.too_large.format(path=shown, size=size, limit=limit), TOO_LARGE)
        return Path(path).read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise error("", words.unreadable.format(path=shown, reason=exc.strerror), UNREADABLE) from None
    except UnicodeDecodeError:
        raise error("", words.not_utf8.format(path=shown), NOT_UTF8) from None


def decoded(content: str | bytes, limit: int, words: Words, error: type[RuleError]) -> str:
    """:func:`read_text`'s rules for content already read (an upload): bytes of at most
    ``limit``, UTF-8, a byte-order mark dropped; text passes as it is."""
    if isinstance(content, str):
        return content
    if len(content) > limit:
        raise error("", words.too_large.format(path="", size=len(content), limit=limit), TOO_LARGE)
    try:
        return content.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise error("", words.not_utf8.format(path=""), NOT_UTF8) from None


def strict_json(text: str | bytes, limit: int, words: Words, error: type[RuleError]) -> Any:
    """The JSON value of an input of at most ``limit`` characters, no key of an object given
    twice, not nested too deeply; else ``error`` (``too_large``, ``duplicate_key``,
    ``bad_json``) worded by ``words``. NaN and Infinity are read as floats: the number rule of
    the key they stand at refuses them, naming it."""
    if len(text) > limit:
        raise error("", words.too_long.format(size=len(text), limit=limit), TOO_LARGE)

    def unique(pairs):
        counts = Counter(k for k, _ in pairs)  # one pass: an object of 100 000 keys stays quick
        repeated = sorted(k for k, n in counts.items() if n > 1)
        if repeated:
            said = words.twice.format(key=repeated[0])
            raise error(repeated[0], said, DUPLICATE_KEY) if words.key_twice else error("", said, DUPLICATE_KEY)
        return dict(pairs)

    try:
        return json.loads(text, object_pairs_hook=unique)
    except json.JSONDecodeError as exc:
        raise error("", words.bad_json.format(msg=exc.msg, line=exc.lineno, column=exc.colno),
                    BAD_JSON) from None
    except RecursionError:
        raise error("", words.too_deep, BAD_JSON) from None
