"""Issue #27 items 5–7 in the page: units, no silent corrections, one number formatter.

A typo or an out-of-range number is refused with a message beside its field and nothing changes;
the what-if targets carry their units; fitted values, links and tick labels are written short
(the one formatter's digits, no ``e+``), and a link gives back the numbers it was written from."""

import re
from pathlib import Path
from urllib.parse import parse_qsl, urlsplit

import pytest
from playwright.sync_api import expect

from tests.ui.bokeh_page import EXPLORER_TITLES, open_explorer, settle, wait_ready

pytestmark = pytest.mark.usefixtures("console_errors")

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
E_NOTATION = re.compile(r"\de[+\-−]?\d", re.IGNORECASE)

# the major tick labels every axis of every figure draws, as Bokeh's axis views write them
# (the canvas shows the same texts): {figure title: [label, …]}
TICK_LABELS_JS = """() => {
  const out = {};
  for (const v of Bokeh.index.all_views()) {
    const m = v.model;
    if (!(m.type === 'LinearAxis' || m.type === 'LogAxis') || v.tick_coords === undefined) continue;
    const ticks = v.tick_coords.major[v.dimension];
    const boxes = v.compute_labels(ticks).items;
    const text = (b) => b.text ?? ((b.base && b.expo) ? `${text(b.base)}^${text(b.expo)}` : String(b));
    let fig = v.parent;
    while (fig && fig.model.type !== 'Figure') fig = fig.parent;
    const title = (fig && fig.model.title && fig.model.title.text) || '?';
    out[title] = [...(out[title] ?? []), ...boxes.map(text)];
  }
  return out;
}"""


def significant_digits(text: str) -> int:
    """The significant digits of a number as a field shows it (``2.41`` → 3, ``35730`` → 4,
    ``15×10⁻⁶`` → 2)."""
    mantissa = text.split("×")[0].lstrip("-").replace(".", "").lstrip("0").rstrip("0")
    return len(mantissa)


def enter(field, text: str):
    field.fill(text)
    field.press("Enter")


def test_a_typo_in_length_is_refused_with_a_message_and_the_design_is_kept(page, explorer_url):
    open_explorer(page, explorer_url)
    summary = page.locator(".op-summary").inner_text()
    field = page.get_by_label("Length L (mm)")
    enter(field, "9o")
    message = page.locator('.field-error[data-field="length_mm"]')
    expect(message).to_contain_text("9o")
    expect(message).to_contain_text("not a number")
    assert page.locator(".op-summary").inner_text() == summary  # |K| as before: no 9 mm


def test_a_size_out_of_range_is_worded_in_mm(page, explorer_url):
    open_explorer(page, explorer_url)
    field = page.get_by_label("Length L (mm)")
    enter(field, "2000000")
    message = page.locator('.field-error[data-field="length_mm"]')
    expect(message).to_contain_text("1000000 mm")
    assert " m," not in message.inner_text() and "e-06" not in message.inner_text()


def test_what_ifs_refuse_a_tolerance_of_95_and_a_typo_with_a_message(page, explorer_url):
    """95 % and −5 % are no tolerance (0 to 89 %, as a link's): each gets a message beside its
    field, the field keeps what was typed, and the tolerances stay as they were (the link has
    none); a typo in a limit gets its message too and sets nothing."""
    open_explorer(page, explorer_url)
    page.get_by_text("What-ifs", exact=True).click()
    page.get_by_role("button", name="Find designs").wait_for()
    box = page.get_by_label("Shear modulus µ ± %")
    enter(box, "95")
    message = page.locator('.field-error[data-field="shear_modulus"]')
    expect(message).to_contain_text("95 %")
    expect(message).to_contain_text("89 %")
    expect(box).to_have_value("95")  # not silently set back to 89 or 0
    enter(box, "-5")
    expect(message).to_contain_text("−5 %")  # as the one formatter writes it: a true minus sign
    enter(page.get_by_label("Length L ± %"), "3")  # a good one is taken…
    page.wait_for_url(re.compile(r"tol=L(%3A|:)3"))
    assert "mu" not in dict(parse_qsl(urlsplit(page.url).query)).get("tol", "")  # …the refused ones never were
    limit = page.get_by_label("b at most (mm)")
    enter(limit, "4o")
    expect(page.locator('.field-error[data-field="b_max_mm"]')).to_contain_text("“4o” is not a number")


def test_the_k_target_carries_its_unit_and_the_results_are_in_the_typed_units(page, explorer_url):
    open_explorer(page, explorer_url)
    page.get_by_text("What-ifs", exact=True).click()
    page.get_by_role("button", name="Find designs").wait_for()
    target = page.get_by_label(re.compile(r"^\|K\| target"))
    expect(target).to_have_count(1)
    label = page.locator("label").filter(has_text=re.compile(r"^\|K\| target"))
    expect(label).to_contain_text("(kN/mm)")  # axial: the explorer's stiffness unit
    enter(target, "4.5")
    enter(page.get_by_label(re.compile(r"^b at most")), "40")
    page.get_by_role("button", name="Find designs").click()
    result = page.get_by_text(re.compile("design meets every target|closest"))
    result.first.wait_for(timeout=60_000)
    target_line = page.get_by_text(re.compile(r"^Target 1:"))
    expect(target_line).to_contain_text("4.5 kN/mm")  # the target as typed, in its unit
    table = page.get_by_role("table").filter(has_text="target 1")
    expect(table).to_contain_text("kN/mm")  # what each design achieves, in the same unit
    text = target_line.inner_text() + "\n" + table.inner_text() + "\n" + result.first.inner_text()
    assert "N/m " not in text and "SI units" not in text and not E_NOTATION.search(text), text


def _load_and_fit(page, fit_on: str = ""):
    page.get_by_text("Measured data and fit", exact=True).click()
    page.get_by_role("button", name="Fit the five material parameters").wait_for()
    page.locator("#main input[type=file]").first.set_input_files(str(EXAMPLES / "paper_b_stiffness.csv"))
    page.get_by_text("150 points").first.wait_for()
    if fit_on:
        enter(page.get_by_label(re.compile("^Fit on")), fit_on)
    page.get_by_role("button", name="Fit the five material parameters").click()


def test_fitted_values_are_shown_short_and_their_link_gives_them_back(page, explorer_url, context):
    """After a fit taken into the explorer, every design field shows at most 4 significant
    digits (not 2.41046111863), the link's numbers at most 9 (not 0.09999999973330827), and
    the link opened in a new page shows the same fields and the same operating point."""
    from core.parameters import PARAMETERS

    open_explorer(page, explorer_url)
    _load_and_fit(page)
    page.get_by_text("Correlation between parameters").wait_for(timeout=120_000)
    page.get_by_role("button", name="Use the fitted design in the explorer").click()
    page.get_by_text("(fitted)").first.wait_for()
    page.get_by_text("Explorer", exact=True).click()
    wait_ready(page)
    fields = {p.display_label: page.get_by_label(p.display_label).input_value() for p in PARAMETERS}
    assert all(significant_digits(v) <= 4 for v in fields.values()), fields
    mu = next(p for p in PARAMETERS if p.name == "shear_modulus")
    page.wait_for_url(re.compile(f"{mu.url_key}="))  # the link has the fitted design
    expect(page.locator(".op-summary")).to_have_text(re.compile(r"\|K\| = "))  # drawn after the tab switch
    summary = page.locator(".op-summary").inner_text()
    numbers = {k: v for k, v in parse_qsl(urlsplit(page.url).query) if re.fullmatch(r"-?[\d.]+", v)}
    assert numbers and all(significant_digits(v) <= 9 for v in numbers.values()), numbers
    other = context.new_page()
    open_explorer(other, page.url)
    expect(other.locator(".op-summary")).to_have_text(summary)
    assert {k: other.get_by_label(k).input_value() for k in fields} == fields
    other.close()


def test_fit_on_takes_the_amplitude_in_mm(page, explorer_url):
    open_explorer(page, explorer_url)
    _load_and_fit(page, "mode=axial,amplitude=0.1")
    page.get_by_text(re.compile(r"Fitted on mode=axial,amplitude=0\.1")).wait_for(timeout=120_000)
    table = page.get_by_text(re.compile(r"Fitted on")).locator("xpath=ancestor::div[1]")
    expect(page.get_by_role("cell", name="0.1 mm").first).to_be_visible()
    assert page.get_by_role("cell", name="predicted").count() >= 1, table.inner_text()


def test_tick_labels_are_written_without_e_notation(page, explorer_url):
    open_explorer(page, explorer_url)
    ticks = page.evaluate(TICK_LABELS_JS)
    assert set(EXPLORER_TITLES) <= set(ticks), list(ticks)
    _load_and_fit(page)
    page.get_by_text("Correlation between parameters").wait_for(timeout=120_000)
    settle(page)
    measured = page.evaluate(TICK_LABELS_JS)
    assert any(t.endswith("residual against amplitude") for t in measured), list(measured)
    ticks.update(measured)
    labels = [label for texts in ticks.values() for label in texts]
    assert labels and all(labels), ticks
    assert [t for t in labels if E_NOTATION.search(t)] == [], ticks
    # a negative tick (the residuals') with a true minus sign, as every text writes it
    assert any(t.startswith("−") for t in labels) and [t for t in labels if "-" in t] == [], ticks
