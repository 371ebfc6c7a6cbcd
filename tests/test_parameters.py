"""The one table of design parameters, modes and units (core/parameters.py) against what fixes it
from outside: the documentation, the SI prefixes, dimensional analysis, the model's branches and
the reference designs; and no second list of modes or parameters in the core or the command line."""

import ast
import math
import re
from dataclasses import fields
from pathlib import Path

import numpy as np

from core.design import PAPER_B, TABLE_1
from core.effects import branch_moduli
from core.parameters import (
    BRANCH_PARAMETERS,
    BY_NAME,
    GEOMETRY,
    MATERIAL,
    MODE_TABLE,
    MODES,
    NAMES,
    OPTIONAL,
    PARAMETERS,
)
from core.parts import Geometry, Material, as_dict
from core.registry import parameter, parameter_unit

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _design_parameter_rows() -> dict[str, list[str]]:
    """docs/model.md, "Symbols and units": the cells of each row naming a parameter (`name`)."""
    text = (DOCS / "model.md").read_text(encoding="utf-8")
    section = text.split("## Symbols and units", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 7 and re.fullmatch(r"`\w+`", cells[1]):
            rows[cells[1].strip("`")] = cells
    return rows


def test_the_model_page_shows_every_design_parameter_as_the_table_has_it():
    rows = _design_parameter_rows()
    assert list(rows) == [p.name for p in PARAMETERS]  # none the page lacks, none the table lacks, in order
    for name, (symbol, _, si, shown, factor, link, meaning) in rows.items():
        p = BY_NAME[name]
        assert (symbol, si, shown, link.strip("`"), meaning) == (p.symbol, p.unit.si, p.unit.display, p.url_key,
                                                                 p.doc), name
        assert math.isclose(float(factor), p.unit.factor, rel_tol=1e-12), name


def test_the_link_keys_are_those_the_files_page_documents():
    """docs/files.md names the tolerances' keys of a link (``tol=mu:10``), the table's in its
    order; a parameter's own key in the link (docs/model.md) begins with it."""
    text = (DOCS / "files.md").read_text(encoding="utf-8")
    listed = re.search(r"`tol=[^`]*`[^)]*?keys ((?:`[^`]+`,\s*)+)percents", text)
    assert listed, "docs/files.md no longer lists the tolerances' keys of a link"
    # the parameters with tolerances: every design's (not the optional bulk modulus)
    assert re.findall(r"`([^`]+)`", listed.group(1)) == [BY_NAME[n].tolerance_key for n in NAMES]
    rows = _design_parameter_rows()
    assert len(rows) == len(PARAMETERS)
    for name, cells in rows.items():
        p, link, shown = BY_NAME[name], cells[5].strip("`"), cells[3]
        assert link == p.tolerance_key if shown == "–" else link.startswith(f"{p.tolerance_key}_"), name


# ---- units: SI prefixes and dimensions ----------------------------------------------------------

PREFIXES = {"": 1.0, "k": 1e3, "M": 1e6, "G": 1e9, "m": 1e-3}


def _prefix_factor(display: str, si: str) -> float:
    """The factor display → SI that SI prefixes give: ``kN/mm`` of ``N/m`` is 1e3 / 1e-3."""
    factor = 1.0
    for k, (shown, base) in enumerate(zip(display.split("/"), si.split("/"), strict=True)):
        assert shown.endswith(base) and shown[: len(shown) - len(base)] in PREFIXES, (display, si)
        factor *= PREFIXES[shown[: len(shown) - len(base)]] ** (1 if k == 0 else -1)
    return factor


def test_every_display_unit_is_the_si_unit_with_the_prefix_its_factor_says():
    units = [p.unit for p in PARAMETERS] + [u for m in MODE_TABLE for u in (m.amplitude, m.stiffness, m.force)]
    for unit in units:
        assert math.isclose(_prefix_factor(unit.display, unit.si), unit.factor, rel_tol=1e-12), unit


BASE = {"kg": {"M": 1}, "m": {"L": 1}, "s": {"T": 1}, "N": {"M": 1, "L": 1, "T": -2}, "rad": {}}


def _dimension(unit: str) -> dict[str, int]:
    """Mass, length and time exponents of a unit such as ``N·m/rad`` or ``kg·m²``."""
    out: dict[str, int] = {}
    for k, part in enumerate(unit.split("/")):
        for factor in part.split("·"):
            base, power = (factor[:-1], 2) if factor.endswith("²") else (factor, 1)
            for d, n in BASE[base].items():
                out[d] = out.get(d, 0) + (1 if k == 0 else -1) * power * n
    return {d: n for d, n in out.items() if n}


def _product(*dims: dict[str, int]) -> dict[str, int]:
    out: dict[str, int] = {}
    for dim in dims:
        for d, n in dim.items():
            out[d] = out.get(d, 0) + n
    return {d: n for d, n in out.items() if n}


def test_stiffness_is_load_per_drive_and_an_apparent_mass_makes_its_load_from_an_acceleration():
    """Dimensions fix each mode's units: K = F / x̂, and the apparent mass M of the inertia effect
    turns the drive's acceleration into the load, F = M ẍ (so kg in a translation, kg·m² in a
    rotation, whose angle has no dimension), also for a rig tied to another mode."""
    per_second_squared = {"T": -2}
    for m in MODE_TABLE:
        force, drive = _dimension(m.force.si), _dimension(m.amplitude.si)
        assert _dimension(m.stiffness.si) == _product(force, {d: -n for d, n in drive.items()}), m.name
        for design_mode in MODES:
            name = "inertia.mass" if design_mode == m.name else f"inertia@{m.name}.mass"
            mass = _dimension(parameter_unit(name, design_mode))
            assert _product(mass, drive, per_second_squared) == force, (m.name, design_mode)


# ---- the fit's view of the table ---------------------------------------------------------------


def test_the_reference_designs_lie_inside_every_fitting_range():
    for design in (PAPER_B, TABLE_1):
        for name, value in as_dict(design.material).items():
            lo, hi = parameter(name).bounds
            assert lo < value < hi, (design.name, name)


def test_the_design_file_keys_are_the_tables_in_its_order():
    assert tuple(f.name for f in fields(Geometry)) == GEOMETRY
    assert tuple(f.name for f in fields(Material)) == MATERIAL + OPTIONAL
    assert all(f.default is None for f in fields(Material) if f.name in OPTIONAL)
    assert all(BY_NAME[n].fit_range is None for n in GEOMETRY)
    assert all(BY_NAME[n].fit_range is not None for n in MATERIAL)


def test_each_material_parameter_moves_its_own_branch_of_the_modulus_only():
    """The branches the table gives the parameters are the model's: a parameter changed by 10 %
    moves µ_eq's elastic, fractional (viscoelastic) or friction part, and no other."""
    parts = {"elastic": "elastic", "fractional": "viscoelastic", "friction": "friction"}
    f, eps = np.array([0.3, 30.0]), np.array([[1e-4], [3e-3]])
    base = branch_moduli(PAPER_B.material, {}, f, eps)
    assert sorted(n for names in BRANCH_PARAMETERS.values() for n in names) == sorted(MATERIAL)
    for branch, names in BRANCH_PARAMETERS.items():
        for name in names:
            changed = PAPER_B.replace(**{name: 0.9 * getattr(PAPER_B.material, name)})
            moved = {part for part, k in branch_moduli(changed.material, {}, f, eps).items()
                     if not np.allclose(k, base[part], rtol=1e-9, atol=0)}
            assert moved == {parts[branch]}, name


# ---- no second list ----------------------------------------------------------------------------

# values by mode or by parameter that are no list of them: the finite-element model's symmetry
# conditions of each mode, the design search's default limits of each size
KEPT = {("core/shape.py", "_HELD"), ("core/io/targets.py", "DEFAULT_LIMITS"),
        # and the what-ifs' radial/axial ratio: one pair of modes, in the order of the quotient
        ("app/targets_form.py", "STIFFNESS_RATIO")}


def _typed_out(node: ast.AST) -> bool:
    """A tuple, list or set of two or more mode (or parameter) names, or a dict keyed by them."""
    if isinstance(node, ast.Dict):
        items = node.keys
    elif isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        items = node.elts
    else:
        return False
    words = [i.value for i in items if isinstance(i, ast.Constant) and isinstance(i.value, str)]
    return any(sum(w in names for w in words) >= 2 for names in (MODES, NAMES))


def test_no_list_of_modes_or_parameters_is_typed_out_in_the_core_the_command_line_or_the_app():
    found = []
    for path in sorted(p for package in ("core", "cli", "app") for p in ROOT.joinpath(package).rglob("*.py")):
        where = path.relative_to(ROOT).as_posix()
        if where == "core/parameters.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        kept = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Assign)
                for t in n.targets if isinstance(t, ast.Name) and (where, t.id) in KEPT}
        skip = {id(sub) for n in ast.walk(tree) if id(n) in kept for sub in ast.walk(n)}
        found += [f"{where}:{n.lineno}: {ast.unparse(n)[:60]}" for n in ast.walk(tree)
                  if id(n) not in skip and _typed_out(n)]
    assert found == []
