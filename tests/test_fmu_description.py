"""What the FMU's modelDescription.xml says (docs/fmu.md), without a C compiler: its parameters
are the element's own list (:meth:`core.element.Coefficients.parameters`, docs/element.md's
table), and its default step is the longest that the held input allows (Element.held_error)."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest

from core import PAPER_B
from core.element import CHANNELS, Element, coefficients
from core.element.element import HELD_LIMIT
from fmu import FmuError, write_fmu
from fmu.description import UNITS

DOCS = Path(__file__).resolve().parent.parent / "docs"
DESIGNS = {
    "Paper B, 3 slices": (PAPER_B, 3, (0.1, 2000.0)),
    "a bulk spring, α = 0.4": (PAPER_B.replace(shape="finite", bulk_modulus=2.0e8, fractional_order=0.4), 1,
                               (0.1, 50.0)),
    "α = 0.8": (PAPER_B.replace(fractional_order=0.8), 2, (0.1, 50.0)),
    "α = 1": (PAPER_B.replace(fractional_order=1.0), 1, (0.1, 50.0)),
}


def description(co, tmp_path) -> ET.Element:
    result = write_fmu(co, tmp_path / "b.fmu", compiler=None)  # source only: no compiler needed
    return ET.fromstring(zipfile.ZipFile(result.path).read("modelDescription.xml"))


@pytest.fixture(scope="module", params=DESIGNS)
def written(request, tmp_path_factory):
    design, slices, band = DESIGNS[request.param]
    co = coefficients(design, slices, band)
    return co, description(co, tmp_path_factory.mktemp("fmu"))


def test_the_parameters_are_the_elements_own_list(written):
    co, root = written
    rows = [(v.get("name"), v.get("description"), v.find("Real").get("unit"), float(v.find("Real").get("start")))
            for v in root.iter("ScalarVariable") if v.get("causality") == "parameter"]
    assert rows == [(p.name, p.description, p.unit, p.value) for p in co.parameters()]
    assert [v.get("valueReference") for v in root.iter("ScalarVariable")][12:] == [str(12 + k)
                                                                                  for k in range(len(rows))]
    names = [r[0] for r in rows]
    assert f"rate[{len(co.rate)}]" in names or not co.rate  # indices from 1 …
    assert "rate[0]" not in names and "dz.S[0]" not in names and "dz.S[1]" in names  # … never 0
    # every unit is defined, with its SI base units where the exponents are whole
    units = {u.get("name"): u for u in root.iter("Unit")}
    for _, _, unit, _ in rows:
        assert unit in units
        base = units[unit].find("BaseUnit")
        assert (base.attrib if base is not None else {}) == {k: str(v) for k, v in UNITS.get(unit, {}).items()}


def test_the_default_step_is_the_longest_the_held_input_allows(written):
    """Under the element's own warning threshold over the band at the step; past it at 1.5 times it."""
    co, root = written
    h = float(root.find("DefaultExperiment").get("stepSize"))
    element = Element(co)
    mag, phase = element.held_error(h)
    assert mag <= HELD_LIMIT[0] and phase <= HELD_LIMIT[1]
    mag, phase = element.held_error(1.5 * h)
    assert mag > HELD_LIMIT[0] or phase > HELD_LIMIT[1]


def test_element_md_s_table_names_every_parameter_with_its_unit():
    """docs/element.md's coefficient table, read as patterns (``<channel>`` any input, ``[j]`` an
    index, α the order's value), matches every parameter's name and unit, in order."""
    text = (DOCS / "element.md").read_text(encoding="utf-8")
    table = text[text.index("| name | unit |"):].split("\n\n")[0].splitlines()[2:]
    co = coefficients(PAPER_B.replace(shape="finite", bulk_modulus=2.0e8), 1)
    co3 = coefficients(PAPER_B, 3)
    for c in (co, co3):
        patterns = []
        for line in table:
            name, unit = (cell.strip().strip("`") for cell in line.split("|")[1:3])
            name = re.escape(name).replace("<channel>", "(?:" + "|".join(CHANNELS) + ")")
            name = re.sub(r"\\\[[jk]\\\]", r"\\[[1-9][0-9]*\\]", name)
            units = [u.strip().strip("`").replace("α", f"{c.alpha:g}") for u in unit.split(" or ")]
            patterns.append((re.compile(name), units))
        rows = []
        for p in c.parameters():
            found = [k for k, (pattern, units) in enumerate(patterns) if pattern.fullmatch(p.name) and p.unit in units]
            assert len(found) == 1, (p.name, p.unit)
            rows += found
        # the table's rows in its order, every one used, the channel's three once per channel
        assert [k for i, k in enumerate(rows) if not i or k != rows[i - 1]] == [*range(9), *[9, 10, 11] * 6]


def test_write_fmu_takes_the_elements_coefficients_only(tmp_path):
    with pytest.raises(FmuError, match=r"coefficients: give core\.element\.coefficients"):
        write_fmu(coefficients(PAPER_B).as_dict(), tmp_path / "b.fmu", compiler=None)
    assert not (tmp_path / "b.fmu").exists()
