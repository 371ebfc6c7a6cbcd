"""Designs and the design file: round trips and every refusal, naming key and rule."""

import copy
import json
import math

import pytest

from core import PAPER_B, TABLE_1, Design, DesignError, Geometry, Material, loads_design
from core.io.design_file import dumps_design, read_design, write_design


def paper_b_dict():
    return copy.deepcopy(PAPER_B.to_dict())


@pytest.mark.parametrize("design", [PAPER_B, TABLE_1])
def test_round_trip_through_file(tmp_path, design):
    path = tmp_path / "d.json"
    write_design(design, path)
    assert read_design(path) == design
    assert loads_design(dumps_design(design)) == design


def test_format_example_of_formats_md_reads():
    text = """{
      "name": "VP 40/70120 (Paper B)",
      "mode": "axial",
      "geometry": {"inner_radius": 0.020, "outer_radius": 0.035, "length": 0.090},
      "material": {"shear_modulus": 2.42e6, "fractional_coefficient": 6.0e5,
        "fractional_order": 0.20, "friction_stress_max": 1.92e4, "friction_strain_half": 4.0e-3}
    }"""
    assert loads_design(text) == PAPER_B


def test_name_is_optional_and_integers_are_numbers():
    data = paper_b_dict()
    del data["name"]
    data["material"]["fractional_order"] = 1
    design = loads_design(json.dumps(data))
    assert design.name is None and design.material.fractional_order == 1.0


def test_designs_are_immutable_and_hashable():
    with pytest.raises(AttributeError):
        PAPER_B.geometry.length = 1.0
    assert hash(PAPER_B) == hash(loads_design(dumps_design(PAPER_B)))


def _refusal(mutate):
    data = paper_b_dict()
    mutate(data)
    with pytest.raises(DesignError) as info:
        loads_design(json.dumps(data))
    return info.value


GEOMETRY_KEYS = ["inner_radius", "outer_radius", "length"]
MATERIAL_POSITIVE = [
    "shear_modulus",
    "fractional_coefficient",
    "friction_stress_max",
    "friction_strain_half",
]


@pytest.mark.parametrize("key", GEOMETRY_KEYS)
@pytest.mark.parametrize("value", [0.0, -0.01])
def test_non_positive_sizes_refused(key, value):
    err = _refusal(lambda d: d["geometry"].__setitem__(key, value))
    assert err.key == f"geometry.{key}"
    assert "positive" in str(err) and key in str(err)


@pytest.mark.parametrize("key", MATERIAL_POSITIVE)
@pytest.mark.parametrize("value", [0.0, -1.0])
def test_non_positive_moduli_refused(key, value):
    err = _refusal(lambda d: d["material"].__setitem__(key, value))
    assert err.key == f"material.{key}" and "positive" in str(err)


@pytest.mark.parametrize("outer", [0.020, 0.019])
def test_outer_not_beyond_inner_refused(outer):
    err = _refusal(lambda d: d["geometry"].__setitem__("outer_radius", outer))
    assert err.key == "geometry.outer_radius" and "b > a" in str(err)


@pytest.mark.parametrize("alpha", [0.0, -0.2, 1.0000001, 2.0])
def test_fractional_order_outside_unit_interval_refused(alpha):
    err = _refusal(lambda d: d["material"].__setitem__("fractional_order", alpha))
    assert err.key == "material.fractional_order" and "(0, 1]" in str(err)


def test_fractional_order_one_accepted_and_is_a_viscous_damper():
    """α = 1 is allowed: m D¹ε is a viscous stress m dε/dt, whose modulus is iωm/2."""
    from core.material import fractional_modulus

    material = Material(2e6, 1e5, 1.0, 1e4, 1e-3)
    assert material.fractional_order == 1.0
    f = [0.5, 10.0, 300.0]
    expected = [1j * math.pi * fi * 1e5 for fi in f]
    assert fractional_modulus(f, material.fractional_coefficient, material.fractional_order) == pytest.approx(expected)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), "2e6", None, True, [1]])
def test_non_numbers_and_non_finite_refused(value):
    err = _refusal(lambda d: d["material"].__setitem__("shear_modulus", value))
    assert err.key == "material.shear_modulus"


def test_nan_in_json_text_refused():
    text = dumps_design(PAPER_B).replace("0.09", "NaN")
    with pytest.raises(DesignError, match="geometry.length"):
        loads_design(text)


@pytest.mark.parametrize(
    "section,key", [("geometry", k) for k in GEOMETRY_KEYS] + [("material", "fractional_order")]
)
def test_missing_keys_refused(section, key):
    err = _refusal(lambda d: d[section].pop(key))
    assert err.key == f"{section}.{key}" and "missing" in str(err)


@pytest.mark.parametrize("top", ["mode", "geometry", "material"])
def test_missing_top_level_keys_refused(top):
    err = _refusal(lambda d: d.pop(top))
    assert err.key == top and "missing" in str(err)


@pytest.mark.parametrize(
    "where,mutate",
    [
        ("colour", lambda d: d.__setitem__("colour", "black")),
        ("geometry.width", lambda d: d["geometry"].__setitem__("width", 0.01)),
        ("material.density", lambda d: d["material"].__setitem__("density", 1100)),
    ],
)
def test_unknown_keys_refused(where, mutate):
    err = _refusal(mutate)
    assert err.key == where and "unknown key" in str(err)


@pytest.mark.parametrize("mode", ["radial-ish", "", 3, None, "Axial"])
def test_bad_mode_refused(mode):
    err = _refusal(lambda d: d.__setitem__("mode", mode))
    assert err.key == "mode" and "axial" in str(err)


@pytest.mark.parametrize("text", ["", "{", "[1, 2]", '"design"'])
def test_not_a_design_object_refused(text):
    with pytest.raises(DesignError):
        loads_design(text)


def test_unreadable_file_refused(tmp_path):
    with pytest.raises(DesignError, match="cannot read"):
        read_design(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(DesignError):
        read_design(bad)


def test_api_refuses_at_the_door():
    with pytest.raises(DesignError, match="geometry.outer_radius"):
        Geometry(0.02, 0.01, 0.05)
    with pytest.raises(DesignError, match="geometry.length"):
        Geometry(0.01, 0.02, math.nan)
    with pytest.raises(DesignError, match="mode"):
        Design("shear", PAPER_B.geometry, PAPER_B.material)


def test_replace_revalidates():
    assert PAPER_B.replace(length=0.1).geometry.length == 0.1
    with pytest.raises(DesignError, match="outer_radius"):
        PAPER_B.replace(outer_radius=0.01)


# --- effects -----------------------------------------------------------------------------


def test_effects_round_trip():
    effects = {"inertia": {"mass": 1.5}, "nonuniform_strain": {}, "wave_effects": {"density": 1100}}
    design = PAPER_B.replace(effects=effects)
    assert design.effect_parameters == {
        "inertia": {"mass": 1.5},
        "nonuniform_strain": {},
        "wave_effects": {"density": 1100.0},
    }
    assert loads_design(dumps_design(design)) == design


@pytest.mark.parametrize(
    "effects,key",
    [
        ({"magnetism": {}}, "effects.magnetism"),
        ({"friction": {"friction_stress_max": 1e4}}, "effects.friction"),
        ({"inertia": {}}, "effects.inertia.mass"),
        ({"inertia": {"mass": -1}}, "effects.inertia.mass"),
        ({"inertia": {"mass": "heavy"}}, "effects.inertia.mass"),
        ({"viscous": {"viscosity": 1, "extra": 2}}, "effects.viscous.extra"),
        ({"viscous": 3}, "effects.viscous"),
        ([], "effects"),
    ],
)
def test_bad_effects_refused(effects, key):
    err = _refusal(lambda d: d.__setitem__("effects", effects))
    assert err.key == key


def test_every_direction_and_the_shape_round_trip():
    from core.io.design_file import design_from_dict, dumps_design, loads_design

    for mode in ("axial", "torsion", "radial", "conical"):
        for shape in (None, "finite", "long"):
            if mode == "conical" and shape == "long":
                with pytest.raises(DesignError, match="shape"):
                    PAPER_B.replace(mode=mode, shape=shape)
                continue
            d = PAPER_B.replace(mode=mode, shape=shape)
            assert loads_design(dumps_design(d)) == d
    data = PAPER_B.to_dict()
    data["shape"] = "short"
    with pytest.raises(DesignError, match="shape"):
        design_from_dict(data)


def test_the_shape_words_of_the_design_file():
    """The design file's ``shape`` is ``thesis`` or ``finite`` (docs/files.md): ``thesis`` gives the
    long-bushing closed forms, eq 18 axially (2πL / ln(b/a), computed here), and is what a file is
    written with; ``long``, the word earlier versions wrote, reads as the same design; anything
    else, or ``thesis`` across the axis (radial, conical: no closed form of the thesis, as
    docs/files.md says), is refused by its key; a radial ``long`` (the plane-strain closed form)
    is read and written as such."""
    from core.io.design_file import design_from_dict

    a, b, length = (PAPER_B.geometry.inner_radius, PAPER_B.geometry.outer_radius, PAPER_B.geometry.length)
    for word in ("thesis", "long"):
        data = paper_b_dict()
        data["shape"] = word
        design = design_from_dict(data)
        assert design.shape_kind == "long"
        assert design.shape_factor == pytest.approx(2 * math.pi * length / math.log(b / a), rel=1e-12)
        assert json.loads(dumps_design(design))["shape"] == "thesis"
    finite = paper_b_dict()
    finite["shape"] = "finite"
    assert json.loads(dumps_design(design_from_dict(finite)))["shape"] == "finite"
    for word, rule in [("Thesis", "must be one of thesis, finite, got 'Thesis'"), (18, "must be one of thesis, finite, got 18"),
                       ("short", "must be one of thesis, finite")]:
        data = paper_b_dict()
        data["shape"] = word
        with pytest.raises(DesignError, match=rule) as caught:
            design_from_dict(data)
        assert caught.value.key == "shape"
    for mode in ("radial", "conical"):  # the thesis has no closed form across the axis
        data = paper_b_dict()
        data.update(mode=mode, shape="thesis")
        with pytest.raises(DesignError, match=f"{mode}: the thesis' closed forms are axial .eq 18. and torsion .eq 17.; "
                                              "use shape 'finite'") as caught:
            design_from_dict(data)
        assert caught.value.key == "shape"
    # the plane-strain radial closed form, no formula of the thesis, keeps this project's word
    radial = paper_b_dict()
    radial.update(mode="radial", shape="long")
    design = design_from_dict(radial)
    assert design.shape_kind == "long" and json.loads(dumps_design(design))["shape"] == "long"


@pytest.mark.parametrize("where", ["key", "mode", "shape", "number", "effect"])
def test_a_long_key_or_value_is_quoted_short(where):
    """A design file's message quotes what it refuses in a few dozen characters, however long the
    key or value (a 300 000-character one made a message line of 300 kB), naming the same key."""
    data = paper_b_dict()
    long = "q" * 300_000
    if where == "key":
        data[long] = 1
    elif where == "mode":
        data["mode"] = long
    elif where == "shape":
        data["shape"] = long
    elif where == "number":
        data["material"]["shear_modulus"] = long
    else:
        data["effects"] = {long: {}}
    with pytest.raises(DesignError) as caught:
        loads_design(json.dumps(data))
    assert len(str(caught.value)) < 300 and "q" * 30 in str(caught.value) and "…" in str(caught.value)
