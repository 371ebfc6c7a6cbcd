"""The measured-data reader against files as they come: blank lines at the end, huge fields
and headers, a column named twice, several files at once, a loop recorded in ms. Every refusal
is one short line naming the file, the line and the rule."""

from pathlib import Path

import pytest
from numpy.testing import assert_allclose

from core import PAPER_B
from core.data import DataError
from core.io.measured import parse_loop, parse_stiffness, read_loop, read_stiffness
from core.numbers import format_outside
from core.rules import EXCERPT_CHARS, excerpt
from core.synthetic import synthetic_loop
from tests.helpers import run

HEAD = "frequency_hz,amplitude,magnitude,loss_factor\n"
GOOD = HEAD + "10,1e-4,4.2e6,0.138\n20,1e-4,4.3e6,0.14\n"
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
# a message quoting a file's value: the excerpt and the words around it, never the value whole
SHORT = 400


def refusal(parse, text) -> DataError:
    with pytest.raises(DataError) as info:
        parse(text)
    return info.value


# ---- 2. blank lines at the end ------------------------------------------------------------------


@pytest.mark.parametrize("tail", ["\n", "\n\n", "\r\n\r\n", "   \n\t\n", "\n  "])
def test_blank_lines_at_the_end_carry_nothing(tail):
    assert_allclose(parse_stiffness(GOOD + tail).magnitude, [4.2e6, 4.3e6])
    loop = synthetic_loop(PAPER_B, 1.0, 1e-4, seed=1).to_csv()
    assert len(parse_loop(loop + tail).time_s) == len(parse_loop(loop).time_s)


@pytest.mark.parametrize("text, line", [
    (HEAD + "10,1e-4,4e6,0.1\n\n20,1e-4,4e6,0.1\n\n", "line 3"),  # a blank line among the data
    (HEAD + "10,1e-4,4e6,0.1\n,,,\n", "line 3"),  # separators are a row, its values missing
    (HEAD + "\n\n", ""),  # a header only
])
def test_a_missing_row_inside_the_data_is_still_refused(text, line):
    err = refusal(parse_stiffness, text)
    assert err.key == line and ("missing" in err.rule if line else "no data rows" in err.rule), str(err)


# ---- 3. and 4. huge fields, headers and cells: exit 2, one short line -----------------------------

HUGE = {
    "a first field over the csv module's limit": "x" * 140_000 + "\n1,2,3,4\n",
    "a 3 MB cell": HEAD + "10,1e-4," + "9" * 3_000_000 + "x,0.1\n",
    "a header of 2.6 MB of names": ",".join(f"column_{i}" for i in range(260_000)) + "\n1\n",
    "an unknown column with a long name": HEAD.strip() + "," + "y" * 100_000 + "\n10,1e-4,4e6,0.1,1\n",
    "a long mode": "mode," + HEAD + "m" * 100_000 + ",10,1e-4,4e6,0.1\n",
    "a long name given twice": HEAD.strip() + ("," + "z" * 50_000) * 2 + "\n10,1e-4,4e6,0.1,1,1\n",
    "an open quote": HEAD + '10,1e-4,4e6,"' + "0" * 200_000 + "\n",
}


@pytest.mark.parametrize("name", HUGE)
def test_a_huge_field_is_refused_in_one_short_line(name):
    err = refusal(parse_stiffness, HUGE[name])
    assert len(str(err)) < SHORT, str(err)[:SHORT]
    assert err.key or "line" in err.rule


@pytest.mark.parametrize("command", ["fit", "diagnose"])
def test_a_huge_field_exits_2_naming_the_file_and_line(command, tmp_path, capsys):
    measured = tmp_path / "tt.csv"
    measured.write_text(HUGE["a first field over the csv module's limit"])
    status, out, err = run([command, measured, "--design", EXAMPLES / "paper_b_true.json"], capsys)
    assert status == 2 and out == "" and err.count("\n") == 1 and len(err) < SHORT, err[:SHORT]
    assert "internal error" not in err and "line 1" in err and "tt.csv" in err and "more than 131072" in err


def test_a_huge_field_in_a_loop_exits_2(tmp_path, capsys):
    loop = tmp_path / "loop.csv"
    loop.write_text("time_s,displacement,force\n" + "1" * 200_000 + ",0,0\n")
    status, _, err = run(["fit", EXAMPLES / "paper_b_stiffness.csv", "--design", EXAMPLES / "paper_b_guess.json",
                          "--loop", loop], capsys)
    assert status == 2 and err.count("\n") == 1 and "line 2" in err and "loop.csv" in err, err[:SHORT]


def test_the_apps_upload_says_what_is_wrong_with_a_huge_field():
    from app.state import ExplorerState

    state = ExplorerState()
    assert not state.load_measured(HUGE["a first field over the csv module's limit"].encode(), "tt.csv")
    assert state.data_message.startswith("tt.csv: ") and "line 1" in state.data_message
    assert len(state.data_message) < SHORT
    assert not state.load_measured_loop(b"time_s,displacement,force\n" + b"1" * 200_000 + b",0,0\n", "l.csv")
    assert state.data_message.startswith("l.csv: ") and len(state.data_message) < SHORT


def test_an_excerpt_is_short_and_says_it_was_cut():
    assert excerpt("4.2e6") == "4.2e6"
    assert excerpt("x" * 1000) == "x" * EXCERPT_CHARS + "…"
    assert excerpt("y" * 100, 10) == "y" * 10 + "…"


# ---- 5. several files: each refusal names its file ------------------------------------------------


def test_a_row_error_names_its_file_among_several(tmp_path, capsys):
    good, bad = tmp_path / "a.csv", tmp_path / "b.csv"
    good.write_text((EXAMPLES / "paper_b_stiffness.csv").read_text())
    bad.write_text(HEAD + "10,1e-4,4e6,0.1\n" * 6 + "10,1e-4,inf,0.1\n")
    status, _, err = run(["fit", good, bad, "--design", EXAMPLES / "paper_b_true.json"], capsys)
    assert status == 2 and err == "bushing: line 8: magnitude is not finite ('inf') (in b.csv)\n"
    with pytest.raises(DataError, match=r"^line 8: magnitude is not finite .*\(in b\.csv\)$"):
        read_stiffness(bad)
    loop = tmp_path / "l.csv"
    loop.write_text("time_s,displacement,force\n0,0,0\n")
    with pytest.raises(DataError, match=r"at least 16 .*\(in l.csv\)$"):
        read_loop(loop)


# ---- 6. a column given twice ---------------------------------------------------------------------


def test_a_column_given_twice_is_named_as_written():
    err = refusal(parse_stiffness, HEAD.strip() + ",magnitude\n10,1e-4,4e6,0.1,1\n")
    assert (err.key, err.code) == ("line 1", "duplicate_key")
    assert "'magnitude' is given twice" in err.rule and "magnitude.1" not in str(err)
    err = refusal(parse_loop, "time_s,displacement,force,time_s\n0,0,0,0\n")
    assert "'time_s' is given twice" in err.rule


# ---- 7. a loop in ms ------------------------------------------------------------------------------


def test_a_loop_in_ms_is_refused_with_a_message_that_holds():
    loop = synthetic_loop(PAPER_B, 0.1, 1e-4, seed=2)  # 0.1 Hz, time in s
    ms = type(loop)(loop.time_s * 1000, loop.displacement, loop.force)
    err = refusal(parse_loop, ms.to_csv())
    assert "0.0001 Hz," not in err.rule and "(0.0001 Hz" not in err.rule
    assert "time_s looks like milliseconds" in err.rule and "0.1 Hz" in err.rule, err.rule
    assert "must be within 0.0001–100000 Hz" in err.rule


def test_a_value_beside_its_bound_is_written_with_the_digits_that_keep_it_outside():
    assert format_outside(9.99999e-5, 1e-4, 1e5, 3) == "99.9999×10⁻⁶"
    assert format_outside(100000.4, 1e-4, 1e5, 3) == "100000.4"
    assert format_outside(5e-5, 1e-4, 1e5, 3) == "50×10⁻⁶"
    assert format_outside(5.0, 1e-4, 1e5, 3) == "5"  # inside: as format_number writes it
