"""Issue #29 in the page: the optional bulk-modulus field. Empty, the rubber is nearly
incompressible; 2 GPa makes a thin wall's radial |K| the core's for that design, the views say that
|K| includes K, and the Every direction card compares each direction with an incompressible
rubber; a K/µ outside 50–10⁶ is refused beside the field in GPa and the design is kept."""

import re

import pytest
from playwright.sync_api import expect

from core import PAPER_B, stiffness
from core.numbers import format_number
from tests.ui.bokeh_page import open_explorer

pytestmark = pytest.mark.usefixtures("console_errors")

THIN = PAPER_B.replace(mode="radial", inner_radius=0.02, outer_radius=0.025, length=0.06)
QUERY = "?mode=radial&a_mm=20&b_mm=25&L_mm=60"


def shown_k(page) -> str:
    return re.search(r"\|K\| = ([\d.]+) kN/mm", page.locator(".op-summary").inner_text()).group(1)


def enter(field, text: str):
    field.fill(text)
    field.press("Enter")


def test_the_bulk_modulus_field_softens_a_thin_wall_as_the_core_does(page, explorer_url):
    open_explorer(page, explorer_url + QUERY)
    field = page.get_by_label("Bulk modulus K (GPa)")
    assert field.input_value() == "" and "nearly incompressible" in field.get_attribute("placeholder")
    before = shown_k(page)
    expected = {k: stiffness(THIN.replace(bulk_modulus=k), [10.0], [1e-4]).magnitude[0, 0] / 1e6
                for k in (None, 2e9)}
    assert before == format_number(expected[None], "stiffness")
    enter(field, "2")
    expect(page.locator(".op-summary")).to_contain_text(f"|K| = {format_number(expected[2e9], 'stiffness')} kN/mm")
    expect(page.locator(".shape-phrase").first).to_contain_text("Bulk modulus K = 2 GPa")
    page.get_by_text("Every direction", exact=True).click()
    expect(page.get_by_text("against an incompressible rubber").first).to_be_visible()
    expect(page.get_by_text(re.compile(r"bulk modulus K = 2 GPa \(K/µ 826\)"))).to_be_visible()


def test_a_bulk_modulus_far_from_rubber_is_refused_in_gpa_and_the_design_kept(page, explorer_url):
    open_explorer(page, explorer_url + QUERY)
    before = shown_k(page)
    enter(page.get_by_label("Bulk modulus K (GPa)"), "0.01")
    message = page.locator('.field-error[data-field="bulk_modulus_gpa"]')
    expect(message).to_contain_text("0.121 GPa to 2420 GPa; got 0.01 GPa")
    assert shown_k(page) == before
