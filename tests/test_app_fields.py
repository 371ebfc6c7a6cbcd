"""The explorer's design fields and its link against what the docs say: each field's parameter,
symbol and unit as docs/model.md and the README give them, the link's tolerance keys as
docs/files.md lists them, and the keys of links people have shared."""

import re
from dataclasses import fields
from pathlib import Path

import pytest

from app.bands import parse_tolerances
from app.link import URL_NAMES
from app.state import ExplorerState
from core import Design, Geometry, Material
from core.parameters import OPTIONAL
from core.whatif.tolerance import ToleranceError

ROOT = Path(__file__).resolve().parents[1]
PREFIXES = {"": 1.0, "m": 1e-3, "k": 1e3, "M": 1e6, "G": 1e9}  # the SI prefixes of the units shown
DESIGN_NAMES = tuple(f.name for f in fields(Geometry)) + tuple(f.name for f in fields(Material))
# the keys of a link as people have shared them (tests/ui opens such links): key → state parameter
SHARED = {"mode": "mode", "finite": "finite_length", "a_mm": "inner_radius_mm", "b_mm": "outer_radius_mm",
          "L_mm": "length_mm", "mu_MPa": "shear_modulus_mpa", "m_MPa": "fractional_coefficient_mpa",
          "alpha": "fractional_order", "sigma_kPa": "friction_stress_max_kpa", "eps_half": "friction_strain_half",
          "amp": "amplitude", "f_Hz": "frequency_hz", "fmin_Hz": "freq_min", "fmax_Hz": "freq_max",
          "K_GPa": "bulk_modulus_gpa", "tol": "tolerance_text", "bands": "band_on"}


def text(path: str) -> str:
    """A document's text, its line breaks as spaces."""
    return " ".join((ROOT / path).read_text(encoding="utf-8").split())


def documented_symbols() -> dict[str, tuple[str, str]]:
    """docs/model.md's "Symbols and units": name in files and code → (symbol, SI unit)."""
    rows = re.findall(r"^\| (\S+) \| `(\w+)` \| ([^|]+?) \|", (ROOT / "docs/model.md").read_text(encoding="utf-8"),
                      re.MULTILINE)
    return {name: (symbol, unit) for symbol, name, unit in rows}


def documented_display_units() -> dict[str, str]:
    """The README's left panel: symbol → the unit the explorer shows it in ("–" for a plain
    number): "the geometry in mm, the five material parameters (µ and m in MPa, …)"."""
    readme = text("README.md")
    symbols = documented_symbols()
    out = {symbols[n][0]: re.search(r"geometry in (\S+?),", readme).group(1) for n in DESIGN_NAMES[:3]}
    for part in re.search(r"the five material parameters \(([^)]*)\)", readme).group(1).split(", "):
        shown, unit = re.fullmatch(r"(.+?) (?:in (\S+)|plain)", part).groups()
        out.update({symbol: unit or "–" for symbol in shown.split(" and ")})
    for symbol, unit in re.findall(r"the bulk modulus (\S+) in (\S+) \(optional", readme):
        out[symbol] = unit
    return out


def test_each_design_field_shows_its_documented_parameter_in_its_documented_unit():
    symbols, shown = documented_symbols(), documented_display_units()
    assert set(shown) == {symbols[n][0] for n in DESIGN_NAMES}  # the README names all nine
    for name in DESIGN_NAMES:
        symbol, si = symbols[name]
        state = ExplorerState()
        (field,) = [p for p in state.param if p == name or p.startswith(f"{name}_")]
        words, unit = re.fullmatch(r"(.+) \((.+)\)", state.param[field].label).groups()
        assert words.endswith(f" {symbol}"), (field, words)
        assert unit.split("·")[0] == shown[symbol], (field, unit)  # MPa·s^α is shown "in MPa"
        prefix = "" if si == "–" else unit.removesuffix(si)  # mm: m × 1e-3; MPa·s^α: Pa·s^α × 1e6
        assert prefix in PREFIXES and prefix + si == unit, (field, unit, si)  # a plain number: "–" both
        shown_value = getattr(state, field)
        if shown_value is None:  # an optional field, empty at first: a value it takes (K = 1000 µ)
            shown_value = 1000 * state.design.material.shear_modulus / PREFIXES[prefix] / 1.1
        value = 1.1 * shown_value  # a valid design still (b stays above a)
        setattr(state, field, value)
        assert state.errors == {}
        group = state.design.geometry if name in DESIGN_NAMES[:3] else state.design.material
        assert getattr(group, name) == pytest.approx(value * PREFIXES[prefix], rel=1e-12)


def test_the_links_tolerance_keys_are_those_docs_files_md_lists():
    files = text("docs/files.md")
    example = re.search(r"\(`tol=([^&`]+)&bands=true`: (.+?); keys ((?:`\w+`, )+)percents from 0 to 89\)", files)
    tol, said, keys = example.group(1), example.group(2), re.findall(r"`(\w+)`", example.group(3))
    assert (URL_NAMES["tolerance_text"], URL_NAMES["band_on"]) == ("tol", "bands")
    by_symbol = {symbol: name for name, (symbol, _unit) in documented_symbols().items()}
    meant = {by_symbol[symbol]: float(pct) for symbol, pct in re.findall(r"(\S+) ±(\S+) %", said)}
    assert parse_tolerances(tol) == meant  # mu:10,L:1 is µ ±10 %, L ±1 %
    every = parse_tolerances(",".join(f"{key}:1" for key in keys))
    # one key per design parameter every design has, none left out (not the optional bulk modulus)
    assert sorted(every) == sorted(n for n in DESIGN_NAMES if n not in OPTIONAL)
    for wrong in ("mu_MPa:1", "mu:90", "mu:1,mu:2"):
        with pytest.raises(ToleranceError, match=", ".join(keys)):
            parse_tolerances(wrong)


def test_a_link_people_shared_still_opens_the_same_design():
    assert {key: name for name, key in URL_NAMES.items()} == SHARED
    link = {"mode": "axial", "a_mm": 18, "b_mm": 40, "L_mm": 70, "mu_MPa": 1.9, "m_MPa": 0.5, "alpha": 0.25,
            "sigma_kPa": 15, "eps_half": 0.003, "amp": 0.05, "f_Hz": 20}
    state = ExplorerState()
    state.apply_url_values({SHARED[key]: value for key, value in link.items()})
    assert state.errors == {}
    expected = Design("axial", Geometry(0.018, 0.040, 0.070), Material(1.9e6, 0.5e6, 0.25, 15e3, 0.003))
    got, want = state.design.to_dict(), expected.to_dict()
    for group in ("geometry", "material"):
        assert got[group] == pytest.approx(want[group], rel=1e-12)
    assert (state.amplitude, state.frequency_hz) == (0.05, 20)


def test_the_mode_and_amplitude_help_name_every_documented_mode():
    modes = re.search(r"the mode \((\w+), (\w+), (\w+) or (\w+):", text("README.md")).groups()
    state = ExplorerState()
    assert list(state.param.mode.objects) == list(modes)
    for mode in modes:
        assert mode in state.param.mode.doc.lower()
        assert mode in state.param.amplitude.doc  # the drive's unit in every mode (mm or rad)


@pytest.mark.parametrize(("code", "words"), [("outer_not_larger", "Must be larger than the inner radius a."),
                                              ("not_positive", "Must be positive."),
                                              ("order_range", "Must lie in (0, 1].")])
def test_the_panel_words_a_design_rule_by_its_code_not_by_its_english(code, words):
    from app.fields import _plain
    from core.rules import DesignError

    # the core may reword a rule at any time: the panel still says its own words for the code
    assert _plain(DesignError("geometry.outer_radius", "reworded by the core", code)) == words
    # and English that merely contains a phrase of another rule is not mistaken for it
    other = DesignError("material.shear_modulus", "must be positive and at most 1e12 Pa (b > a, (0, 1])", "out_of_range")
    assert _plain(other) == "Must be positive and at most 1e12 Pa (b > a, (0, 1])"


def test_each_field_shows_the_panel_words_of_the_core_s_rule():
    # end to end through the state: the core's refusals as the panel words them
    state = ExplorerState()
    state.param.update(inner_radius_mm=40.0)  # b = 35 mm
    assert state.errors == {"outer_radius_mm": "Must be larger than the inner radius a."}
    state.param.update(inner_radius_mm=20.0, shear_modulus_mpa=-1.0)
    assert state.errors == {"shear_modulus_mpa": "Must be positive."}
    state.param.update(shear_modulus_mpa=2.42, fractional_order=1.5)
    assert state.errors == {"fractional_order": "Must lie in (0, 1]."}


@pytest.mark.parametrize("text", ["mu:1_0", "mu:１０", "mu:١٠", "mu:nan", "mu:0x10"])
def test_a_links_tolerance_follows_the_one_number_rule(text):
    # as in the files and on the command line: plain ASCII decimals only (float() took 1_0 and １０)
    with pytest.raises(ToleranceError):
        parse_tolerances(text)
    assert parse_tolerances("mu:10,L:1.5e0") == {"shear_modulus": 10.0, "length": 1.5}
