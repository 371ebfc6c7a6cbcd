"""`bushing fmu DESIGN.json -o BUSHING.fmu [--slices N] [--band F1 F2]` (docs/fmu.md): what it
writes, and one line on stderr with exit status 2 for every bad input."""

from __future__ import annotations

import os
import re
import stat
import zipfile

import pytest

from core import PAPER_B, write_design
from core.element import coefficients
from fmu import default_step
from tests.test_cli import run


@pytest.fixture
def design(tmp_path):
    path = tmp_path / "paper_b.json"
    write_design(PAPER_B, path)
    return path


def test_the_fmu_holds_its_description_sources_resources_and_binary(design, tmp_path, capsys):
    out = tmp_path / "front left.fmu"
    status, stdout, err = run(["fmu", design, "-o", out, "--slices", 2, "--band", 0.5, 1000], capsys)
    assert (status, stdout, err) == (0, "", "")
    names = set(zipfile.ZipFile(out).namelist())
    assert {"modelDescription.xml", "resources/coefficients.txt", "sources/bushing_kernel.c",
            "sources/bushing_fmu.c", "binaries/linux64/front_left.so"} <= names
    xml = zipfile.ZipFile(out).read("modelDescription.xml").decode()
    assert "dz.S[2]" in xml and "dx.S[2]" not in xml
    # the step follows the band asked (its top 1000 Hz) and the slices
    step = float(re.search(r'stepSize="([^"]+)"', xml).group(1))
    assert step == default_step(coefficients(PAPER_B, 2, (0.5, 1000.0))) and 1e-6 < step < 1e-5


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_the_fmu_gets_a_new_files_usual_permissions(design, tmp_path, capsys, umask):
    out = tmp_path / "b.fmu"
    old = os.umask(umask)
    try:
        status, _, _ = run(["fmu", design, "-o", out, "--band", 1, 50], capsys)
    finally:
        os.umask(old)
    assert status == 0 and stat.S_IMODE(out.stat().st_mode) == 0o666 & ~umask


def test_without_a_compiler_it_writes_the_source_only_fmu_and_says_so(design, tmp_path, capsys,
                                                                      monkeypatch):
    monkeypatch.setenv("CC", str(tmp_path / "no-compiler-here"))
    out = tmp_path / "b.fmu"
    status, _, err = run(["fmu", design, "-o", out], capsys)
    assert status == 0 and err.count("\n") == 1 and "no C compiler found" in err and "source-only" in err
    names = zipfile.ZipFile(out).namelist()
    assert "sources/bushing_kernel.c" in names and not [n for n in names if n.startswith("binaries/")]


@pytest.mark.parametrize(("args", "words"), [
    (["--slices", 0], "--slices must be at least 1"),
    (["--slices", 101], "--slices must be at most 100"),  # the element's limit, at the parser
    (["--slices", 2.5], "--slices must be a whole number"),
    (["--band", 100, 10], "the lower frequency must be below the upper one"),
    (["--band", 10, 10], "the lower frequency must be below the upper one"),
    (["--band", 0, 10], "--band must be a positive finite number"),
    (["--band", "nan", 10], "--band must be a number"),
    (["--band", 1, "inf"], "--band must be a number"),
    (["--band", 1, "1e400"], "--band must be a positive finite number"),
    (["--band", 1e-5, 1e4], "at most 8 decades wide"),
    (["--band", 1], "expected 2 arguments"),
])
def test_bad_options_are_one_line_and_status_2(design, tmp_path, capsys, args, words):
    status, _, err = run(["fmu", design, "-o", tmp_path / "b.fmu", *args], capsys)
    assert status == 2 and err.count("\n") == 1 and words in err and "Traceback" not in err
    assert not (tmp_path / "b.fmu").exists()


def test_an_unwritable_output_is_one_line_and_status_2(design, tmp_path, capsys):
    for out, words in ((tmp_path / "missing" / "b.fmu", "its directory does not exist"),
                       (tmp_path / "b.csv", "must end in .fmu")):
        status, _, err = run(["fmu", design, "-o", out], capsys)
        assert status == 2 and err.count("\n") == 1 and words in err
    (tmp_path / "dir.fmu").mkdir()
    status, _, err = run(["fmu", design, "-o", tmp_path / "dir.fmu"], capsys)
    assert status == 2 and "it is a directory" in err
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if not os.access(locked, os.W_OK):  # root writes anywhere
            status, _, err = run(["fmu", design, "-o", locked / "b.fmu"], capsys)
            assert status == 2 and err.count("\n") == 1 and "cannot write" in err
    finally:
        locked.chmod(0o700)


def test_an_effect_without_a_time_domain_form_is_one_line_and_status_2(tmp_path, capsys):
    path = tmp_path / "rig.json"
    write_design(PAPER_B.replace(effects={"inertia": {"mass": 1.0}}), path)
    status, _, err = run(["fmu", path, "-o", tmp_path / "b.fmu"], capsys)
    assert status == 2 and err.count("\n") == 1 and err.startswith("bushing fmu: effects.inertia: the time-domain")
    assert not (tmp_path / "b.fmu").exists()


def test_design_file_errors_are_one_line_and_status_2(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    for text in ("{", '{"mode": "axial"}', "[]"):
        bad.write_text(text)
        status, _, err = run(["fmu", bad, "-o", tmp_path / "b.fmu"], capsys)
        assert status == 2 and err.count("\n") == 1 and "Traceback" not in err
    status, _, err = run(["fmu", tmp_path / "nowhere.json", "-o", tmp_path / "b.fmu"], capsys)
    assert status == 2 and err.count("\n") == 1
