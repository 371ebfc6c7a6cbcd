"""The public API's docstrings are numpydoc and say the unit of every quantity.

Covered: every name in ``core.__all__`` and ``app.plots.__all__``; of a class, its own docstring
and its public methods (functions of this project whose names do not start with ``_``).
Each docstring is parsed by ``numpydoc.docscrape`` with its warnings turned into errors (an
unknown or malformed section fails), and must have:

* a one-line summary;
* ``Parameters`` naming exactly the signature's parameters (``self`` left out; ``*args`` and
  ``**kwargs`` written with their stars), each with a description and, but for the starred
  ones, a type;
* ``Returns`` (or ``Yields``) unless the return annotation is ``None``;
* ``Raises`` naming each of ValueError, DesignError and ConvergenceError that the function's own
  source raises (errors raised by the helpers it calls are documented by hand, not checked);
* a class: ``Attributes`` naming exactly its dataclass fields and public properties (inherited
  ones too); a class that is no dataclass: ``Parameters`` naming its ``__init__``'s parameters;
* a unit in every entry of ``Parameters``, ``Returns``, ``Yields`` and ``Attributes``: its type
  or description names one of :data:`UNITS` (SI, the display units of the plotting API,
  ``dimensionless``, ``count``, ``pixels``), unless the entry's type (its first alternative,
  before " or ", "," or "of") is one of :data:`UNITLESS_TYPES`: flags, strings and string
  choices, whole numbers (counts, indices), callables, and the objects of this API that carry
  their units themselves (a design, a result).

The data constants (:data:`DATA`) have no docstring of their own and are skipped.
"""

import dataclasses
import inspect
import json
import re
import warnings
from pathlib import Path

import pytest
from numpydoc.docscrape import ClassDoc, FunctionDoc

import core
from app import plots

ROOT = Path(__file__).resolve().parents[1]

# Instances, not functions or classes: their meaning is documented where they are defined.
DATA = {"PAPER_B", "TABLE_1"}

UNITS = ("m", "mm", "rad", "Pa", "kPa", "MPa", "Pa·s", "Pa·s^α", "Hz", "s", "N", "kN", "N·m",
         "N/m", "kN/mm", "N·m/rad", "kg", "kg·m²", "m³/rad", "1/m", "1/rad", "%",
         "dimensionless", "count", "pixels")
UNITLESS_TYPES = {"bool", "str", "int", "None", "callable", "Design", "Geometry", "Material",
                  "StiffnessResult", "LoopResult", "HistoryResult", "MeasuredStiffness",
                  "Diagnosis"}
CHECKED_ERRORS = ("ValueError", "DesignError", "ConvergenceError")

_ALTERNATIVES = "|".join(re.escape(u) for u in sorted(UNITS, key=len, reverse=True))
_UNIT = re.compile(rf"(?<![\w·/^'’])(?:{_ALTERNATIVES})(?![\w·/^²³])")  # a unit as a whole word


def public_names():
    core_names = [("core", n, getattr(core, n)) for n in core.__all__ if n not in DATA]
    return core_names + [("app.plots", n, getattr(plots, n)) for n in plots.__all__]


def documented_objects():
    """(id, object, owning class or None) of every function, class and public method covered."""
    out = []
    for module, name, obj in public_names():
        out.append((f"{module}.{name}", obj, None))
        if inspect.isclass(obj):
            for meth, fn in inspect.getmembers(obj, inspect.isfunction):
                if not meth.startswith("_") and fn.__module__.split(".")[0] in ("core", "app"):
                    out.append((f"{module}.{name}.{meth}", fn, obj))
    return out


OBJECTS = documented_objects()


def parsed(obj):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        if inspect.isclass(obj):
            return ClassDoc(obj, config={"show_class_members": False})
        return FunctionDoc(obj)


def signature_names(fn, method: bool) -> list[str]:
    params = list(inspect.signature(fn).parameters.values())
    if method:
        params = params[1:]  # self
    stars = {inspect.Parameter.VAR_POSITIONAL: "*", inspect.Parameter.VAR_KEYWORD: "**"}
    return [stars.get(p.kind, "") + p.name for p in params]


def properties(cls) -> list[str]:
    return sorted(n for n, v in inspect.getmembers(cls, lambda v: isinstance(v, property))
                  if not n.startswith("_"))


def first_type(type_text: str) -> str:
    first = re.split(r",| or | of ", type_text.strip())[0].strip()
    if first.startswith("{"):  # a choice of strings: {'analytic', 'time-domain'}
        return "str"
    return first.split(".")[-1]


def missing_units(entries) -> list[str]:
    return [e.name for e in entries if first_type(e.type) not in UNITLESS_TYPES
            and not _UNIT.search(f"{e.type} {' '.join(e.desc)}")]


def own_raises(obj) -> set[str]:
    source = inspect.getsource(obj)
    return {e for e in CHECKED_ERRORS if re.search(rf"\braise {e}\(", source)}


def test_the_covered_names_are_the_public_api():
    assert DATA <= set(core.__all__)
    assert all(isinstance(getattr(core, n), core.Design) for n in DATA)
    assert len(OBJECTS) > len(core.__all__)  # the classes' methods are covered too


def test_the_plotting_api_is_what_the_readme_and_the_notebook_call():
    """``app.plots.__all__`` names defined functions, and every ``plots.X(`` the README and the
    notebook show is one of them."""
    assert all(callable(getattr(plots, n)) for n in plots.__all__)
    notebook = json.loads((ROOT / "examples" / "plotting_api.ipynb").read_text(encoding="utf-8"))
    code = ["".join(c["source"]) for c in notebook["cells"] if c["cell_type"] == "code"]
    text = "\n".join([(ROOT / "README.md").read_text(encoding="utf-8"), *code])
    called = set(re.findall(r"\bplots\.(\w+)\(", text))
    assert called and called <= set(plots.__all__), sorted(called - set(plots.__all__))


@pytest.mark.parametrize("obj, owner", [(o, c) for _, o, c in OBJECTS],
                         ids=[i for i, _, _ in OBJECTS])
def test_numpydoc_with_units(obj, owner):
    doc = parsed(obj)
    assert len(doc["Summary"]) == 1 and doc["Summary"][0].strip(), "a one-line summary"
    for section in ("Parameters", "Returns", "Yields", "Attributes"):
        for e in doc[section]:
            assert e.desc and "".join(e.desc).strip(), f"{section}: {e.name} has no description"
            typed = section == "Returns" or e.name.startswith("*") or e.type
            assert typed, f"{section}: {e.name} has no type"
    if inspect.isclass(obj):
        if dataclasses.is_dataclass(obj):
            wanted = sorted({f.name for f in dataclasses.fields(obj)} | set(properties(obj)))
            assert sorted(e.name for e in doc["Attributes"]) == wanted
        elif "__init__" in vars(obj):
            assert [e.name for e in doc["Parameters"]] == signature_names(obj.__init__, method=True)
    else:
        assert [e.name for e in doc["Parameters"]] == signature_names(obj, method=owner is not None)
        if inspect.signature(obj).return_annotation not in (None, "None"):
            assert doc["Returns"] or doc["Yields"], "a Returns section"
    raised = {e.type for e in doc["Raises"]}
    assert own_raises(obj) <= raised, sorted(own_raises(obj) - raised)
    for section in ("Parameters", "Returns", "Yields", "Attributes"):
        assert missing_units(doc[section]) == [], f"{section}: no unit"
