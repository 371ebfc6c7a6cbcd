"""Links and design files in a real browser (issue #27, items 4 and 10): a link reproduces what
the user saw (a diagnosed design's effects and name, the pinned reference), a downloaded design
file opens again in one click, the copy button copies the link, and a hand-edited link's invalid
values get messages naming them and never reach the address bar."""

import re
from urllib.parse import parse_qsl, urlsplit

from playwright.sync_api import expect

from tests.ui.bokeh_page import open_explorer, wait_plot

SUMMARY = ".op-summary"  # the operating point's line: amplitude, frequency → |K|, loss factor
BANNER = ".input-errors"


def query(url: str) -> dict[str, str]:
    return dict(parse_qsl(urlsplit(url).query, keep_blank_values=True))


def summary(page) -> str:
    return page.locator(SUMMARY).first.inner_text()


def reopen(page, url: str):
    """The link opened afresh in the same page (a new session), as someone it was sent to."""
    open_explorer(page, url)


def test_a_diagnosed_designs_link_reproduces_its_numbers_and_effects(page, context, explorer_url, console_errors,
                                                                     no_server_tracebacks):
    from core.synthetic import MYSTERIES

    # a mystery with a hidden effect (the demo starts at a random one; two hide none): loaded
    # again until it is one, at most once per mystery
    with_effects = [i + 1 for i, m in enumerate(MYSTERIES) if m.hidden]
    open_explorer(page, explorer_url)
    page.get_by_text("Find the missing effect", exact=True).click()
    source, shown = page.get_by_text(re.compile(r"mystery data set \d+ of")).first, None
    for _ in MYSTERIES:
        page.get_by_role("button", name="Load a mystery data set (demo)").click()
        if shown is None:
            source.wait_for()
        else:
            expect(source).not_to_have_text(shown)  # the next mystery's line, not the last one's
        shown = source.inner_text()
        if int(re.search(r"mystery data set (\d+) of", shown).group(1)) in with_effects:
            break
    page.get_by_role("button", name="Diagnose").click()
    page.get_by_role("button", name="Use the final model in the explorer").click(timeout=60_000)
    status = page.locator(".design-status").locator("div").first  # the design's name, mode, effects
    expect(status).to_contain_text(re.compile(r"\(fitted\), \w+; effects: \w+"))  # what the demo hid
    said = status.inner_text()
    page.get_by_text("Explorer", exact=True).click()
    page.wait_for_url(re.compile(r"effects="))
    # the link opened in a second page, as someone it was sent to opens it
    other = context.new_page()
    open_explorer(other, page.url)
    expect(other.locator(".design-status").locator("div").first).to_have_text(said)  # the name and the effects
    shown = other.locator(SUMMARY).first.inner_text()
    assert "|K| =" in shown
    expect(page.locator(SUMMARY).first).to_have_text(shown)  # the same |K| and loss factor as the user's page
    other.close()


def test_a_pinned_reference_survives_the_link(page, explorer_url, console_errors, no_server_tracebacks):
    open_explorer(page, explorer_url)
    page.get_by_role("button", name="Pin as reference").click()
    expect(page.locator(".comparison")).to_contain_text("this design")
    field = page.get_by_label("Length L (mm)")
    field.fill("99")
    field.press("Enter")
    page.get_by_text("+10.00 %").first.wait_for()
    page.wait_for_url(re.compile(r"L_mm=99.*ref\.L_mm=90|ref\.L_mm=90.*L_mm=99"))
    table = page.locator(".comparison").locator("div").first  # the pane's text, in its shadow root
    compared = table.inner_text()
    assert "+10.00 %" in compared
    reopen(page, page.url)
    expect(table).to_have_text(compared)
    wait_plot(page, "|K| against frequency", "p.legends.includes('reference')")


def test_a_downloaded_design_file_opens_again_in_one_click(page, explorer_url, tmp_path, console_errors, no_server_tracebacks):
    open_explorer(page, explorer_url + "?mu_MPa=3.1&f_Hz=40&amp=0.3")
    expect(page.locator(SUMMARY).first).to_contain_text("0.3 mm, 40 Hz")
    seen = summary(page)
    with page.expect_download() as download:
        page.get_by_role("button", name="Design file (JSON)").click()
    path = tmp_path / "bushing-design.json"
    download.value.save_as(path)
    field = page.get_by_label("Shear modulus µ (MPa)")
    field.fill("1.5")
    field.press("Enter")
    expect(page.locator(SUMMARY).first).not_to_have_text(seen)
    opener = page.locator(".design-file input[type=file]")
    expect(opener).to_have_count(1)  # the design file's own upload, in the sidebar
    opener.set_input_files(str(path))
    expect(page.locator(".design-file-message")).to_contain_text("Loaded bushing-design.json")
    expect(page.locator(SUMMARY).first).to_have_text(seen)
    expect(field).to_have_value("3.1")
    # a file that is no design file is refused, named, with what is wrong; the design stays
    bad = tmp_path / "broken.json"
    bad.write_text('{"mode": "axial", "geometry": {}}')
    opener.set_input_files(str(bad))
    expect(page.locator(".design-file-message")).to_contain_text("broken.json not loaded: ")
    expect(page.locator(".design-file-message")).not_to_contain_text("Traceback")
    expect(page.locator(SUMMARY).first).to_have_text(seen)


def test_the_copy_button_copies_the_link(page, context, explorer_url, console_errors, no_server_tracebacks):
    context.grant_permissions(["clipboard-read", "clipboard-write"])
    open_explorer(page, explorer_url + "?L_mm=80")
    button = page.get_by_role("button", name="Copy link")
    expect(button).to_have_count(1)
    page.wait_for_url(re.compile(r"fmin_Hz="))  # the session's link written
    button.click()
    expect(page.get_by_role("button", name="Link copied")).to_be_visible()
    assert page.evaluate("navigator.clipboard.readText()") == page.url


def test_a_hand_edited_links_invalid_values_are_named_and_never_written_back(page, explorer_url, console_errors, no_server_tracebacks):
    open_explorer(page, explorer_url + "?amp=1e6&mu_MPa=abc&b_mm=15&mode=diagonal&L_mm=80")
    banner = page.locator(BANNER)
    # each field with its message: the key, the value, the rule
    expect(banner).to_contain_text("Drive amplitude: The link's amp=1000000.0 is outside this bushing's amplitude axis")
    expect(banner).to_contain_text("Shear modulus µ (MPa): The link's mu_MPa='abc' is not a number; kept 2.42.")
    expect(banner).to_contain_text("Outer radius b (mm): Must be larger than the inner radius a.")
    expect(banner).to_contain_text("Mode: The link's mode='diagonal' must be one of axial")
    # beside the fields too
    expect(page.locator('.field-error[data-field="amplitude"]')).to_contain_text("amp=1000000.0")
    expect(page.locator('.field-error[data-field="outer_radius_mm"]')).to_contain_text("Must be larger")
    expect(page.locator(".op-point")).to_contain_text("0.1 mm")  # not clamped to the axis' end: kept
    page.wait_for_url(re.compile(r"fmin_Hz="))
    written = query(page.url)
    assert (written["amp"], written["mu_MPa"], written["b_mm"], written["mode"], written["L_mm"]) == (
        "0.1", "2.42", "35", "axial", "90")  # the design drawn: L = 80 is valid, b = 15 with it is not
    # the session goes on: a valid edit is written, the invalid field stays as typed, with its message
    field = page.get_by_label("Inner radius a (mm)")
    field.fill("10")
    field.press("Enter")
    page.wait_for_url(re.compile(r"a_mm=10(&|$)"))
    written = query(page.url)
    assert (written["b_mm"], written["L_mm"]) == ("15", "80")  # now valid: a < b, drawn, linked
    expect(page.locator(".op-point")).to_contain_text("0.1 mm")  # the refused amplitude never applied
    for value in ("1e6", "1000000", "abc", "diagonal"):
        assert value not in page.url
