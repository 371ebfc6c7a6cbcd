"""Issue #27 items 5–7 in the page: a typo in a field is refused with a message beside it (the
design unchanged), and a bound is given in the field's unit."""

import pytest
from playwright.sync_api import expect

from tests.ui.bokeh_page import open_explorer

pytestmark = pytest.mark.usefixtures("console_errors")


def test_a_typo_in_length_is_refused_with_a_message_and_the_design_is_kept(page, explorer_url):
    open_explorer(page, explorer_url)
    summary = page.locator(".op-summary").inner_text()
    field = page.get_by_label("Length L (mm)")
    field.fill("9o")
    field.press("Enter")
    message = page.locator('.field-error[data-field="length_mm"]')
    expect(message).to_contain_text("9o")
    expect(message).to_contain_text("not a number")
    assert page.locator(".op-summary").inner_text() == summary  # |K| as before: no 9 mm


def test_a_size_out_of_range_is_worded_in_mm(page, explorer_url):
    open_explorer(page, explorer_url)
    field = page.get_by_label("Length L (mm)")
    field.fill("2000000")
    field.press("Enter")
    message = page.locator('.field-error[data-field="length_mm"]')
    expect(message).to_contain_text("1000000 mm")
    assert " m," not in message.inner_text() and "e-06" not in message.inner_text()
