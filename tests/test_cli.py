"""The `bushing` command line exactly as docs/files.md describes it."""

import csv
import io
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core import PAPER_B, TABLE_1, loop, stiffness, write_design
from tests.helpers import fetch, run

STIFFNESS_COLUMNS = ["frequency_hz", "amplitude", "stiffness_real", "stiffness_imag", "magnitude",
                     "loss_factor"]
LOOP_COLUMNS = ["displacement", "force", "force_elastic", "force_viscoelastic", "force_friction"]


@pytest.fixture
def designs(tmp_path):
    paths = {}
    for key, design in (("axial", PAPER_B), ("torsion", TABLE_1)):
        paths[key] = tmp_path / f"{key}.json"
        write_design(design, paths[key])
    return paths


def read_csv(text):
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], np.array(rows[1:], dtype=float)


def test_stiffness_to_stdout(designs, capsys):
    argv = ["stiffness", designs["axial"], "--freq", 1, 100, 5, "--amp", 1e-4, 1e-3]
    status, out, err = run(argv, capsys)
    assert status == 0 and err == ""
    header, data = read_csv(out)
    assert header == STIFFNESS_COLUMNS and data.shape == (10, 6)
    ref = stiffness(PAPER_B, np.linspace(1, 100, 5), [1e-4, 1e-3])
    assert_allclose(data[:, 0], np.tile(np.linspace(1, 100, 5), 2))
    assert_allclose(data[:, 1], np.repeat([1e-4, 1e-3], 5))
    assert_allclose(data[:, 2] + 1j * data[:, 3], ref.stiffness.ravel(), rtol=1e-11)
    assert_allclose(data[:, 4], ref.magnitude.ravel(), rtol=1e-11)
    assert_allclose(data[:, 5], ref.loss_factor.ravel(), rtol=1e-11)


def test_stiffness_log_grid_slices_and_file(designs, capsys, tmp_path):
    out_path = tmp_path / "k.csv"
    status, out, _ = run(
        ["stiffness", designs["torsion"], "--freq", 10, 1000, 3, "--log", "--amp", 1e-3,
         "--slices", 3, "-o", out_path],
        capsys,
    )
    assert status == 0 and out == ""
    _, data = read_csv(out_path.read_text())
    assert_allclose(data[:, 0], [10, 100, 1000])
    ref = stiffness(TABLE_1, [10, 100, 1000], 1e-3, slices=3)
    assert_allclose(data[:, 4], ref.magnitude.ravel(), rtol=1e-11)


def test_stiffness_continuum_and_time_domain(designs, capsys):
    argv = ["stiffness", designs["axial"], "--freq", 10, 10, 1, "--amp", 2e-4, "--continuum"]
    _, out, _ = run(argv, capsys)
    cont = read_csv(out)[1]
    assert_allclose(cont[0, 4], stiffness(PAPER_B, 10, 2e-4, slices="continuum").magnitude[0, 0],
                    rtol=1e-11)
    _, out, _ = run(["stiffness", designs["axial"], "--freq", 10, 10, 1, "--amp", 2e-4,
                     "--route", "time-domain"], capsys)
    td = read_csv(out)[1]
    assert_allclose(td[0, 4], stiffness(PAPER_B, 10, 2e-4).magnitude[0, 0], rtol=1e-4)


def test_loop(designs, capsys):
    status, out, _ = run(["loop", designs["axial"], "--freq", 0.1, "--amp", 1e-3, "--points", 64],
                         capsys)
    assert status == 0
    header, data = read_csv(out)
    assert header == LOOP_COLUMNS and data.shape == (64, 5)
    ref = loop(PAPER_B, 0.1, 1e-3, 64)
    assert_allclose(data[:, 1], ref.force, rtol=1e-11, atol=1e-9)
    assert_allclose(data[:, 1], data[:, 2:].sum(axis=1), rtol=1e-9, atol=1e-9)


def test_loop_default_points(designs, capsys):
    _, out, _ = run(["loop", designs["torsion"], "--freq", 10, "--amp", 0.01], capsys)
    assert read_csv(out)[1].shape == (256, 5)


def _bad_design(tmp_path, mutate):
    data = PAPER_B.to_dict()
    mutate(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    return path


BAD = [
    (["stiffness", "{axial}", "--freq", 1, 100, "--amp", 1e-4], "--freq"),
    (["stiffness", "{axial}", "--freq", 1, 100, 0, "--amp", 1e-4], "--freq"),
    (["stiffness", "{axial}", "--freq", -1, 100, 5, "--amp", 1e-4], "--freq"),
    (["stiffness", "{axial}", "--freq", 1, 100, 2.5, "--amp", 1e-4], "--freq"),
    (["stiffness", "{axial}", "--freq", 1, 100, 5, "--amp", "-1e-4"], "--amp"),
    (["stiffness", "{axial}", "--freq", 1, 100, 5, "--amp", "abc"], "--amp"),
    (["stiffness", "{axial}", "--freq", 1, 100, 5], "--amp"),
    (["stiffness", "{axial}", "--freq", 1, 100, 5, "--amp", 1e-4, "--slices", 0], "--slices"),
    (["stiffness", "{axial}", "--freq", 1, 100, 5, "--amp", 1e-4, "--slices", 2, "--continuum"],
     "--continuum"),
    (["stiffness", "{axial}", "--freq", 1, 100, 5, "--amp", 1e-4, "--route", "magic"], "--route"),
    (["stiffness", "{axial}", "--freq", 1, 100, 5, "--amp", 1e-4, "-o", "/no/such/dir/k.csv"],
     "cannot write"),
    (["stiffness", "missing.json", "--freq", 1, 100, 5, "--amp", 1e-4], "cannot read"),
    (["stiffness", "{bad}", "--freq", 1, 100, 5, "--amp", 1e-4], "geometry.outer_radius"),
    (["loop", "{axial}", "--freq", "nan", "--amp", 1e-3], "--freq"),
    (["loop", "{axial}", "--freq", 1, "--amp", 0], "--amp"),
    (["loop", "{axial}", "--freq", 1, "--amp", 1e-3, "--points", 2], "--points"),
    (["loop", "{inertia}", "--freq", 1, "--amp", 1e-3], "effects.inertia"),
    # every number on the command line is plain ASCII, as in the data files: other digits refused
    (["stiffness", "{axial}", "--freq", 1, 100, "١٠", "--amp", 1e-4], "--freq N must be a whole number"),
    (["loop", "{axial}", "--freq", 1, "--amp", 1e-3, "--points", "６４"], "--points must be a whole number"),
    (["fit", "{measured}", "--design", "{axial}", "--fit-on", "amplitude=nan"], "amplitudes are numbers"),
    (["fit", "{measured}", "--design", "{axial}", "--fit-on", "amplitude=1_0"], "amplitudes are numbers"),
    (["teleport"], "invalid choice"),
    ([], "required"),
]


@pytest.mark.parametrize("argv,needle", BAD)
def test_bad_input_is_one_line_and_status_2(argv, needle, designs, capsys, tmp_path):
    bad = _bad_design(tmp_path, lambda d: d["geometry"].__setitem__("outer_radius", 0.01))
    inertia = tmp_path / "inertia.json"
    write_design(PAPER_B.replace(effects={"inertia": {"mass": 1.0}}), inertia)
    measured = tmp_path / "measured.csv"
    measured.write_text("frequency_hz,amplitude,magnitude,loss_factor\n10,1e-4,4e6,0.14\n20,1e-4,4.2e6,0.15\n")
    argv = [str(a).format(axial=designs["axial"], bad=bad, inertia=inertia, measured=measured) for a in argv]
    status, out, err = run(argv, capsys)
    assert status == 2
    assert out == ""
    assert err.count("\n") == 1 and needle in err
    assert "Traceback" not in err


def test_help_exits_zero(capsys):
    for argv in (["--help"], ["stiffness", "--help"], ["loop", "--help"]):
        status, out, _ = run(argv, capsys)
        assert status == 0 and "usage" in out


def installed_script() -> list[str]:
    """The `bushing` console script pip installed beside this Python (pyproject's
    [project.scripts]), as a user types it."""
    script = shutil.which("bushing", path=str(Path(sys.executable).parent))
    assert script is not None, f"no installed `bushing` script in {Path(sys.executable).parent}"
    return [script]


def test_installed_entry_point_runs_without_traceback(designs, tmp_path):
    """The console script as a user types it, in a separate process."""
    bushing = installed_script()
    ok = subprocess.run(
        [*bushing, "stiffness", str(designs["axial"]), "--freq", "1", "10", "2", "--amp", "1e-4"],
        capture_output=True, text=True, check=False,
    )
    assert ok.returncode == 0 and ok.stdout.splitlines()[0] == ",".join(STIFFNESS_COLUMNS)
    assert_allclose(read_csv(ok.stdout)[1][:, 4],
                    stiffness(PAPER_B, [1, 10], 1e-4).magnitude.ravel(), rtol=1e-11)  # 12 digits
    bad = subprocess.run(
        [*bushing, "loop", str(tmp_path / "none.json"), "--freq", "1", "--amp", "1e-3"],
        capture_output=True, text=True, check=False,
    )
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "Traceback" not in bad.stderr
    # the script is the whole command line (cli.main), not the core's alone: it knows `serve`
    helped = subprocess.run([*bushing, "--help"], capture_output=True, text=True, check=False)
    assert helped.returncode == 0 and "serve" in helped.stdout


def test_serve_prints_its_url_and_answers():
    """`bushing serve --port 0`: the OS picks a free port (no "find one, then bind it" race) and
    the command prints the URL once its socket is bound, so one request is answered without
    polling (it waits in the listen backlog)."""
    proc = subprocess.Popen([sys.executable, "-m", "cli.main", "serve", "--port", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        found = re.fullmatch(r"Bushing Explorer: http://localhost:(\d+)/", line.strip())
        assert found and int(found.group(1)) > 0, line
        assert b"Bushing Explorer" in fetch(f"http://localhost:{found.group(1)}/")
    finally:
        proc.terminate()
        proc.wait(10)


def test_serve_refuses_a_busy_or_impossible_port(capsys):
    import socket

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        status, _, err = run(["serve", "--port", port, "--address", "127.0.0.1"], capsys)
    assert status == 2 and err.count("\n") == 1 and "cannot listen" in err
    status, _, err = run(["serve", "--port", 70000], capsys)
    assert status == 2 and "65535" in err


def test_the_command_line_loads_the_browser_libraries_only_to_serve(designs, tmp_path):
    # `bushing card` and every other command run without Panel, Bokeh or HoloViews; `serve` alone
    # needs them
    code = ("import sys\nfrom cli.main import main\n"
            f"main(['card', {str(designs['axial'])!r}, '--freq', '10', '--amp-mm', '0.1', '--amp-rad', '0.01',"
            f" '-o', {str(tmp_path / 'card.csv')!r}])\n"
            "print(sorted(m for m in ('panel', 'bokeh', 'holoviews') if m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=Path(__file__).resolve().parents[1],
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
    assert (tmp_path / "card.csv").read_text().startswith("mode,")


@pytest.mark.parametrize("shape", [None, "thesis", "finite"])
def test_card_and_export_give_each_direction_the_stiffness_of_its_design_file(shape, capsys, tmp_path):
    """One design file, one number per direction, whatever the command (docs/files.md: without a
    shape, the closed forms for axial and torsion and the table for radial and conical; ``finite``,
    the table everywhere): the card's rows and the export's rows of the design's own mode are
    `bushing stiffness` of the same file taken into that direction."""
    base = json.loads(json.dumps(PAPER_B.to_dict()))
    if shape is not None:
        base["shape"] = shape
    amplitude = {"axial": 1e-4, "radial": 1e-4, "torsion": 0.01, "conical": 0.01}
    expected = {}
    for mode, x in amplitude.items():
        data = dict(base, mode=mode)
        if mode in ("radial", "conical") and shape == "thesis":
            data.pop("shape")  # no closed form of the thesis in these directions: the table
        path = tmp_path / f"{mode}.json"
        path.write_text(json.dumps(data), encoding="utf-8")
        status, out, err = run(["stiffness", path, "--freq", 10, 10, 1, "--amp", x], capsys)
        assert status == 0, err
        expected[mode] = read_csv(out)[1][0, 4]
    path = tmp_path / "design.json"
    path.write_text(json.dumps(base), encoding="utf-8")
    status, out, err = run(["card", path, "--freq", 10, "--amp-mm", 0.1, "--amp-rad", 0.01], capsys)
    assert status == 0, err
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [r["mode"] for r in rows] == ["axial", "radial", "torsion", "conical"]
    for r in rows:
        assert float(r["magnitude"]) == pytest.approx(expected[r["mode"]], rel=1e-10)
    status, out, err = run(["export", path, "--format", "table", "--freq", 10, 10, 1, "--amp", 1e-4], capsys)
    assert status == 0, err
    axial = [r for r in csv.DictReader(io.StringIO(out)) if r["mode"] == "axial"]
    assert float(axial[0]["magnitude"]) == pytest.approx(expected["axial"], rel=1e-10)
    table = stiffness(PAPER_B.replace(shape="finite"), [10.0], [1e-4]).magnitude[0, 0]
    if shape == "finite":
        assert expected["axial"] == pytest.approx(table, rel=1e-10)
    else:  # eq 18's closed form: 3.5 % stiffer than the finite-length table for Paper B
        assert expected["axial"] == pytest.approx(stiffness(PAPER_B, [10.0], [1e-4]).magnitude[0, 0], rel=1e-10)
        assert expected["axial"] > 1.03 * table


def _descendants(pid: int) -> set[int]:
    """The processes under ``pid`` (Linux /proc), its children's children included."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found, todo = set(), [pid]
    while todo:
        parent = todo.pop()
        for child, ppid in parents.items():
            if ppid == parent and child not in found:
                found.add(child)
                todo.append(child)
    return found


def _running(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _stopped_with_its_workers(how: int) -> int | None:
    """Start `bushing serve`, send it the signal ``how``, and wait (bounded by count, about 60 s
    at most) for every process it had started to end: the server's exit status. Asserts that
    none is left; kills whatever is, so that a failure leaves nothing running."""
    import signal
    import time

    proc = subprocess.Popen([sys.executable, "-m", "cli.main", "serve", "--port", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    workers: set[int] = set()
    try:
        found = re.fullmatch(r"Bushing Explorer: http://localhost:(\d+)/", proc.stdout.readline().strip())
        assert found, "no URL printed"
        assert b"Bushing Explorer" in fetch(f"http://localhost:{found.group(1)}/")
        workers = _descendants(proc.pid)
        assert len(workers) >= 3  # the resource tracker, the forkserver and its worker
        proc.send_signal(how)
        status = proc.wait(60)
        for _ in range(600):
            if not any(_running(p) for p in workers):
                break
            time.sleep(0.1)
        assert not [p for p in workers if _running(p)]
        return status
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
        proc.stdout.close()
        for p in workers:
            if _running(p):
                os.kill(p, signal.SIGKILL)


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads the process table from /proc")
def test_a_killed_server_leaves_no_worker_process_behind():
    """SIGKILL (the kernel's out-of-memory killer, a forced stop) gives the server no chance to
    stop its worker processes: the worker notices its server gone and ends, and with it the
    forkserver and the resource tracker, which it held open (all three ran on, orphaned)."""
    import signal

    assert _stopped_with_its_workers(signal.SIGKILL) == -signal.SIGKILL


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads the process table from /proc")
def test_serve_stops_with_its_worker_processes_on_sigterm():
    """SIGTERM (a container's or a service manager's stop) ends `bushing serve` with status 0, and
    its worker processes (the diagnosis' forkserver, worker and resource tracker) end with it:
    SIGTERM used to kill the server alone and leave them running, orphaned, at every stop."""
    import signal

    assert _stopped_with_its_workers(signal.SIGTERM) == 0
