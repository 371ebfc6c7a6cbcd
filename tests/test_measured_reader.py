"""The measured-data reader against files as they come: the product's own stiffness CSV fed back,
blank lines at the end, huge fields and headers, a column named twice, several files at once,
a loop recorded in ms. Every refusal is one short line naming the file, the line and the rule."""

import json
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core import PAPER_B
from core.data import DataError
from core.io.measured import FORMS_AGREE, parse_loop, parse_stiffness, read_loop, read_stiffness
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


# ---- 1. both forms of the stiffness, as `bushing stiffness` writes them ---------------------------


def test_the_stiffness_csv_of_the_command_line_is_fitted_back_to_its_material(tmp_path, capsys):
    data, fitted = tmp_path / "d.csv", tmp_path / "fitted.json"
    status, _, err = run(["stiffness", EXAMPLES / "paper_b_true.json", "--freq", 1, 100, 10,
                          "--amp", 1e-5, 1e-4, 1e-3, "-o", data], capsys)
    assert status == 0 and err == ""
    assert data.read_text().splitlines()[0] == ("frequency_hz,amplitude,stiffness_real,stiffness_imag,"
                                                "magnitude,loss_factor")
    status, _, err = run(["fit", data, "--design", EXAMPLES / "paper_b_guess.json", "-o", fitted], capsys)
    assert status == 0, err
    truth = json.loads((EXAMPLES / "paper_b_true.json").read_text())["material"]
    found = json.loads(fitted.read_text())
    assert found["fit"]["gap"] < 1e-8  # noise-free data of the model itself
    for key, value in truth.items():
        assert found["material"][key] == pytest.approx(value, rel=1e-6), key


def test_both_forms_are_read_as_the_cartesian_one_where_re_k_is_negative():
    """The loss-factor form cannot say Re K < 0; `bushing stiffness` writes η = Im K / Re K with
    its sign beside the parts, and the two agree: K is the parts'."""
    k = np.array([4e6 + 5e5j, -2e6 + 1e5j, -3e6 - 2e4j])
    rows = "".join(f"{10 * (i + 1)},1e-4,{z.real:.12g},{z.imag:.12g},{abs(z):.12g},{z.imag / z.real:.12g}\n"
                   for i, z in enumerate(k))
    data = parse_stiffness("frequency_hz,amplitude,stiffness_real,stiffness_imag,magnitude,loss_factor\n" + rows)
    assert_allclose(data.stiffness, k, rtol=1e-12)


@pytest.mark.parametrize("columns", [
    ("stiffness_real", "stiffness_imag", "magnitude", "phase_deg"),
    ("magnitude", "loss_factor", "phase_deg"),
    ("stiffness_real", "stiffness_imag", "magnitude", "loss_factor", "phase_deg"),
])
def test_any_forms_that_agree_are_read_together(columns):
    k = np.array([4e6 + 5e5j, 3e6 - 2e4j, -2e6 + 1e5j, -1e6 - 1e5j, -3e6 + 0j])
    if "stiffness_real" not in columns:  # magnitude, loss factor and phase: Re K > 0 only
        k = k[:2]
    value = {"stiffness_real": k.real, "stiffness_imag": k.imag, "magnitude": np.abs(k),
             "loss_factor": k.imag / k.real, "phase_deg": np.rad2deg(np.angle(k))}
    text = "frequency_hz,amplitude," + ",".join(columns) + "\n" + "".join(
        f"{10 * (i + 1)},1e-4," + ",".join(f"{value[c][i]:.12g}" for c in columns) + "\n" for i in range(k.size))
    assert_allclose(parse_stiffness(text).stiffness, k, rtol=1e-11)


@pytest.mark.parametrize("column, value, words", [
    ("magnitude", "4.3e6", "magnitude is 4300000 but |stiffness_real + i stiffness_imag| is 4200000"),
    ("loss_factor", "0.139", "loss_factor is 0.139 but stiffness_imag/stiffness_real is 0.138"),
])
def test_two_forms_that_disagree_are_refused_naming_the_line_and_both_values(column, value, words):
    re = 4.2e6 / np.hypot(1, 0.138)
    rows = [[10, 1e-4, f"{re:.12g}", f"{0.138 * re:.12g}", "4.2e6", "0.138"] for _ in range(3)]
    rows[1][{"magnitude": 4, "loss_factor": 5}[column]] = value
    text = "frequency_hz,amplitude,stiffness_real,stiffness_imag,magnitude,loss_factor\n" + "".join(
        ",".join(map(str, r)) + "\n" for r in rows)
    err = refusal(parse_stiffness, text)
    assert (err.key, err.code) == ("line 3", "conflict") and words in err.rule, str(err)
    # agreement within FORMS_AGREE: a last digit of 12 is no disagreement, 1e-8 relative is
    rows[1][4 if column == "magnitude" else 5] = f"{(4.2e6 if column == 'magnitude' else 0.138) * (1 + 1e-11):.12g}"
    assert len(parse_stiffness(text.split("\n", 1)[0] + "\n" + "".join(",".join(map(str, r)) + "\n" for r in rows)))
    assert FORMS_AGREE == 1e-9


def test_a_file_whose_forms_disagree_is_refused_by_the_command_line_naming_file_and_line(tmp_path, capsys):
    measured = tmp_path / "edited.csv"
    size = f"{np.hypot(4e6, 4e5):.12g}"  # |K| of the parts, to the 12 digits written
    measured.write_text("frequency_hz,amplitude,stiffness_real,stiffness_imag,magnitude,loss_factor\n"
                        f"10,1e-4,4000000,400000,{size},0.1\n20,1e-4,4000000,400000,4100000,0.1\n")
    status, out, err = run(["fit", measured, "--design", EXAMPLES / "paper_b_true.json"], capsys)
    assert status == 2 and out == "" and err.count("\n") == 1
    assert "line 3: the two forms of the stiffness disagree" in err and "(in edited.csv)" in err


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
