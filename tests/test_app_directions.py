"""The explorer in every direction: radial and conical modes, the finite-length switch with how
far it is from the closed form, a geometry outside the shape-factor table, and the bushing card
tab holding the core's numbers."""

import numpy as np
import pytest

from app import units
from app.main import App
from core import PAPER_B, stiffness
from core.bushing import shape_factor, strain_factor
from core.card import card
from core.numbers import format_number
from tests.helpers import xy


@pytest.fixture
def app():
    return App()


@pytest.mark.parametrize("mode, unit", [("radial", "mm"), ("conical", "rad")])
def test_radial_and_conical_modes_draw_the_core_stiffness(app, mode, unit):
    s = app.state
    s.amplitude = 0.2  # mm, axial
    eps = strain_factor(s.design.geometry, "axial") * 0.2e-3
    s.mode = mode
    assert s.design.mode == mode and s.design.shape_kind == "finite" and s.errors == {}
    assert units.amplitude_unit(s.design.mode) == unit
    assert strain_factor(s.design.geometry, mode) * units.to_si_amplitude(s.amplitude, mode) == pytest.approx(eps,
                                                                                                           rel=1e-2)
    x, y = xy(app.plots.frame(("magnitude", "amplitude")), "operating point")
    expected = stiffness(s.design, s.frequency_hz, units.to_si_amplitude(x, mode)).magnitude[:, 0]
    np.testing.assert_allclose(units.display_stiffness(expected, mode), y, rtol=1e-9)
    assert app.inputs.finite_length.disabled
    assert "Finite-length S" in app.inputs.shape_note.object or "Conical S" in app.inputs.shape_note.object


def test_the_finite_length_switch_and_its_comparison(app):
    s = app.state
    assert s.design.shape is None and "in use: the long-bushing formula" in app.inputs.shape_note.object
    g = s.design.geometry
    ratio = shape_factor(g, "axial", "finite") / shape_factor(g, "axial", "long")
    assert f"{ratio:.3f} of the long-bushing formula" in app.inputs.shape_note.object
    # the change as a percentage with a true minus sign (it read "(-3.6 %)", issue #27 item 7)
    assert ratio < 1 and f"(−{100 * (1 - ratio):.3g} %)" in app.inputs.shape_note.object
    s.finite_length = True
    assert s.design.shape == "finite" and "in use: the finite-element" in app.inputs.shape_note.object
    x, y = xy(app.plots.frame(("magnitude", "amplitude")), "operating point")
    expected = stiffness(PAPER_B.replace(shape="finite"), s.frequency_hz, units.to_si_amplitude(x, "axial"))
    np.testing.assert_allclose(units.display_stiffness(expected.magnitude[:, 0], "axial"), y, rtol=1e-9)


def test_a_geometry_outside_the_table_is_a_message_not_a_crash(app):
    s = app.state
    s.mode = "radial"
    s.length_mm = 5000.0  # L/(b − a) = 333: beyond the table
    assert "length_mm" in s.errors and "L/(b − a)" in s.errors["length_mm"]
    assert s.design.geometry.length == pytest.approx(0.09)  # the last good design stays
    s.length_mm = 90.0
    assert s.errors == {}


def test_the_card_tab_holds_the_core_card(app):
    view = app.card
    app.tabs.active = [t for t, *_ in App.LAZY_TABS].index("Every direction") + 1  # shown: it refreshes
    view.param.update(displacement_mm=0.2, angle_rad=0.02)
    rows = card(app.state.design, app.state.frequency_hz, 0.2e-3, 0.02)
    # the axial row is the explorer's own stiffness (one shape-factor setting): long by default
    explorer_axial = stiffness(app.state.design, app.state.frequency_hz, 0.2e-3).magnitude[0, 0]
    assert rows[0]["mode"] == "axial" and rows[0]["magnitude"] == pytest.approx(explorer_axial, rel=1e-12)
    for r in rows:
        # each number held to its unit: a narrow cell at 1280×720 broke "4.207 | kN/mm" over two lines
        k = format_number(units.display_stiffness(r['magnitude'], r['mode']), "stiffness")
        assert f"| {k}\u00a0{units.stiffness_unit(r['mode'])} |" in view.table.object
    radial = next(r for r in rows if r["mode"] == "radial")["magnitude"]
    axial = next(r for r in rows if r["mode"] == "axial")["magnitude"]
    assert f"radial / axial **{radial / axial:.2f}**" in view.table.object
    x, y = xy(view.frame("radial"), "radial")
    assert len(x) == 60 and np.all(np.diff(y) < 0)  # the radial stiffness softens with amplitude
    _, eta = xy(view.frame("rotation_loss"), "conical")
    assert np.all(np.isfinite(eta)) and eta.max() > eta[0]  # the loss factor's Fletcher–Gent peak


def test_exports_and_the_plotting_api_in_a_new_direction(app):
    """The design file and the stiffness table of a conical, finite-length design: the public
    formats, the core's numbers; the card's plots from the plotting API."""
    import csv
    import io

    import holoviews as hv

    from app.plots import card_plots
    from core import loads_design

    app.state.mode = "conical"
    design = loads_design(app.export._design_json().getvalue())
    assert design == app.state.design and design.mode == "conical" and design.shape_kind == "finite"
    rows = list(csv.reader(io.StringIO(app.export._table_csv().getvalue())))
    values = np.array(rows[1:], dtype=float)
    ref = stiffness(design, values[:, 0], values[0, 1])
    first = values[:, 1] == values[0, 1]
    np.testing.assert_allclose(values[first, 4], ref.magnitude[0, first], rtol=1e-10)
    layout = card_plots(PAPER_B, 10.0)
    assert isinstance(layout, hv.Layout) and len(layout) == 6


def test_a_long_radial_bushing_is_named_by_its_closed_form():
    """A design set to the long shape uses the plane-strain closed form in the radial direction
    (core.shape: no thesis equation, not the table), conical keeps the table: each named so, in
    one direction and across all four."""
    from app.shapes import shape_phrase, shape_used
    from core.shape import shape_factor

    design = PAPER_B.replace(shape="long")
    radial = design.in_mode("radial")
    assert radial.shape_kind == "long"
    assert radial.shape_factor == shape_factor(radial.geometry, "radial", "long")
    assert radial.shape_factor != shape_factor(radial.geometry, "radial", "finite")
    assert shape_used(design, "radial") == "long-bushing closed form (plane strain)"
    assert shape_used(design, "conical") == "finite-length table"
    assert shape_phrase(radial) == "Shape factor: long-bushing closed form (plane strain)."
    assert shape_phrase(design, ("axial", "torsion", "radial", "conical")) == (
        "Shape factor: axial and torsion, long-bushing formulas (eqs 18, 17); radial, long-bushing closed "
        "form (plane strain); conical, finite-length table.")
