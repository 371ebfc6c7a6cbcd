"""Messages where the user looks, in the user's words (issue #27, item 9): a tolerance the design
cannot take is said beside that tolerance in the What-ifs tab, in mm, naming only what has a
tolerance; a geometry outside the finite-length table is said beside the field just edited, with
the table's limits in mm and without the files' vocabulary; a checkbox's or a switch's words
toggle it."""

from playwright.sync_api import expect

from tests.ui.bokeh_page import open_explorer


def open_tab(page, title: str):
    page.locator(".bk-tab").filter(has_text=title).first.click()


def test_a_refused_tolerance_is_said_beside_it_in_mm(page, explorer_url, console_errors):
    open_explorer(page, explorer_url)
    open_tab(page, "What-ifs")
    field = page.get_by_label("Outer radius b ± %")
    field.fill("50")  # b = 35 mm −50 % = 17.5 mm, below a = 20 mm
    field.press("Enter")
    message = page.locator('.field-error[data-field="tolerance:outer_radius"]')
    expect(message).to_contain_text("b ± 50 % lets b fall to 17.5 mm")
    expect(message).to_contain_text("below 42.9 %")  # (35 − 20)/35: how far b's tolerance may go
    text = message.inner_text()
    assert " m " not in text and "0.0175" not in text and "a reach" not in text  # mm; a has no tolerance
    expect(page.locator('.field-error[data-field^="tolerance:"]')).to_have_count(1)  # beside b only
    field.fill("40")  # 21 mm > 20 mm: taken, the message goes
    field.press("Enter")
    expect(message).to_have_count(0)


def test_a_geometry_outside_the_table_is_said_beside_the_field_edited(page, explorer_url, console_errors):
    open_explorer(page, explorer_url)
    page.locator(".bk-Switch .bk-body").click()  # the finite-length shape factor on
    expect(page.get_by_text("in use: the finite-element", exact=False)).to_be_visible()
    field = page.get_by_label("Inner radius a (mm)")
    field.fill("8")  # b/a = 35/8 = 4.4: beyond the table's 4
    field.press("Enter")
    message = page.locator('.field-error[data-field="inner_radius_mm"]')
    expect(message).to_contain_text("Outside the finite-length table")
    expect(message).to_contain_text("b may be 9.6–32 mm")  # b/a 1.2–4 with a = 8 mm
    expect(message).to_contain_text("switch off the finite-length shape factor")
    assert "shape '" not in message.inner_text()  # no file vocabulary ('thesis', 'finite')
    expect(page.locator('.field-error[data-field="length_mm"]')).to_have_count(0)  # not beside L
    field.fill("20")
    field.press("Enter")
    expect(page.locator(".field-error")).to_have_count(0)


def test_a_checkbox_or_switch_label_toggles_it(page, explorer_url, console_errors):
    open_explorer(page, explorer_url)
    page.get_by_text("Finite-length shape factor", exact=True).click()  # the words, not the switch
    expect(page.locator(".bk-Switch")).to_have_class("bk-Switch bk-active")
    expect(page.get_by_text("in use: the finite-element", exact=False)).to_be_visible()

    open_tab(page, "What-ifs")
    field = page.get_by_label("Shear modulus µ ± %")
    field.fill("10")
    field.press("Enter")
    box = page.locator(".band-switch input[type=checkbox]")
    expect(box).not_to_be_checked()
    page.get_by_text("Show tolerance bands on the stiffness plots", exact=True).click()
    expect(box).to_be_checked()
    expect(page.get_by_text("Bands are drawn on the Explorer's stiffness plots")).to_be_visible()
    page.get_by_text("Show tolerance bands on the stiffness plots", exact=True).click()
    expect(box).not_to_be_checked()
    expect(page.get_by_text("Bands are drawn on the Explorer's stiffness plots")).to_have_count(0)
