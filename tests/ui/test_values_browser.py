"""The numbers the page shows are the core's: the plotted curves, read from their Bokeh data
sources in the page, and the numbers written in the text, against ``core.stiffness`` of the same
design (built here from the link's values), before and after a widget changes the design.

Tolerances. Bokeh sends a NumPy float64 array as a binary float64 buffer (each curve is checked to
arrive as a Float64Array), so the transport is exact; the page's curve and this test's number are
the same model evaluated on the same inputs, which can differ only in round-off (the link's
values scaled to SI here and in the app, a product or two apart): RTOL = 1e-12. A float32
anywhere on the way would be off by about 3e-8. A number in the text is printed to 4 significant
digits: half a unit of its last digit."""

import math
import re
from urllib.parse import urlencode

import numpy as np
import pytest
from numpy.testing import assert_allclose
from playwright.sync_api import expect

from core import Design, Geometry, Material, stiffness
from tests.ui.bokeh_page import curve, open_explorer, wait_curve_changed

pytestmark = pytest.mark.usefixtures("console_errors", "no_server_tracebacks")

RTOL = 1e-12
SWEEP_TITLES = ("|K| against frequency", "Loss factor against frequency", "|K| against amplitude",
                "Loss factor against amplitude")
# display units of the page, from SI (docs/files.md: N/m and N·m/rad in files)
PER_SI = {"kN/mm": 1e-6, "N·m/rad": 1.0}

# a design that is none of the presets, and its operating point
LINK = {"mode": "axial", "a_mm": 18, "b_mm": 40, "L_mm": 70, "mu_MPa": 1.9, "m_MPa": 0.5, "alpha": 0.25,
        "sigma_kPa": 15, "eps_half": 0.003, "amp": 0.05, "f_Hz": 20}


def link_design(link: dict, mode: str, shape=None) -> Design:
    """The design a link describes, in SI."""
    return Design(mode, Geometry(link["a_mm"] * 1e-3, link["b_mm"] * 1e-3, link["L_mm"] * 1e-3),
                  Material(link["mu_MPa"] * 1e6, link["m_MPa"] * 1e6, link["alpha"], link["sigma_kPa"] * 1e3,
                           link["eps_half"]), shape=shape)


def printed_close(shown: float, exact: float) -> bool:
    """``shown`` is ``exact`` printed to 4 significant digits (half a unit of the last one, and
    round-off)."""
    half_unit = 0.5 * 10.0 ** (math.floor(math.log10(abs(exact))) - 3)
    return abs(shown - exact) <= half_unit * (1 + 1e-9)


def check_explorer_curves(page, design: Design, amplitude_m: float, frequency_hz: float):
    """The operating curves of the four sweep plots against the core at their own abscissae."""
    k_f = curve(page, "|K| against frequency", "operating point")
    eta_f = curve(page, "Loss factor against frequency", "operating point")
    k_a = curve(page, "|K| against amplitude", "operating point")
    eta_a = curve(page, "Loss factor against amplitude", "operating point")
    assert all(c["float64"] for c in (k_f, eta_f, k_a, eta_a))
    along_f = stiffness(design, k_f["x"], amplitude_m)  # one amplitude: row 0
    assert_allclose(k_f["y"], along_f.magnitude[0] * PER_SI["kN/mm"], rtol=RTOL)
    assert_allclose(eta_f["x"], k_f["x"], rtol=0, atol=0)  # the same grid, sent twice
    assert_allclose(eta_f["y"], along_f.loss_factor[0], rtol=RTOL)
    along_a = stiffness(design, frequency_hz, np.asarray(k_a["x"]) * 1e-3)  # mm → m; one frequency: column 0
    assert_allclose(k_a["y"], along_a.magnitude[:, 0] * PER_SI["kN/mm"], rtol=RTOL)
    assert_allclose(eta_a["y"], along_a.loss_factor[:, 0], rtol=RTOL)


def shown_point(page) -> tuple[float, float]:
    """|K| (kN/mm) and the loss factor in the operating point's summary."""
    text = page.locator(".op-summary").inner_text()
    found = re.search(r"\|K\| = ([0-9.e+-]+) kN/mm, loss factor ([0-9.e+-]+)", text)
    assert found, text
    return float(found.group(1)), float(found.group(2))


def check_operating_point(page, design: Design, amplitude_m: float, frequency_hz: float):
    k = stiffness(design, frequency_hz, amplitude_m)
    magnitude, loss = shown_point(page)
    assert printed_close(magnitude, k.magnitude[0, 0] * PER_SI["kN/mm"]), (magnitude, k.magnitude[0, 0])
    assert abs(loss - k.loss_factor[0, 0]) <= 0.5e-4 * (1 + 1e-9)  # printed to 4 decimals


def test_the_plotted_curves_and_the_summary_are_the_cores_numbers(page, explorer_url):
    open_explorer(page, explorer_url + "?" + urlencode(LINK))
    assert page.locator(".op-point").inner_text() == "0.05 mm, 20 Hz"  # the link's operating point
    design = link_design(LINK, "axial")
    amplitude_m = LINK["amp"] * 1e-3
    check_explorer_curves(page, design, amplitude_m, LINK["f_Hz"])
    check_operating_point(page, design, amplitude_m, LINK["f_Hz"])
    # a new shear modulus typed in: the curves change, and are the new design's
    before = {t: curve(page, t, "operating point")["y"] for t in SWEEP_TITLES}
    summary = page.locator(".op-summary").inner_text()
    field = page.get_by_label("Shear modulus µ (MPa)")
    field.fill("2.6")
    field.press("Enter")
    for title, y in before.items():
        wait_curve_changed(page, title, "operating point", y)
    expect(page.locator(".op-summary")).not_to_have_text(summary)
    changed = link_design({**LINK, "mu_MPa": 2.6}, "axial")
    check_explorer_curves(page, changed, amplitude_m, LINK["f_Hz"])
    check_operating_point(page, changed, amplitude_m, LINK["f_Hz"])


def card_rows(page) -> dict:
    """The card's table: mode → (amplitude, its unit, |K|, its unit, loss factor)."""
    rows = {}
    for row in page.locator("tr").filter(has_text="finite-length table").all():
        cells = row.locator("td").all_inner_texts()
        mode = cells[0].split()[0]
        amplitude, amplitude_unit = cells[1].split()
        magnitude, magnitude_unit = cells[2].split()
        rows[mode] = (float(amplitude), amplitude_unit, float(magnitude), magnitude_unit, float(cells[3]))
    return rows


def check_card(page, link: dict, displacement_mm: float, angle_rad: float):
    """Each direction's |K| and loss factor in the card against the core (finite-length shape
    factors: the link asks for them)."""
    rows = card_rows(page)
    assert sorted(rows) == ["axial", "conical", "radial", "torsion"]
    for mode, (amplitude, amplitude_unit, magnitude, unit, loss) in rows.items():
        x = displacement_mm * 1e-3 if amplitude_unit == "mm" else angle_rad
        assert amplitude == pytest.approx(displacement_mm if amplitude_unit == "mm" else angle_rad, rel=5e-3)
        k = stiffness(link_design(link, mode, shape="finite"), link["f_Hz"], x)
        assert printed_close(magnitude, k.magnitude[0, 0] * PER_SI[unit]), (mode, magnitude, k.magnitude[0, 0])
        assert abs(loss - k.loss_factor[0, 0]) <= 0.5e-4 * (1 + 1e-9), (mode, loss)


def test_the_cards_numbers_are_the_cores(page, explorer_url):
    link = {**LINK, "mode": "radial", "finite": "true", "f_Hz": 30}
    open_explorer(page, explorer_url + "?" + urlencode(link))
    page.get_by_text("Every direction", exact=True).click()
    page.get_by_text("Ratios").wait_for()
    displacement = page.get_by_label("Displacement amplitude (mm)")
    angle = page.get_by_label("Angle amplitude (rad)")
    check_card(page, link, float(displacement.input_value()), float(angle.input_value()))
    # a new displacement typed in: the rows along and across the axis follow it
    displacement.fill("0.3")
    displacement.press("Enter")
    for mode in ("axial", "radial"):
        row = page.locator("tr").filter(has=page.locator("td:first-child", has_text=re.compile(rf"^\s*{mode}\b")))
        expect(row).to_contain_text("0.3 mm")
    check_card(page, link, 0.3, float(angle.input_value()))
