"""Issue 27, items 2 and 13: one shape-factor setting in every view, each view saying which it
uses; the pinned reference in every plot of the same quantity; the preset select naming a custom
design "Custom"; hover tooltips naming their curve; each direction's |K| on its own axes; the
teaching player starting at the operating amplitude.

The numbers are checked against ``core.stiffness`` of the design built here from the link's
values (the shape factor named explicitly): a number in the text is printed to 4 significant
digits, so it is that number to half a unit of its last digit."""

import re
from urllib.parse import urlencode

import pytest
from playwright.sync_api import expect

from core import stiffness
from tests.ui.bokeh_page import open_explorer
from tests.ui.test_values_browser import LINK, PER_SI, link_design, printed_close, shown_point

pytestmark = pytest.mark.usefixtures("console_errors", "no_server_tracebacks")

# the explorer's default setting: the thesis' long-bushing formula for axial (eq 18)
PHRASES = {"long": "Shape factor: long-bushing formula (eq 18).", "finite": "Shape factor: finite-length table."}
# every direction's shape factors (the card, the what-ifs' card bands, the diagnosis of data in any mode)
EVERY_DIRECTION = {"finite": "Shape factor: finite-length table, every direction.",
                   "long": "Shape factor: axial and torsion, long-bushing formulas (eqs 18, 17); radial and conical, "
                           "finite-length table."}
# each tab: does it show the design's own mode (PHRASES) or every direction (EVERY_DIRECTION)
TABS = {"Slices": PHRASES, "Fletcher–Gent, branch by branch": PHRASES, "Measured data and fit": PHRASES,
        "Find the missing effect": EVERY_DIRECTION, "What-ifs": EVERY_DIRECTION}


def axial_row(page):
    """The axial row of the Every direction table."""
    return page.locator("tr").filter(has=page.locator("td:first-child", has_text=re.compile(r"^\s*axial\b"))).first


def card_axial(page) -> float:
    """|K| (kN/mm) of the axial row of the Every direction table."""
    cells = axial_row(page).locator("td").all_inner_texts()
    magnitude, unit = cells[2].split()
    assert unit == "kN/mm", cells
    return float(magnitude)


@pytest.mark.parametrize("shape", ["long", "finite"])
def test_one_shape_factor_in_every_view(page, explorer_url, shape):
    """Item 2: the axial |K| of the Explorer's operating point and of the Every direction card
    (at the same displacement and frequency) are one number, the core's for the shape factor
    the setting names; each tab says which shape factor it uses."""
    link = {**LINK, "finite": "true" if shape == "finite" else "false"}
    open_explorer(page, explorer_url + "?" + urlencode(link))
    amplitude_m = LINK["amp"] * 1e-3
    exact = stiffness(link_design(LINK, "axial", shape=shape), LINK["f_Hz"], amplitude_m).magnitude[0, 0]
    explorer_k, _ = shown_point(page)
    assert printed_close(explorer_k, exact * PER_SI["kN/mm"]), (explorer_k, exact)

    page.get_by_text("Every direction", exact=True).click()
    page.get_by_text("Ratios").wait_for()
    displacement = page.get_by_label("Displacement amplitude (mm)")
    if float(displacement.input_value()) != LINK["amp"]:
        displacement.fill(str(LINK["amp"]))
        displacement.press("Enter")
    expect(axial_row(page)).to_contain_text(f"{LINK['amp']:g} mm")
    card_k = card_axial(page)
    assert card_k == explorer_k, (card_k, explorer_k)  # the same number, printed the same way
    assert printed_close(card_k, exact * PER_SI["kN/mm"]), (card_k, exact)
    # the card names each direction's shape factor: radial and conical are always finite
    phrase = page.locator(".shape-phrase:visible")
    expect(phrase).to_have_text(EVERY_DIRECTION[shape])
    for tab, phrases in TABS.items():
        page.get_by_text(tab, exact=True).click()
        expect(page.locator(".shape-phrase:visible")).to_have_text(phrases[shape])
    page.get_by_text("Explorer", exact=True).click()
    expect(page.locator(".shape-phrase:visible")).to_have_text(PHRASES[shape])


def test_the_switch_moves_every_view(page, explorer_url):
    """Item 2: the sidebar's switch flipped in the page while Every direction is shown: its
    axial row goes from the core's long-bushing |K| to its finite-length one, and the Explorer's
    operating point follows."""
    open_explorer(page, explorer_url + "?" + urlencode(LINK))
    page.get_by_text("Every direction", exact=True).click()
    page.get_by_text("Ratios").wait_for()
    x = float(page.get_by_label("Displacement amplitude (mm)").input_value()) * 1e-3
    long, finite = (stiffness(link_design(LINK, "axial", shape=shape), LINK["f_Hz"], x).magnitude[0, 0]
                    * PER_SI["kN/mm"] for shape in ("long", "finite"))
    assert printed_close(card_axial(page), long), (card_axial(page), long)
    switch = page.get_by_role("switch", name="Finite-length shape factor")
    box = switch.bounding_box()
    switch.click(position={"x": box["width"] - 8, "y": box["height"] / 2})  # on its knob, at the right
    expect(axial_row(page)).to_contain_text(f"{finite:.4g} kN/mm")
    assert printed_close(card_axial(page), finite), (card_axial(page), finite)
    expect(page.locator(".shape-phrase:visible")).to_have_text(EVERY_DIRECTION["finite"])
    page.get_by_text("Explorer", exact=True).click()
    at_point = stiffness(link_design(LINK, "axial", shape="finite"), LINK["f_Hz"], LINK["amp"] * 1e-3)
    expect(page.locator(".op-summary")).to_contain_text(f"{at_point.magnitude[0, 0] * PER_SI['kN/mm']:.4g} kN/mm")
    expect(page.locator(".shape-phrase:visible")).to_have_text(PHRASES["finite"])
