"""The tolerance file (docs/files.md): a design's tolerances as
:class:`core.whatif.tolerance.Tolerances`, read strictly.

Every refusal is a :class:`core.whatif.tolerance.ToleranceError` naming the key and the rule
(and its code, :mod:`core.rules`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..rules import (
    BAD_TYPE,
    DECIMAL,
    EMPTY,
    NOT_A_NUMBER,
    UNKNOWN_KEY,
    input_file_words,
    number,
    read_text,
    strict_json,
)
from ..whatif.tolerance import PERCENTILES, SAMPLES, FitCovariance, ToleranceError, Tolerances

MAX_FILE_BYTES = 100_000
_FILE_KEYS = ("tolerances", "distribution", "samples", "seed", "percentiles", "fit_covariance")
_WORDS = input_file_words("tolerance")


def _percent(text: str) -> float | None:
    """``"10%"`` (blanks around its parts allowed) as 0.1: an unsigned decimal (the rule of
    :data:`core.rules.DECIMAL`) and a per cent sign; None for any other text."""
    body = text.strip()
    if not body.endswith("%"):
        return None
    body = body[:-1].rstrip()
    if body[:1] in "+-" or not DECIMAL.fullmatch(body):
        return None
    return float(body) / 100.0


def _spread(name: str, value: Any) -> tuple[str, float]:
    """"10%" → relative 0.1; a number → absolute (SI)."""
    key = f"tolerances.{name}"
    words = f"give a percentage such as \"10%\" or a number in SI units, got {str(value)[:40]}"
    if isinstance(value, str):
        fraction = _percent(value)
        if fraction is None:
            raise ToleranceError(key, words, NOT_A_NUMBER)
        return "relative", fraction
    try:
        return "absolute", number(key, value, ToleranceError)
    except ToleranceError as exc:
        raise ToleranceError(key, words, exc.code) from None


def tolerances_from_dict(data: Any, fit_report: Any = None) -> Tolerances:
    """The tolerance file's object (``docs/files.md``); ``fit_report`` the design file's ``fit``
    object, used when ``fit_covariance`` is true."""
    if not isinstance(data, Mapping):
        raise ToleranceError("", "the tolerance file must hold a JSON object", BAD_TYPE)
    unknown = [k for k in data if k not in _FILE_KEYS]
    if unknown:
        raise ToleranceError(unknown[0], f"unknown key (allowed: {', '.join(_FILE_KEYS)})", UNKNOWN_KEY)
    spreads = data.get("tolerances", {})
    if not isinstance(spreads, Mapping):
        raise ToleranceError("tolerances", "must be an object of parameter → tolerance", BAD_TYPE)
    relative, absolute = {}, {}
    for name, value in spreads.items():
        kind, h = _spread(str(name), value)
        (relative if kind == "relative" else absolute)[str(name)] = h
    use_fit = data.get("fit_covariance", False)
    if not isinstance(use_fit, bool):
        raise ToleranceError("fit_covariance", f"true or false, got {str(use_fit)[:40]}", BAD_TYPE)
    percentiles = data.get("percentiles", list(PERCENTILES))
    if not isinstance(percentiles, list):
        raise ToleranceError("percentiles", f"a list of numbers from 0 to 100, got {str(percentiles)[:60]}", BAD_TYPE)
    tol = Tolerances(relative, absolute, data.get("distribution", "uniform"), data.get("samples", SAMPLES),
                     data.get("seed", 0), tuple(percentiles),
                     FitCovariance.from_report(fit_report) if use_fit else None)
    if not tol.varied:
        raise ToleranceError("tolerances", "nothing varies (give at least one tolerance above 0, or fit_covariance)",
                             EMPTY)
    return tol


def loads_tolerances(text: str | bytes, fit_report: Any = None) -> Tolerances:
    """The tolerances of a tolerance file's text (strict JSON of at most
    :data:`MAX_FILE_BYTES` characters), with the design file's ``fit_report`` for
    ``fit_covariance``."""
    return tolerances_from_dict(strict_json(text, MAX_FILE_BYTES, _WORDS, ToleranceError), fit_report)


def read_tolerances(path: str | Path, fit_report: Any = None) -> Tolerances:
    """:func:`loads_tolerances` of a file of at most :data:`MAX_FILE_BYTES` bytes of UTF-8."""
    return loads_tolerances(read_text(path, MAX_FILE_BYTES, _WORDS, ToleranceError), fit_report)
