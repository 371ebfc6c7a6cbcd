"""examples/ holds exactly what examples/make_examples.py writes (examples/README.md: "regenerates
them exactly (seeded)"): the generator is run into an empty folder and every file compared."""

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
# written by hand (examples/README.md says so), not by the generator
BY_HAND = {"paper_b_tolerances.json", "paper_b_targets.json"}

# The data files carry 10 significant digits (core.data.FILE_NUMBER_FORMAT). The generator's
# numbers are closed-form model values times seeded noise: regenerated elsewhere they differ by
# round-off (~1e-15 relative), which can move the 10th printed digit by one unit: at most 1e-9
# relative. Numbers near zero (sin(πk) of the loop's drive, ~1e-19) are judged against the
# column's scale: 1e-12 of its largest value is far below anything a change of the data would do.
RTOL = 1.5e-9
ATOL_OF_SCALE = 1e-12


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    out = tmp_path_factory.mktemp("examples")
    done = subprocess.run([sys.executable, str(EXAMPLES / "make_examples.py"), str(out)],
                          capture_output=True, text=True, check=False, cwd=out)
    assert done.returncode == 0, done.stderr
    return out


def read_csv(path):
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def assert_same_csv(made, committed):
    header, rows = read_csv(made)
    header_c, rows_c = read_csv(committed)
    assert header == header_c, committed.name
    assert len(rows) == len(rows_c), committed.name
    for j, name in enumerate(header):
        col = [r[j] for r in rows]
        col_c = [r[j] for r in rows_c]
        try:
            values, values_c = np.array(col, float), np.array(col_c, float)
        except ValueError:  # a text column (mode)
            assert col == col_c, f"{committed.name}: column {name}"
            continue
        scale = np.max(np.abs(values_c))
        np.testing.assert_allclose(values, values_c, rtol=RTOL, atol=ATOL_OF_SCALE * scale,
                                   err_msg=f"{committed.name}: column {name}")


def assert_same_json(made, committed, where=""):
    if isinstance(committed, dict):
        assert isinstance(made, dict) and made.keys() == committed.keys(), where
        for key in committed:
            assert_same_json(made[key], committed[key], f"{where}.{key}")
    elif isinstance(committed, list):
        assert isinstance(made, list) and len(made) == len(committed), where
        for i, (a, b) in enumerate(zip(made, committed)):
            assert_same_json(a, b, f"{where}[{i}]")
    elif isinstance(committed, (int, float)) and not isinstance(committed, bool):
        # design files: the stated constants, written by json as their shortest repr: exact
        assert made == pytest.approx(committed, rel=1e-15), where
    else:
        assert made == committed, where


def test_the_generator_writes_every_committed_data_file(generated):
    made = {p.name for p in generated.iterdir()}
    committed = {p.name for p in EXAMPLES.iterdir() if p.suffix in (".csv", ".json")}
    assert made, "make_examples.py wrote nothing"
    assert made <= committed, f"generated but not committed: {sorted(made - committed)}"
    extra = sorted(committed - made - BY_HAND)
    assert committed - made == BY_HAND, f"committed, not generated: {extra}"


@pytest.mark.parametrize("name", sorted(
    p.name for p in EXAMPLES.iterdir() if p.suffix in (".csv", ".json") and p.name not in BY_HAND))
def test_committed_file_equals_the_generated_one(name, generated):
    made, committed = generated / name, EXAMPLES / name
    assert made.exists(), f"make_examples.py does not write {name}"
    if committed.suffix == ".csv":
        assert_same_csv(made, committed)
    else:
        assert_same_json(json.loads(made.read_text(encoding="utf-8")),
                         json.loads(committed.read_text(encoding="utf-8")), name)

