"""The repository stands on its own: docs/ say what the code does, and nothing points outside."""

import re
import subprocess
from pathlib import Path

from cli.main import build_parser
from core.effects import EFFECTS

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NUMBER = re.compile(r"(?<![\w.])\d+(?:\.\d+)?(?:e[-+]?\d+)?")


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


def test_every_thesis_equation_the_code_cites_is_in_the_model_page():
    cited = set()
    for path in [*ROOT.joinpath("core").glob("*.py"), *ROOT.joinpath("app").glob("*.py")]:
        for match in re.finditer(r"\beqs? (\d+)(?:[–-](\d+))?", path.read_text(encoding="utf-8")):
            lo = int(match.group(1))
            cited.update(range(lo, int(match.group(2) or lo) + 1))
    text = (DOCS / "model.md").read_text(encoding="utf-8")
    documented = set()
    for match in re.finditer(r"\beqs? (\d+)(?:[–-](\d+))?|^\| (\d+)(?:[–-](\d+))? \|", text, re.MULTILINE):
        lo = int(match.group(1) or match.group(3))
        hi = int(match.group(2) or match.group(4) or lo)
        documented.update(range(lo, hi + 1))
    assert cited and cited <= documented, sorted(cited - documented)


def test_the_core_never_imports_the_app():
    """The arrow points one way: app/ uses core/, never the other way round."""
    found = [f"{p.name}: {line.strip()}" for p in ROOT.joinpath("core").glob("*.py")
             for line in p.read_text(encoding="utf-8").splitlines()
             if re.match(r"\s*(from app\b|import app\b)", line)]
    assert found == []
