"""The targets file (docs/files.md): a start design, its targets and the limits of the search,
read strictly into a :class:`core.whatif.target.Problem`.

Every refusal is a :class:`core.whatif.target.TargetError` naming the key and the rule (and
its code, :mod:`core.rules`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..bushing import stiffness_points
from ..design import Design
from ..parameters import FREQUENCY_HZ, GEOMETRY, MATERIAL, MODE, MODES
from ..parts import SIZE_RANGE
from ..registry import parameter
from ..rules import (
    BAD_CHOICE,
    BAD_TYPE,
    CONFLICT,
    MISSING_KEY,
    NOT_POSITIVE,
    OUT_OF_RANGE,
    UNKNOWN_KEY,
    DesignError,
    RuleError,
    input_file_words,
    positive,
    read_text,
    strict_json,
    whole_number,
)
from ..whatif.target import SEARCHED, Problem, Target, TargetError
from .design_file import design_from_dict

QUANTITIES = ("magnitude", "loss_factor")
GEOMETRY_LIMITS = (*GEOMETRY, "thickness")  # a, b, L and the rubber's thickness b − a
DEFAULT_LIMITS = {"inner_radius": (1e-3, 1.0), "outer_radius": (2e-3, 1.0), "length": (1e-3, 1.0),
                  "thickness": (1e-3, 1.0)}
TOLERANCE = 0.01  # a numeric target is met within ±1 % unless the file says otherwise
MAX_TARGETS, MAX_SOLUTIONS = 20, 10
MAX_FILE_BYTES = 1_000_000
_FILE_KEYS = ("design", "targets", "tolerance", "limits", "free_material", "fixed", "solutions")
_WORDS = input_file_words("targets")


def _number(key: str, value: Any) -> float:
    """``value`` as a positive finite float (:func:`core.rules.positive`), or a TargetError
    naming ``key`` in the targets file's words."""
    try:
        return positive(key, value, RuleError)
    except RuleError as exc:
        if exc.code == NOT_POSITIVE:
            raise TargetError(key, f"must be positive, got {value!r}", exc.code) from None
        raise TargetError(key, f"must be a finite number, got {str(value)[:40]}", exc.code) from None


def _range(key: str, spec: Any) -> tuple[float | None, float | None]:
    if not isinstance(spec, Mapping) or not spec or any(k not in ("min", "max") for k in spec):
        raise TargetError(key, "give a number or an object with min and/or max", BAD_TYPE)
    low = _number(f"{key}.min", spec["min"]) if "min" in spec else None
    high = _number(f"{key}.max", spec["max"]) if "max" in spec else None
    if low is not None and high is not None and low > high:
        raise TargetError(key, f"min {low:g} is above max {high:g}", CONFLICT)
    return low, high


def _ranges(key: str, spec: Any, known: tuple[str, ...]) -> dict[str, tuple[float | None, float | None]]:
    """An object of name → {min, max}, its names from ``known``."""
    if not isinstance(spec, Mapping):
        raise TargetError(key, "an object of name → {min, max}", BAD_TYPE)
    unknown = [n for n in spec if n not in known]
    if unknown:
        raise TargetError(f"{key}.{unknown[0]}", f"unknown (known: {', '.join(known)})", UNKNOWN_KEY)
    return {name: _range(f"{key}.{name}", r) for name, r in spec.items()}


def _target(i: int, spec: Any, tolerance: float, start: Design) -> Target:
    key = f"targets[{i}]"
    if not isinstance(spec, Mapping):
        raise TargetError(key, "must be an object", BAD_TYPE)
    allowed = ("mode", "ratio", "frequency_hz", "amplitude", "amplitudes", "magnitude", "loss_factor", "tolerance")
    unknown = [k for k in spec if k not in allowed]
    if unknown:
        raise TargetError(f"{key}.{unknown[0]}", f"unknown key (allowed: {', '.join(allowed)})", UNKNOWN_KEY)
    if ("mode" in spec) == ("ratio" in spec):
        raise TargetError(key, "give either mode (one direction) or ratio (two)", CONFLICT)
    modes = [spec["mode"]] if "mode" in spec else spec["ratio"]
    if not isinstance(modes, list) or len(modes) != (1 if "mode" in spec else 2) or any(m not in MODES for m in modes):
        raise TargetError(key, f"mode is one of {', '.join(MODES)}; ratio is a list of two of them", BAD_CHOICE)
    if "ratio" in spec and modes[0] == modes[1]:
        raise TargetError(f"{key}.ratio", "two different modes", BAD_CHOICE)
    f = _number(f"{key}.frequency_hz", spec.get("frequency_hz"))
    if not FREQUENCY_HZ[0] <= f <= FREQUENCY_HZ[1]:
        raise TargetError(f"{key}.frequency_hz", f"from {FREQUENCY_HZ[0]:g} to {FREQUENCY_HZ[1]:g} Hz, got {f:g}",
                          OUT_OF_RANGE)
    if "amplitudes" in spec:
        amps = spec["amplitudes"]
        if not isinstance(amps, list) or len(amps) != len(modes):
            raise TargetError(f"{key}.amplitudes", f"one amplitude per mode ({len(modes)})", BAD_TYPE)
        amps = [_number(f"{key}.amplitudes[{j}]", a) for j, a in enumerate(amps)]
    else:
        amps = [_number(f"{key}.amplitude", spec.get("amplitude"))] * len(modes)
    if len(modes) == 2 and "amplitudes" not in spec and MODE[modes[0]].amplitude.si != MODE[modes[1]].amplitude.si:
        raise TargetError(key, f"{modes[0]} and {modes[1]} are driven in different units: give amplitudes, one per "
                          "mode", MISSING_KEY)
    quantities = [q for q in QUANTITIES if q in spec]
    if len(quantities) != 1 or (len(modes) == 2 and quantities != ["magnitude"]):
        code = MISSING_KEY if not quantities else CONFLICT if len(quantities) > 1 else BAD_CHOICE
        raise TargetError(key, "give one of magnitude or loss_factor (a ratio takes magnitude)", code)
    quantity = quantities[0]
    tol = _number(f"{key}.tolerance", spec["tolerance"]) if "tolerance" in spec else tolerance
    value = spec[quantity]
    if isinstance(value, Mapping):
        low, high = _range(f"{key}.{quantity}", value)
        number = None
    else:
        number = _number(f"{key}.{quantity}", value)
        low, high = number * (1 - tol), number * (1 + tol)
    for m, x in zip(modes, amps):
        try:
            stiffness_points(start.in_mode(m), f, x)
        except ValueError as exc:
            raise TargetError(key, str(exc), OUT_OF_RANGE) from None
    return Target(tuple(modes), quantity, f, tuple(amps), low, high, number)


def _start(spec: Any) -> Design:
    """The start design (a design-file object); its refusal named under ``design``."""
    try:
        return design_from_dict(spec)
    except DesignError as exc:
        if exc.key:
            raise TargetError(f"design.{exc.key}", exc.rule, exc.code) from None
        raise TargetError("", f"design.{exc.rule}", exc.code) from None


def problem_from_dict(data: Any) -> Problem:
    """The targets file's object (``docs/files.md``)."""
    if not isinstance(data, Mapping):
        raise TargetError("", "the targets file must hold a JSON object", BAD_TYPE)
    unknown = [k for k in data if k not in _FILE_KEYS]
    if unknown:
        raise TargetError(unknown[0], f"unknown key (allowed: {', '.join(_FILE_KEYS)})", UNKNOWN_KEY)
    if "design" not in data:
        raise TargetError("design", "missing (the starting design, a design-file object)", MISSING_KEY)
    start = _start(data["design"])
    tolerance = _number("tolerance", data.get("tolerance", TOLERANCE))
    if tolerance >= 1:
        raise TargetError("tolerance", f"a fraction below 1, got {tolerance:g}", OUT_OF_RANGE)
    targets = data.get("targets")
    if not isinstance(targets, list) or not 1 <= len(targets) <= MAX_TARGETS:
        raise TargetError("targets", f"a list of 1 to {MAX_TARGETS} targets",
                          OUT_OF_RANGE if isinstance(targets, list) else BAD_TYPE)
    parsed = tuple(_target(i, t, tolerance, start) for i, t in enumerate(targets))
    limits = dict(DEFAULT_LIMITS)
    for name, (low, high) in _ranges("limits", data.get("limits", {}), GEOMETRY_LIMITS).items():
        low = DEFAULT_LIMITS[name][0] if low is None else low
        high = DEFAULT_LIMITS[name][1] if high is None else high
        if not SIZE_RANGE[0] <= low < high <= SIZE_RANGE[1]:
            raise TargetError(f"limits.{name}", f"min < max, both within {SIZE_RANGE[0]:g}–{SIZE_RANGE[1]:g} m",
                              OUT_OF_RANGE)
        limits[name] = (low, high)
    fixed = data.get("fixed", [])
    if not isinstance(fixed, list) or any(n not in SEARCHED for n in fixed):
        raise TargetError("fixed", f"a list of {', '.join(SEARCHED)} (held at the start design's)",
                          BAD_CHOICE)
    free = {}
    for name, (low, high) in _ranges("free_material", data.get("free_material", {}), MATERIAL).items():
        p_lo, p_hi = parameter(name).bounds  # within the fitting range (α's is (0, 1])
        low, high = max(low or p_lo, p_lo, 1e-30), min(high or p_hi, p_hi)
        if not low < high:
            raise TargetError(f"free_material.{name}", "an empty range", OUT_OF_RANGE)
        free[name] = (low, high)
    n = data.get("solutions", 3)
    if code := whole_number(n, 1, MAX_SOLUTIONS):
        raise TargetError("solutions", f"a whole number from 1 to {MAX_SOLUTIONS}", code)
    # the fixed variables must lie within their limits
    values = Problem(start, parsed, limits, free, tuple(fixed)).values(start)
    for name in fixed:
        lo, hi = limits[name]
        if not lo <= values[name] <= hi:
            raise TargetError("fixed", f"{name} of the start design ({values[name]:.4g} m) is outside its limits",
                              OUT_OF_RANGE)
    return Problem(start, parsed, limits, free, tuple(fixed), n)


def loads_problem(text: str | bytes) -> Problem:
    """The problem of a targets file's text (strict JSON of at most :data:`MAX_FILE_BYTES`
    characters)."""
    return problem_from_dict(strict_json(text, MAX_FILE_BYTES, _WORDS, TargetError))


def read_problem(path: str | Path) -> Problem:
    """:func:`loads_problem` of a file of at most :data:`MAX_FILE_BYTES` bytes of UTF-8."""
    return loads_problem(read_text(path, MAX_FILE_BYTES, _WORDS, TargetError))
