"""Exports (docs/export.md): each file is written, read back by a parser written here from the
formats' documentation (not by the writer's code), and compared with the core's stiffness."""

import io
import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cli.main import main
from core import PAPER_B, force_history, write_design
from core.bushing import stiffness_points, strain_factor
from core.card import CARD_MODES, card_design
from core.io.export import direction_grid, export

FREQS = np.linspace(1.0, 100.0, 5)
AMPS = [1e-5, 1e-4]
DOCS = Path(__file__).resolve().parents[1] / "docs" / "export.md"


def expected(mode, amp_design_mode, f, design=PAPER_B):
    """The core's K of ``mode`` at the equivalent strain of ``amp_design_mode`` in the design's
    mode."""
    own = card_design(design, design.mode)
    eps = strain_factor(own.geometry, own.mode, own.shape) * amp_design_mode
    d = card_design(design, mode)
    amp = eps / strain_factor(d.geometry, mode, d.shape)
    return amp, complex(stiffness_points(d, f, amp))


def test_neutral_csv_table():
    table = pd.read_csv(io.StringIO(export(PAPER_B, "table", FREQS, AMPS)))
    assert len(table) == 4 * len(AMPS) * len(FREQS)
    # the design's own mode: as given
    assert set(table.loc[table["mode"] == "axial", "amplitude"]) == set(AMPS)
    for _, row in table.sample(12, random_state=0).iterrows():
        amps = table.loc[(table["mode"] == row["mode"]), "amplitude"].unique()
        i = int(np.argmin(np.abs(np.log(amps / row["amplitude"]))))
        amp, k = expected(row["mode"], AMPS[i], row["frequency_hz"])
        assert row["amplitude"] == pytest.approx(amp, rel=1e-10)
        assert row["stiffness_real"] == pytest.approx(k.real, rel=1e-10)
        assert row["loss_factor"] == pytest.approx(k.imag / k.real, rel=1e-10)
        assert row["stiffness_unit"] == ("N/m" if row["mode"] in ("axial", "radial") else "N·m/rad")


def test_neutral_json_table():
    data = json.loads(export(PAPER_B, "table", FREQS, AMPS, as_json=True))
    assert data["frequency_hz"] == FREQS.tolist() and data["header"]["design"]["mode"] == "axial"
    for mode in CARD_MODES:
        d = data["directions"][mode]
        for i, a in enumerate(AMPS):
            for j, f in enumerate(FREQS):
                amp, k = expected(mode, a, f)
                assert d["amplitude"][i] == pytest.approx(amp, rel=1e-12)
                assert d["magnitude"][i][j] == pytest.approx(abs(k), rel=1e-12)


def nastran_cards(text):
    """Small-field fixed format: 8-character fields, field 1 the name (blank: continuation)."""
    cards = []
    for line in text.splitlines():
        if line.startswith("$") or not line.strip():
            continue
        fields = [line[i:i + 8].strip() for i in range(8, len(line), 8)]
        if line[:8].strip():
            cards.append([line[:8].strip(), *fields])
        else:
            cards[-1].extend(fields)
    return cards


def nastran_float(text):
    """Nastran reals: 1.5, 1.5E+6, and the short exponent 1.5+6 or 1.5-6."""
    m = re.fullmatch(r"([+-]?\d*\.\d*)([+-]\d+)", text)
    return float(f"{m.group(1)}e{m.group(2)}") if m else float(text)


def test_nastran_pbush_pbusht_tabled1():
    cards = nastran_cards(export(PAPER_B, "nastran", FREQS, AMPS))
    pbush = [c for c in cards if c[0] == "PBUSH"]
    pbusht = {int(c[1]): c for c in cards if c[0] == "PBUSHT"}
    tables = {int(c[1]): c for c in cards if c[0] == "TABLED1"}
    assert [int(c[1]) for c in pbush] == [1, 2]
    order = ("axial", "radial", "radial", "torsion", "conical", "conical")
    for card in pbush:
        pid = int(card[1])
        assert card[2] == "K" and card[9] == "" and card[10] == "GE"
        k_values = [nastran_float(v) for v in card[3:9]]
        ge_values = [nastran_float(v) for v in card[11:17]]
        t = pbusht[pid]
        assert t[2] == "K" and t[10] == "GE"
        for d, mode in enumerate(order):
            _, k0 = expected(mode, AMPS[pid - 1], FREQS[0])
            assert k_values[d] == pytest.approx(k0.real, rel=2e-5)
            assert ge_values[d] == pytest.approx(k0.imag / k0.real, rel=2e-5)
            for tid, part in ((int(t[3 + d]), "k"), (int(t[11 + d]), "ge")):
                table = tables[tid]
                assert table[2:4] == ["LINEAR", "LINEAR"]
                values = [v for v in table[4:] if v]
                assert values[-1] == "ENDT"
                xy = np.array([nastran_float(v) for v in values[:-1]]).reshape(-1, 2)
                np.testing.assert_allclose(xy[:, 0], FREQS, rtol=1e-6)
                for f, y in xy:
                    _, k = expected(mode, AMPS[pid - 1], f)
                    assert y == pytest.approx(k.real if part == "k" else k.imag / k.real, rel=2e-5)


def adams_sections(text):
    """TeimOrbit: [SECTION] headers, KEY = value lines, {column names} then rows of numbers."""
    sections, current = {}, None
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("$"):
            continue
        if line.startswith("[") and line.endswith("]"):
            current = sections.setdefault(line[1:-1], {"keys": {}, "rows": []})
        elif "=" in line and current is not None:
            key, value = (s.strip() for s in line.split("=", 1))
            current["keys"][key] = value.strip("'")
        elif line.startswith(("{", "(", "'")):
            continue
        elif current is not None:
            current["rows"].append([float(v) for v in line.split()])
    return sections


def test_adams_bus_file():
    sections = adams_sections(export(PAPER_B, "adams", [10.0], [1e-4]))
    assert sections["MDI_HEADER"]["keys"]["FILE_TYPE"] == "bus"
    assert sections["UNITS"]["keys"] == {"LENGTH": "meter", "ANGLE": "radians", "FORCE": "newton",
                                         "MASS": "kg", "TIME": "second"}
    for mode, curve, damping in (("axial", "Z_FORCE_CURVE", "Z_DAMPING"),
                                 ("radial", "Y_FORCE_CURVE", "Y_DAMPING"),
                                 ("torsion", "Z_TORQUE_CURVE", "RZ_DAMPING"),
                                 ("conical", "X_TORQUE_CURVE", "RX_DAMPING")):
        amp, k = expected(mode, 1e-4, 10.0)
        rows = np.array(sections[curve]["rows"])
        assert rows[:, 0].min() == pytest.approx(-amp) and rows[:, 0].max() == pytest.approx(amp)
        slope = np.polyfit(rows[:, 0], rows[:, 1], 1)[0]
        assert slope == pytest.approx(k.real, rel=1e-8)
        c = float(sections[damping]["keys"]["DAMPING"])
        assert c == pytest.approx(k.imag / (2 * math.pi * 10.0), rel=1e-8)


def test_the_co_simulation_loop_of_the_docs_gives_the_force_history():
    code = re.search(r"```python\n(.*?)```", DOCS.read_text(), re.DOTALL).group(1)
    code = code.replace("range(2000)", "range(300)")  # the same loop, shorter
    scope = {}
    exec(code, scope)  # noqa: S102 - the documentation's own example
    whole = force_history(PAPER_B, np.array(scope["record"]), 1e-3).force
    np.testing.assert_allclose(scope["forces"], whole, rtol=1e-9, atol=1e-9 * np.max(np.abs(whole)))


def test_the_command_line_export_and_its_limits(tmp_path, capsys):
    write_design(PAPER_B, tmp_path / "d.json")
    assert main(["export", str(tmp_path / "d.json"), "--format", "table", "--freq", "1", "100", "3",
                 "--amp", "1e-4", "-o", str(tmp_path / "t.json")]) == 0
    radial = json.loads((tmp_path / "t.json").read_text())["directions"]["radial"]
    assert radial["amplitude_unit"] == "m"
    assert main(["export", str(tmp_path / "d.json"), "--format", "nastran", "--freq", "1", "100",
                 "3", "--amp", "1e-4"]) == 0
    assert capsys.readouterr().out.count("PBUSH ") == 1
    refused_argv = ((["--format", "abaqus", "--freq", "1", "10", "2", "--amp", "1e-4"], "--format"),
                    (["--format", "table", "--freq", "1", "10", "100000", "--amp", "1e-4", "2e-4"],
                     "at most"))
    for argv, needle in refused_argv:
        with pytest.raises(SystemExit) as refused:
            main(["export", str(tmp_path / "d.json"), *argv])
        assert refused.value.code == 2 and needle in capsys.readouterr().err


def test_grid_amplitudes_follow_the_equivalent_strain():
    grid = direction_grid(PAPER_B.replace(mode="torsion"), FREQS, [0.01])
    assert grid["torsion"]["amplitude"][0] == pytest.approx(0.01)
    designs = {m: card_design(PAPER_B, m) for m in CARD_MODES}
    c = {m: strain_factor(d.geometry, m, d.shape) for m, d in designs.items()}
    for m in CARD_MODES:
        assert c[m] * grid[m]["amplitude"][0] == pytest.approx(grid["strain"][0], rel=1e-12)


def test_the_explorers_export_panel_writes_every_tool_format():
    from app.export import TOOL_FORMATS
    from app.main import App
    app = App()
    app.state.amplitude = 0.2  # mm
    texts = {label: app.export.tool_text(label) for label in TOOL_FORMATS}
    cards = nastran_cards(texts["Nastran bulk data (PBUSH)"])
    assert len([c for c in cards if c[0] == "PBUSH"]) == 6  # the operating amplitude and five more
    adams_file = adams_sections(texts["Adams bushing file (.bus)"])
    # the explorer's shape factors (long-bushing axial, by default): the explorer's own stiffness
    _, k = expected("axial", 0.2e-3, app.state.frequency_hz, app.state.design)
    assert abs(k - stiffness_points(app.state.design, app.state.frequency_hz, 0.2e-3)) <= 1e-12 * abs(k)
    slope = np.polyfit(*np.array(adams_file["Z_FORCE_CURVE"]["rows"]).T, 1)[0]
    assert slope == pytest.approx(k.real, rel=1e-8)
    table = pd.read_csv(io.StringIO(texts["Neutral table, every direction (CSV)"]))
    assert table["frequency_hz"].nunique() == 30 and set(table["mode"]) == set(CARD_MODES)
    header = json.loads(texts["Neutral table, every direction (JSON)"])["header"]
    assert header["design"] == app.state.design.to_dict()
    app.export.tool_format.value = "Adams bushing file (.bus)"
    assert app.export.tool_file.filename == "bushing.bus"


# ---- the command line's Adams file, read back by a parser of docs/export.md ---------------------

ADAMS_DIRECTIONS = (  # docs/export.md: curve, damping, mode, (column names); z is the bushing axis
    ("Z_FORCE_CURVE", "Z_DAMPING", "axial", ("disp", "force")),
    ("X_FORCE_CURVE", "X_DAMPING", "radial", ("disp", "force")),
    ("Y_FORCE_CURVE", "Y_DAMPING", "radial", ("disp", "force")),
    ("Z_TORQUE_CURVE", "RZ_DAMPING", "torsion", ("rot", "torque")),
    ("X_TORQUE_CURVE", "RX_DAMPING", "conical", ("rot", "torque")),
    ("Y_TORQUE_CURVE", "RY_DAMPING", "conical", ("rot", "torque")),
)


def teim_orbit(text):
    """A TeimOrbit file read strictly: `$` comments, `[SECTION]`, `KEY = value` (quotes off),
    `(SUBSECTION)`, `{col col}` naming the columns of the rows of numbers that follow, and
    a quoted comment string. Anything else is an error."""
    sections, current = {}, None
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("$"):
            continue
        if re.fullmatch(r"\[[A-Z_]+\]", line):
            assert line[1:-1] not in sections, f"line {number}: {line} twice"
            current = sections[line[1:-1]] = {"keys": {}, "columns": None, "rows": [], "text": []}
        elif (m := re.fullmatch(r"([A-Z_]+)\s*=\s*(.+)", line)) and current is not None:
            current["keys"][m.group(1)] = m.group(2).strip().strip("'")
        elif (m := re.fullmatch(r"\{\s*(.+?)\s*\}", line)) and current is not None:
            current["columns"] = tuple(m.group(1).split())
        elif re.fullmatch(r"\(\w+\)", line) or re.fullmatch(r"'.*'", line):
            current["text"].append(line.strip("'"))
        else:
            values = [float(v) for v in line.split()]  # a row of numbers, or a ValueError
            assert current is not None and current["columns"], number
            assert len(values) == len(current["columns"]), number
            current["rows"].append(values)
    return sections


def card_rows(design_path, freq, amp_mm, amp_rad, capsys):
    """`bushing card` as parsed CSV: mode → row."""
    assert main(["card", str(design_path), "--freq", str(freq), "--amp-mm", repr(float(amp_mm)),
                 "--amp-rad", repr(float(amp_rad))]) == 0
    table = pd.read_csv(io.StringIO(capsys.readouterr().out))
    return {row["mode"]: row for _, row in table.iterrows()}


def test_the_command_lines_adams_file_carries_the_cards_stiffness(tmp_path, capsys):
    """`bushing export --format adams` over a grid: linearised at its first frequency (10 Hz) and
    first amplitude (0.1 mm axially; every direction at the same equivalent strain). Each curve's
    slope is K' and each DAMPING is C = K''/ω of `bushing card` at that direction's amplitude."""
    design = tmp_path / "paper_b.json"
    write_design(PAPER_B, design)
    out = tmp_path / "bushing.bus"
    assert main(["export", str(design), "--format", "adams", "--freq", "10", "30", "3",
                 "--amp", "1e-4", "2e-4", "-o", str(out)]) == 0
    assert capsys.readouterr().out == ""
    sections = teim_orbit(out.read_text(encoding="utf-8"))
    assert set(sections) == {"MDI_HEADER", "UNITS"} | {s for d in ADAMS_DIRECTIONS for s in d[:2]}
    header = sections["MDI_HEADER"]
    assert header["keys"] == {"FILE_TYPE": "bus", "FILE_VERSION": "4.0", "FILE_FORMAT": "ASCII"}
    assert re.search(r"linearised at 10 Hz", " ".join(header["text"]))
    omega = 2 * math.pi * 10.0
    loss_factors = []
    for curve, damping, mode, columns in ADAMS_DIRECTIONS:
        section = sections[curve]
        assert section["columns"] == columns, curve
        x, force = np.array(section["rows"]).T
        peak = x.max()
        # five points through ±x̂ (10 printed digits)
        np.testing.assert_allclose(x, peak * np.array([-1, -0.5, 0, 0.5, 1]), rtol=1e-9,
                                   atol=1e-12 * peak)
        if mode == "axial":
            assert peak == pytest.approx(1e-4, rel=1e-12)  # the design's own mode: the first --amp
        rows = card_rows(design, 10, peak * 1e3 if mode in ("axial", "radial") else 0.1,
                         peak if mode in ("torsion", "conical") else 0.01, capsys)
        k = rows[mode]["stiffness_real"] + 1j * rows[mode]["stiffness_imag"]
        # the card's 12 digits against the file's 10: 2e-9 relative, and x̂ read to 10 digits
        np.testing.assert_allclose(force, k.real * x, rtol=1e-8, atol=1e-9 * abs(k.real) * peak,
                                   err_msg=curve)
        c = float(sections[damping]["keys"]["DAMPING"])
        assert c == pytest.approx(k.imag / omega, rel=1e-8), damping
        loss_factors.append(c * omega / (force[-1] / peak))
    # K = S µ_eq(ω, ε) (eqs 16-18): at one equivalent strain, one loss factor in every direction
    np.testing.assert_allclose(loss_factors, loss_factors[0], rtol=1e-8)
