"""The design file (docs/files.md): JSON of a :class:`core.design.Design`, read strictly and
written back, with the report of ``bushing fit`` kept aside when a fitted file has one.

Every refusal is a :class:`core.rules.DesignError` naming the key and the rule (and its code).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..design import Design
from ..parameters import (
    FILE_SHAPE,
    GEOMETRY,
    MATERIAL,
    MODES,
    OPTIONAL,
    SHAPE_FROM_FILE,
    thesis_shape_refused,
)
from ..parts import Geometry, Material, check_bulk_ratio
from ..rules import (
    BAD_CHOICE,
    BAD_TYPE,
    MISSING_KEY,
    UNKNOWN_KEY,
    DesignError,
    Words,
    decoded,
    excerpt,
    read_text,
    strict_json,
)

MAX_DESIGN_BYTES = 1_000_000  # a design file is a few hundred bytes; one of a megabyte is not one
_TOP_KEYS = ("name", "mode", "shape", "geometry", "material", "effects", "fit")
_WORDS = Words(
    too_large="design file {path!r} is too large ({size} bytes; at most {limit})",
    unreadable="cannot read design file {path!r}: {reason}",
    not_utf8="design file {path!r} is not UTF-8 text",
    too_long="too large for a design file ({size} characters; at most {limit})",
    twice="given twice (a design file names each key once)",
    bad_json="not valid JSON: {msg} at line {line} column {column}",
    too_deep="not a design file: nested too deeply",
    key_twice=True,
)


def _exact_keys(where: str, obj: Any, allowed: tuple[str, ...], required: tuple[str, ...]):
    if not isinstance(obj, Mapping):
        raise DesignError(where, f"must be an object with keys {', '.join(allowed)}", BAD_TYPE)
    prefix = f"{where}." if where else ""
    for key in obj:
        if key not in allowed:
            raise DesignError(f"{prefix}{key}", f"unknown key (allowed: {', '.join(allowed)})", UNKNOWN_KEY)
    for key in required:
        if key not in obj:
            raise DesignError(f"{prefix}{key}", "missing (required)", MISSING_KEY)


def design_from_dict(data: Any) -> Design:
    """Build a :class:`Design` from a design-file object (docs/files.md), refusing anything off."""
    _exact_keys("", data, _TOP_KEYS, ("mode", "geometry", "material"))
    _exact_keys("geometry", data["geometry"], GEOMETRY, GEOMETRY)
    _exact_keys("material", data["material"], MATERIAL + OPTIONAL, MATERIAL)
    for key in OPTIONAL:
        if key in data["material"] and data["material"][key] is None:
            raise DesignError(f"material.{key}", "must be a number (leave the key out for a nearly incompressible "
                              "rubber, K = 5000 µ)", BAD_TYPE)
    if "fit" in data and not isinstance(data["fit"], Mapping):  # a fitted file's report: kept aside
        raise DesignError("fit", "must be an object (the report of `bushing fit`)", BAD_TYPE)
    if not isinstance(data["mode"], str):
        raise DesignError("mode", f"must be one of {', '.join(MODES)}, got {excerpt(repr(data['mode']))}", BAD_CHOICE)
    shape = data.get("shape")
    if shape is not None and (not isinstance(shape, str) or shape not in SHAPE_FROM_FILE):
        raise DesignError("shape", f"must be one of {', '.join(FILE_SHAPE.values())}, got {excerpt(repr(shape))}", BAD_CHOICE)
    if shape == "thesis" and (refused := thesis_shape_refused(data["mode"])):
        raise DesignError("shape", refused, BAD_CHOICE)
    material = Material(**data["material"])
    check_bulk_ratio(material)
    return Design(
        mode=data["mode"],
        geometry=Geometry(**data["geometry"]),
        material=material,
        name=data.get("name"),
        effects=data.get("effects", {}),
        shape=None if shape is None else SHAPE_FROM_FILE[shape],
    )


def loads_design(text: str) -> Design:
    """Read a design from the text of a design file (docs/files.md).

    The text is strict JSON (no key given twice, at most :data:`MAX_DESIGN_BYTES` characters,
    not nested too deeply), then :func:`design_from_dict`'s rules, which refuse NaN and
    infinities by their key. A fitted file's ``fit`` report is read past (see
    :func:`loads_design_file`).

    Parameters
    ----------
    text : str
        The design file's JSON text; its values in SI units (m, Pa, Pa·s^α).

    Returns
    -------
    Design
        The design the text describes.

    Raises
    ------
    DesignError
        If the text is too long, no valid JSON, gives a key twice, or a key or value breaks a
        rule of the design file; the error names the key and carries the rule's code.
    """
    return loads_design_file(text)[0]


def loads_design_file(text: str) -> tuple[Design, dict | None]:
    """:func:`loads_design`, and the file's ``fit`` object (the report of ``bushing fit``) if it
    has one."""
    data = strict_json(text, MAX_DESIGN_BYTES, _WORDS, DesignError)
    return design_from_dict(data), (data.get("fit") if isinstance(data, Mapping) else None)


def read_design(path: str | Path) -> Design:
    """Read a design from a design file (docs/files.md).

    The file is read once, at most :data:`MAX_DESIGN_BYTES` bytes of UTF-8 (a byte-order mark
    is accepted), then held to :func:`loads_design`'s rules. A fitted file's ``fit`` report is
    read past (see :func:`read_design_file`).

    Parameters
    ----------
    path : str or Path
        The design file; its values in SI units (m, Pa, Pa·s^α).

    Returns
    -------
    Design
        The design the file describes.

    Raises
    ------
    DesignError
        If the file cannot be read (``unreadable``), is too large (``too_large``) or not UTF-8
        (``not_utf8``), or its content breaks a rule of :func:`loads_design`; a refusal of the
        content names the key, and the file's name in the rule.
    """
    return read_design_file(path)[0]


def read_design_file(path: str | Path) -> tuple[Design, dict | None]:
    """A design file read once (at most :data:`MAX_DESIGN_BYTES` bytes of UTF-8): the design and
    its ``fit`` object, if any; a refusal of its content names the file."""
    path = Path(path)
    text = read_text(path, MAX_DESIGN_BYTES, _WORDS, DesignError)
    try:
        return loads_design_file(text)
    except DesignError as exc:
        raise DesignError(exc.key, f"{exc.rule} (in {path.name})", exc.code) from None


def loads_design_upload(content: bytes | str) -> tuple[Design, dict | None]:
    """:func:`read_design_file` for a file's content already read (an upload): at most
    :data:`MAX_DESIGN_BYTES` bytes of UTF-8 (a byte-order mark dropped), then
    :func:`loads_design_file`'s rules; the design and its ``fit`` object, if any."""
    return loads_design_file(decoded(content, MAX_DESIGN_BYTES, _WORDS, DesignError))


def dumps_design(design: Design) -> str:
    """Write a design as the text of a design file (docs/files.md).

    :func:`loads_design` reads the text back to an equal design.

    Parameters
    ----------
    design : Design
        The design to write.

    Returns
    -------
    str
        JSON of :meth:`Design.to_dict`, indented by two spaces and ending in a newline; the
        values in SI units (m, Pa, Pa·s^α).
    """
    return json.dumps(design.to_dict(), indent=2) + "\n"


def write_design(design: Design, path: str | Path) -> None:
    """Write a design to a design file (docs/files.md), UTF-8, as :func:`dumps_design` words it.

    :func:`read_design` reads the file back to an equal design; an existing file is replaced.

    Parameters
    ----------
    design : Design
        The design to write.
    path : str or Path
        The file to write.

    Raises
    ------
    OSError
        If the file cannot be written.
    """
    Path(path).write_text(dumps_design(design), encoding="utf-8")
