"""The README's set-up commands and .ci/run stay in step."""

import csv
import io
import itertools
import json
import math
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def readme_commands():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Set-up: two commands", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```bash\n(.+?)\n```", section)


def test_readme_has_two_setup_commands():
    run, test = readme_commands()
    assert "bushing serve" in run
    assert "pytest" in test


def test_ci_runs_the_readme_test_command():
    _, test = readme_commands()
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert test in ci.splitlines()


# ---- the worked examples: every `$ .venv/bin/bushing …` of the README's console blocks --------

CSV_HEADER = re.compile(r"[a-z_0-9]+(,[a-z_0-9]+)+")
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")
# A CSV number of the README is the command's value printed with 12 significant digits. The
# closed forms give the same value to ~1e-14 on any machine; the shape factors' table, the
# friction harmonic and the seeded Monte Carlo's percentiles are deterministic too. 1e-6
# relative leaves room for another platform's libm and BLAS, while any change of the model or
# of the examples (a parameter moved by a ppm) shows.
CSV_RTOL = 1e-6
ELIDED = "…"  # a README output line ending so shows the start of the printed line


def console_runs() -> list[tuple[str, list[str]]]:
    """(command, output lines shown under it) for every `$ ` line of the ```console blocks,
    backslash continuations joined."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    runs = []
    for block in re.findall(r"```console\n(.*?)```", text, re.DOTALL):
        lines = block.splitlines()
        i = 0
        while i < len(lines):
            assert lines[i].startswith("$ "), f"output before any command: {lines[i]!r}"
            command = lines[i][2:]
            while command.endswith("\\"):
                i += 1
                command = command[:-1] + " " + lines[i].strip()
            i += 1
            output = []
            while i < len(lines) and not lines[i].startswith("$ "):
                output.append(lines[i])
                i += 1
            runs.append((command, output))
    return runs


def readme_design() -> str:
    """The worked example's design file (the first JSON block after its heading)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## A worked example", 1)[1]
    return re.search(r"```json\n(.*?)```", section, re.DOTALL).group(1)


RUNS = console_runs()


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A fresh folder as a user's clone: paper_b.json from the README, the examples beside it."""
    work = tmp_path_factory.mktemp("readme")
    (work / "paper_b.json").write_text(readme_design(), encoding="utf-8")
    shutil.copytree(ROOT / "examples", work / "examples",
                    ignore=shutil.ignore_patterns("*.py", "*.ipynb", "*.md", "__pycache__"))
    return work


def installed_bushing() -> str:
    script = shutil.which("bushing", path=str(Path(sys.executable).parent))
    assert script, "no installed `bushing` script beside this Python"
    return script


def printed_unit(token: str) -> float:
    """One unit in the last printed digit of a rounded number (0 for an integer: exact)."""
    mantissa, _, exponent = token.lower().partition("e")
    if "." not in mantissa:
        return 0.0 if not exponent else 10.0 ** int(exponent)
    return 10.0 ** (int(exponent or 0) - len(mantissa.split(".")[1]))


def same_number(shown: str, printed: str, rtol: float = 0.0) -> bool:
    """A number of the README against the printed one: within `rtol`, or within one unit of the
    README's last digit (a value rounded for display flips the last digit at a rounding
    boundary under round-off; it never moves by two units)."""
    a, b = float(shown), float(printed)
    return abs(a - b) <= max(rtol * abs(a), printed_unit(shown) * (1 + 1e-9))


def line_mismatch(shown: str, printed: str) -> str | None:
    """Why a text line of the README differs from the printed one: the words exactly, the
    numbers as same_number; a line ending in … matches the start of the printed one."""
    elided = shown.rstrip().endswith(ELIDED)
    if elided:
        shown = shown.rstrip()[: -len(ELIDED)]
    words, numbers = NUMBER.split(shown), NUMBER.findall(shown)
    got_words, got_numbers = NUMBER.split(printed), NUMBER.findall(printed)
    if elided:
        n = len(numbers)
        if len(got_numbers) < n or not got_words[n].startswith(words[n]):
            return f"the start {shown!r} is not that of {printed!r}"
        got_words, got_numbers = got_words[: n + 1], got_numbers[:n]
        got_words[n] = words[n]
    if words != got_words or len(numbers) != len(got_numbers):
        return f"{shown!r} != {printed!r}"
    for a, b in zip(numbers, got_numbers):
        if not same_number(a, b):
            return f"{a} shown, {b} printed, in {printed!r}"
    return None


def csv_mismatch(shown: list[str], printed: list[str]) -> str | None:
    if len(shown) != len(printed):
        return f"{len(shown)} lines shown, {len(printed)} printed"
    if shown[0] != printed[0]:
        return f"header {shown[0]!r} != {printed[0]!r}"
    for row, got in zip(shown[1:], printed[1:]):
        cells, got_cells = row.split(","), got.split(",")
        if len(cells) != len(got_cells):
            return f"{row!r} != {got!r}"
        for a, b in zip(cells, got_cells):
            if NUMBER.fullmatch(a) and NUMBER.fullmatch(b):
                if not same_number(a, b, CSV_RTOL):
                    return f"{a} shown, {b} printed, in row {got!r}"
            elif a != b:
                return f"{a!r} shown, {b!r} printed"
    return None


def check_written(path: Path) -> None:
    """A file a README command writes exists and reads as what its name says."""
    assert path.is_file(), f"{path.name} not written"
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".json":
        json.loads(text)
    elif path.suffix == ".csv":
        rows = list(csv.reader(io.StringIO(text)))
        assert len(rows) > 1 and all(len(r) == len(rows[0]) for r in rows), path.name
        for row in rows[1:]:
            for cell in row:
                assert cell in ("axial", "radial", "torsion", "conical") \
                    or math.isfinite(float(cell)), path.name
    elif path.suffix == ".bdf":
        assert "PBUSH" in text and "ENDT" in text, path.name
    else:
        raise AssertionError(f"no check for {path.name}")


def test_the_readme_shows_bushing_commands():
    assert len(RUNS) >= 9
    for command, _ in RUNS:
        assert shlex.split(command)[0] == ".venv/bin/bushing", command


@pytest.mark.parametrize("command,shown", RUNS,
                         ids=[f"{i}-{shlex.split(c)[1]}" for i, (c, _) in enumerate(RUNS)])
def test_a_readme_command_prints_what_the_readme_shows(command, shown, workdir):
    argv = [installed_bushing(), *shlex.split(command)[1:]]
    done = subprocess.run(argv, cwd=workdir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, check=False)
    assert done.returncode == 0, done.stdout
    printed = done.stdout.splitlines()
    if shown and CSV_HEADER.fullmatch(shown[0]):
        problem = csv_mismatch(shown, printed)
    elif len(shown) != len(printed):
        problem = f"{len(shown)} lines shown, {len(printed)} printed:\n" + "\n".join(printed)
    else:
        problem = next(filter(None, map(line_mismatch, shown, printed)), None)
    assert problem is None, f"{command}\n{problem}\nprinted:\n{done.stdout}"
    for option, name in itertools.pairwise(argv):
        if option in ("-o", "--json", "--predictions"):
            check_written(workdir / name)


def test_the_readme_shows_a_screenshot_of_every_tab():
    """Every picture the README shows is in the repository, a 1280×720 PNG, and there is one per
    tab of the explorer, named after it, in the tabs' order."""
    import struct

    from app.main import App

    text = (ROOT / "README.md").read_text()
    pictures = re.findall(r"!\[([^\]]*)\]\(([^)]+)\)", text)
    titles = ["Explorer", *(title for title, _name, _build in App.LAZY_TABS), "About"]
    assert [alt for alt, _path in pictures] == titles
    for _alt, path in pictures:
        head = (ROOT / path).read_bytes()[:24]
        assert head[:8] == b"\x89PNG\r\n\x1a\n", path
        assert struct.unpack(">II", head[16:24]) == (1280, 720), path
