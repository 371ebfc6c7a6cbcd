"""The repository stands on its own: docs/ say what the code does, and nothing points outside."""

import importlib
import inspect
import re
import subprocess
import sys
from pathlib import Path

from cli.main import build_parser
from core.effects import EFFECTS

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NUMBER = re.compile(r"(?<![\w.])\d+(?:\.\d+)?(?:e[-+]?\d+)?")
DOC_FILES = [*sorted(DOCS.glob("*.md")), ROOT / "README.md", ROOT / "examples" / "README.md"]
CODE_FILES = [p for package in ("core", "cli", "app") for p in sorted(ROOT.joinpath(package).rglob("*.py"))]
# a dotted name of the project in backticks (docs) or in a Sphinx role (docstrings)
DOTTED = re.compile(r"`~?((?:core|app|cli)(?:\.\w+)+)(?:\(\))?`")
# an equation citation: "eq 14", "eqs 16–18", "eqs 14, 15", "eqs 17 and 18"
CITATION = re.compile(r"\beqs? (\d+(?:\s*[–-]\s*\d+)?(?:\s*(?:,|and)\s*\d+(?:\s*[–-]\s*\d+)?)*)")


def tracked_text_files():
    names = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    for name in names:
        path = ROOT / name
        if path.suffix in {".py", ".md", ".toml", ".ipynb", ".txt", ".json", ".cfg"} or path.name in {"Dockerfile", "run"}:
            yield path


def test_nothing_refers_to_a_file_outside_the_repository():
    outside = re.compile(r"\.\./shared|FORMATS\.md|MODEL\.md|thesis-text")
    found = [f"{p.relative_to(ROOT)}:{n}" for p in tracked_text_files() if p.name != "test_docs.py"
             for n, line in enumerate(p.read_text(encoding="utf-8", errors="replace").splitlines(), 1)
             if outside.search(line)]
    assert found == []


def test_every_effect_is_documented_with_its_parameters_and_fitting_ranges():
    text = (DOCS / "model.md").read_text(encoding="utf-8")
    rows = {m.group(1): m.group(0) for m in re.finditer(r"^\| `(\w+)` \|.*$", text, re.MULTILINE)}
    for eid, effect in EFFECTS.items():
        assert eid in rows, eid
        numbers = {float(v) for v in NUMBER.findall(rows[eid])}
        for p in effect.parameters:
            assert f"`{p.name}`" in rows[eid], (eid, p.name)
            assert {float(p.bounds[0]), float(p.bounds[1])} <= numbers, (eid, p.name, p.bounds)


def test_every_command_and_option_of_the_command_line_is_documented():
    text = (DOCS / "files.md").read_text(encoding="utf-8")
    sub = next(a for a in build_parser()._actions if a.__class__.__name__ == "_SubParsersAction")
    for name, parser in sub.choices.items():
        assert f"`bushing {name}" in text, name
        for action in parser._actions:
            for option in action.option_strings:
                if option not in ("-h", "--help"):
                    assert option in text, (name, option)


def cited_equations(text: str) -> set[int]:
    """The equation numbers ``text`` cites ("eq 14", "eqs 16–18", "eqs 17, 18")."""
    numbers: set[int] = set()
    for match in CITATION.finditer(text):
        for part in re.split(r"\s*(?:,|and)\s*", match.group(1)):
            bounds = [int(s) for s in re.split(r"\s*[–-]\s*", part.strip())]
            numbers.update(range(bounds[0], bounds[-1] + 1))
    return numbers


def test_citations_are_read_as_the_numbers_they_name():
    assert cited_equations("eq 14 torsion, eq 15 axial") == {14, 15}
    assert cited_equations("(eqs 16–18)") == {16, 17, 18}
    assert cited_equations("eqs 17, 18 and 10") == {10, 17, 18}
    assert cited_equations("no equation here, 12 sheep") == set()


def test_every_thesis_equation_the_code_cites_is_in_the_model_page():
    cited = set()
    for path in CODE_FILES:
        cited |= cited_equations(path.read_text(encoding="utf-8"))
    text = (DOCS / "model.md").read_text(encoding="utf-8")
    documented = set()
    for match in re.finditer(r"\beqs? (\d+)(?:[–-](\d+))?|^\| (\d+)(?:[–-](\d+))? \|", text, re.MULTILINE):
        lo = int(match.group(1) or match.group(3))
        hi = int(match.group(2) or match.group(4) or lo)
        documented.update(range(lo, hi + 1))
    assert cited and cited <= documented, sorted(cited - documented)


def test_the_core_never_imports_the_app():
    """The arrow points one way: app/ uses core/, never the other way round."""
    found = [f"{p.name}: {line.strip()}" for p in ROOT.joinpath("core").rglob("*.py")
             for line in p.read_text(encoding="utf-8").splitlines()
             if re.match(r"\s*(from app\b|import app\b)", line)]
    assert found == []


def resolve(dotted: str):
    """The object a dotted name of the project names: its longest importable module, then
    attributes; AttributeError or ImportError if it names nothing."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for attr in parts[cut:]:
            obj = getattr(obj, attr)
        return obj
    raise ImportError(dotted)


def cited_names() -> dict[str, list[str]]:
    """Every dotted name the docs and the code's docstrings cite → where."""
    found: dict[str, list[str]] = {}
    for path in [*DOC_FILES, *CODE_FILES]:
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for name in DOTTED.findall(line):
                found.setdefault(name, []).append(f"{path.relative_to(ROOT)}:{n}")
    return found


def test_every_dotted_name_the_docs_cite_imports():
    names = cited_names()
    missing = {}
    for name, where in names.items():
        try:
            resolve(name)
        except (ImportError, AttributeError):
            missing[name] = where
    assert len(names) > 30 and missing == {}


def test_a_dotted_name_that_names_nothing_is_found():
    assert resolve("core.material.equivalent_modulus") is not None
    for wrong in ("core.material.no_such_function", "core.no_such_module.f"):
        try:
            resolve(wrong)
        except (ImportError, AttributeError):
            continue
        raise AssertionError(wrong)


def equation_map() -> list[tuple[set[int], list[str], str]]:
    """docs/model.md's equation rows: (the equations, the dotted names of the code cell, the row)."""
    rows = []
    for line in (DOCS / "model.md").read_text(encoding="utf-8").splitlines():
        match = re.match(r"^\| (\d+)(?:[–-](\d+))? \|.*\| ([^|]*) \|$", line)
        if match:
            lo = int(match.group(1))
            rows.append((set(range(lo, int(match.group(2) or lo) + 1)), DOTTED.findall(match.group(3)), line))
    return rows


def test_every_equation_of_the_map_names_the_function_whose_line_carries_its_number():
    """Each row of the equation map names, fully dotted, the functions that hold the formula, and
    their source cites the row's equation numbers; an equation the code does not compute says so."""
    rows = equation_map()
    assert {1, 3, 5, 6, 7, 10, 11, 14, 15, 16, 17, 18} <= set().union(*(eqs for eqs, _, _ in rows))
    wrong = []
    for eqs, names, row in rows:
        if not names:
            if "not computed" not in row:
                wrong.append(f"no function named: {row}")
            continue
        cited = set()
        for name in names:
            obj = resolve(name)
            cited |= cited_equations(inspect.getsource(obj.fget if isinstance(obj, property) else obj))
        if not eqs <= cited:
            wrong.append(f"eqs {sorted(eqs - cited)} not cited in {names}")
    assert wrong == []


def test_the_readme_layout_is_the_code_s():
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        import layout
    finally:
        sys.path.remove(str(ROOT / "tools"))
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert layout.readme_section(readme) == layout.section()
    listed = re.findall(r"^\| `((?:core|cli|app)/[^`]*)` \|", layout.section(), re.MULTILINE)
    on_disk = [p.relative_to(ROOT).as_posix().removesuffix("__init__.py") for p in CODE_FILES]
    assert sorted(listed) == sorted(on_disk)
