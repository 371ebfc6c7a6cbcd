"""Measured-data files: every refusal names its line and reason; nothing is dropped."""

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core import PAPER_B, write_design
from core.data import DataError, MeasuredStiffness
from core.io.measured import MAX_BYTES, parse_loop, parse_stiffness, read_stiffness
from tests.helpers import run

HEAD = "frequency_hz,amplitude,magnitude,loss_factor\n"
GOOD = HEAD + "10,1e-4,4.2e6,0.138\n20,1e-4,4.3e6,0.14\n"

BAD_STIFFNESS = [
    ("", "empty"),
    ("   \n", "empty"),
    (HEAD, "no data rows"),
    ("freq,amp,mag,eta\n1,2,3,4\n", "line 1"),
    (HEAD.replace("loss_factor", "phase"), "line 1"),
    (HEAD.strip() + ",comment\n10,1e-4,4e6,0.1,ok\n", "unknown column"),
    (HEAD + "10,1e-4,4e6,0.1\n20,1e-4,,0.1\n", "line 3: magnitude is missing"),
    (HEAD + "10,1e-4,4e6\n", "line 2: loss_factor is missing"),
    (HEAD + "10,1e-4,4e6,0.1\n\n30,1e-4,4e6,0.1\n", "line 3"),
    (HEAD + "10,1e-4,four,0.1\n", "line 2: magnitude is not a number"),
    (HEAD + "10,1e-4,inf,0.1\n", "line 2: magnitude is not finite"),
    (HEAD + "10,1e-4,4e6,nan\n", "line 2: loss_factor is not finite"),
    (HEAD + "-10,1e-4,4e6,0.1\n", "line 2: frequency_hz must be positive"),
    (HEAD + "0,1e-4,4e6,0.1\n", "line 2: frequency_hz must be positive"),
    (HEAD + "10,0,4e6,0.1\n", "line 2: amplitude must be positive"),
    (HEAD + "10,1e-4,-4e6,0.1\n", "line 2: magnitude must be positive"),
    (HEAD + "10,1e-4,4e6,0.1,7\n", "line 2 has 5 fields, the header 4"),
    (HEAD + "10,1e-4,4e6,0.1\n20,1e-4,4e6,0.1,7\n", "not a valid CSV"),
    ("frequency_hz,amplitude,stiffness_real,stiffness_imag\n10,1e-4,0,0\n", "line 2: the stiffness is zero"),
]


@pytest.mark.parametrize("text,needle", BAD_STIFFNESS)
def test_bad_stiffness_files_refused(text, needle):
    with pytest.raises(DataError, match=needle):
        parse_stiffness(text)


def test_good_files_in_both_forms_agree():
    polar = parse_stiffness(GOOD)
    cart = parse_stiffness(polar.to_csv(polar=False))
    assert_allclose(cart.stiffness, polar.stiffness, rtol=1e-9)
    assert_allclose(polar.magnitude, [4.2e6, 4.3e6])
    assert_allclose(polar.loss_factor, [0.138, 0.14])
    assert len(polar) == 2


def test_amplitudes_most_frequent_first():
    d = MeasuredStiffness(np.arange(1.0, 7.0), np.array([3e-4, 1e-4, 2e-4, 1e-4, 3e-4, 1e-4]), np.ones(6, complex))
    assert list(d.amplitudes()) == [1e-4, 3e-4, 2e-4]  # 3 times, twice (ties: smaller first), once


def test_a_written_loop_reads_back_as_it_was():
    from core.synthetic import synthetic_loop

    loop = synthetic_loop(PAPER_B, 0.1, 1e-3, seed=5)
    text = loop.to_csv()
    assert text.splitlines()[0] == "time_s,displacement,force"
    back = parse_loop(text)
    for name in ("time_s", "displacement", "force"):
        assert_allclose(getattr(back, name), getattr(loop, name), rtol=1e-9, atol=0)


def test_too_large_and_not_text(tmp_path):
    big = tmp_path / "big.csv"
    big.write_bytes(b"x" * (MAX_BYTES + 1))
    with pytest.raises(DataError, match="too large"):
        read_stiffness(big)
    binary = tmp_path / "bin.csv"
    binary.write_bytes(b"\xff\xfe\x00\x01")
    with pytest.raises(DataError, match="UTF-8"):
        read_stiffness(binary)
    with pytest.raises(DataError, match="cannot read"):
        read_stiffness(tmp_path / "none.csv")


LOOP_HEAD = "time_s,displacement,force\n"


def loop_text(n=40, step=0.01):
    t = np.arange(n) * step
    return LOOP_HEAD + "".join(f"{a},{1e-3 * np.sin(2 * np.pi * a)},{100 * np.sin(2 * np.pi * a)}\n" for a in t)


@pytest.mark.parametrize(
    "text,needle",
    [
        ("", "empty"),
        ("time,x,f\n0,0,0\n", "line 1"),
        (LOOP_HEAD + "0,0,0\n0.1,1,1\n", "at least 16"),
        (loop_text().replace("\n0.02,", "\n0.005,", 1), "time_s must increase"),
        (LOOP_HEAD + "0,0,0,9\n" + loop_text().split("\n", 2)[2], "line 2 has 4 fields"),
        (LOOP_HEAD + "".join(f"{i * 0.01},0,{i}\n" for i in range(20)), "never moves"),
        (loop_text()[:-5] + "x\n", "not a number"),
    ],
)
def test_bad_loop_files_refused(text, needle):
    with pytest.raises(DataError, match=needle):
        parse_loop(text)


def test_good_loop():
    lp = parse_loop(loop_text(200))
    f, amp, _ = lp.harmonic()
    assert f == pytest.approx(1.0, rel=1e-6) and amp == pytest.approx(1e-3, rel=1e-6)


# ---- through the command line --------------------------------------------------------------


@pytest.mark.parametrize("text,needle", BAD_STIFFNESS[:12])
def test_cli_fit_refuses_bad_stiffness_files(text, needle, tmp_path, capsys):
    measured = tmp_path / "m.csv"
    measured.write_text(text)
    design = tmp_path / "d.json"
    write_design(PAPER_B, design)
    status, out, err = run(["fit", measured, "--design", design], capsys)
    assert status == 2 and out == "" and err.count("\n") == 1 and needle.split(":")[0] in err
    assert "Traceback" not in err


def test_cli_fit_refuses_a_bad_loop(tmp_path, capsys):
    measured = tmp_path / "m.csv"
    measured.write_text(GOOD)
    loop = tmp_path / "l.csv"
    loop.write_text("time_s,displacement,force\n0,0,0\n")
    design = tmp_path / "d.json"
    write_design(PAPER_B, design)
    status, _, err = run(["fit", measured, "--design", design, "--loop", loop], capsys)
    assert status == 2 and "at least 16" in err and err.count("\n") == 1


def test_cli_fit_writes_the_fitted_design(tmp_path, capsys):
    from core import read_design, stiffness

    rng = np.random.default_rng(4)
    f = np.linspace(1, 100, 12)
    amps = [2e-5, 1e-4, 5e-4]
    ff, xx = np.meshgrid(f, amps)
    k = stiffness(PAPER_B, f, amps).stiffness.ravel() * (1 + 0.003 * rng.standard_normal(36))
    measured = tmp_path / "m.csv"
    MeasuredStiffness(ff.ravel(), xx.ravel(), k).to_csv(measured)
    start = tmp_path / "start.json"
    write_design(PAPER_B.replace(shear_modulus=1.5e6, friction_strain_half=2e-3), start)
    out = tmp_path / "fitted.json"
    status, stdout, err = run(["fit", measured, "--design", start, "-o", out], capsys)
    assert status == 0 and stdout == "" and err == ""
    fitted = read_design(out)  # a design file the tools read back
    report = json.loads(out.read_text())["fit"]
    assert set(report["standard_errors"]) == set(json.loads(out.read_text())["material"])
    assert report["correlation"]["shear_modulus"]["shear_modulus"] == pytest.approx(1.0)
    assert report["gap"] < 0.01
    assert fitted.material.shear_modulus == pytest.approx(2.42e6, rel=0.02)


def test_byte_order_mark_and_windows_line_endings_are_accepted(tmp_path):
    """Spreadsheets write a UTF-8 byte-order mark and CRLF; neither is data."""
    path = tmp_path / "excel.csv"
    path.write_bytes(b"\xef\xbb\xbf" + GOOD.replace("\n", "\r\n").encode())
    assert_allclose(read_stiffness(path).magnitude, [4.2e6, 4.3e6])
    assert_allclose(parse_stiffness(b"\xef\xbb\xbf" + GOOD.encode()).magnitude, [4.2e6, 4.3e6])


def test_design_file_with_byte_order_mark(tmp_path):
    from core import dumps_design, read_design

    path = tmp_path / "d.json"
    path.write_bytes(b"\xef\xbb\xbf" + dumps_design(PAPER_B).encode())
    assert read_design(path) == PAPER_B
