"""Issue 27, items 2 and 13: one shape-factor setting in every view, each view saying which it
uses; the pinned reference in every plot of the same quantity; the preset select naming a custom
design "Custom"; hover tooltips naming their curve; each direction's |K| on its own axes; the
teaching player starting at the operating amplitude.

The numbers are checked against ``core.stiffness`` of the design built here from the link's
values (the shape factor named explicitly): a number in the text is printed to 4 significant
digits, so it is that number to half a unit of its last digit."""

import re
from urllib.parse import urlencode

import numpy as np
import pytest
from numpy.testing import assert_allclose
from playwright.sync_api import expect

from core import stiffness
from tests.ui.bokeh_page import curve, open_explorer, settle, wait_plot
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


def test_the_preset_select_names_a_custom_design_custom(page, explorer_url):
    """Item 13: a design that is none of the presets shows "Custom" in the preset select; a
    preset picked shows its name until a field changes; picked again, it is loaded again."""
    open_explorer(page, explorer_url + "?" + urlencode(LINK))
    select = page.get_by_label("Preset")
    expect(select).to_have_value("Custom")
    select.select_option("Table 1 bushing (torsion)")
    expect(page.get_by_role("button", name="torsion")).to_have_class(re.compile(r"\bbk-active\b"))
    expect(select).to_have_value("Table 1 bushing (torsion)")
    field = page.get_by_label("Shear modulus µ (MPa)")
    table_1 = field.input_value()
    field.fill("3.3")
    field.press("Enter")
    expect(select).to_have_value("Custom")
    select.select_option("Table 1 bushing (torsion)")
    expect(field).to_have_value(table_1)
    expect(select).to_have_value("Table 1 bushing (torsion)")


def test_the_teaching_player_starts_at_the_operating_amplitude(page, explorer_url):
    """Item 13: the Fletcher–Gent player's first frame is the operating point's amplitude, and
    says so; the amplitude moved in the sidebar's link, the player follows."""
    open_explorer(page, explorer_url + "?" + urlencode(LINK))
    page.get_by_text("Fletcher–Gent, branch by branch", exact=True).click()
    frame = page.locator(".frame-point")
    expect(frame).to_have_text(f"Loop shape at {LINK['amp']:g} mm (the operating amplitude), {LINK['f_Hz']:g} Hz")


# the legend entry ``label`` of the figure ``title``: the page coordinates of its point at
# fraction ``k`` of its data (where a mouse hovers it)
POINT_JS = """([title, label, k]) => {
  const fig = [...Bokeh.documents[0].all_models].find(m => m.type === 'Figure' && m.title && m.title.text === title);
  const view = [...Bokeh.index.all_views()].find(v => v.model === fig);
  const legend = [...fig.center, ...fig.right, ...fig.left, ...fig.above, ...fig.below].find(m => m.type === 'Legend');
  const r = legend.items.find(it => (it.label.value || it.label.field) === label).renderers[0];
  const data = r.data_source.data, xs = data[r.glyph.x.field], ys = data[r.glyph.y.field];
  view.canvas_view.el.scrollIntoView({block: "center"});  // a plot below the window's edge: scrolled to, as a user would
  const i = Math.floor(xs.length * k), box = view.canvas_view.el.getBoundingClientRect();
  return [box.left + view.frame.x_scale.compute(xs[i]), box.top + view.frame.y_scale.compute(ys[i])];
}"""

# the text of every tooltip shown (each in its own shadow root)
TOOLTIPS_JS = """(wanted) => [...document.querySelectorAll('*')].flatMap(
    e => e.shadowRoot ? [...e.shadowRoot.querySelectorAll('.bk-Tooltip')] : [])
  .concat([...document.querySelectorAll('.bk-Tooltip')])
  .some(t => getComputedStyle(t).display !== 'none' && (t.shadowRoot ?? t).textContent.includes(wanted))"""


def hover_names(page, title: str, label: str):
    """The mouse on the curve ``label`` of ``title``: a tooltip names it ("curve: LABEL")."""
    page.mouse.move(0, 0)
    x, y = page.evaluate(POINT_JS, [title, label, 0.5])
    page.mouse.move(x, y)
    page.wait_for_function(TOOLTIPS_JS, arg=f"curve: {label}", timeout=15_000)


def test_hover_tooltips_name_the_curve(page, explorer_url):
    """Item 13: a tooltip says which curve it reads, in the Explorer, Slices and Every direction."""
    open_explorer(page, explorer_url + "?" + urlencode(LINK))
    hover_names(page, "Hysteresis loop at the operating point", "total")
    for title in ("|K| against frequency", "|K| against amplitude", "Loss factor against amplitude"):
        hover_names(page, title, "operating point")
    page.get_by_text("Slices", exact=True).click()
    wait_plot(page, "|K|: single modulus, slices and continuum", "p.points > 0")
    settle(page)
    hover_names(page, "|K|: single modulus, slices and continuum", "continuum")
    page.get_by_text("Every direction", exact=True).click()
    wait_plot(page, "Loss factor, turning and tilting", "p.points > 0")
    settle(page)
    hover_names(page, "Loss factor, turning and tilting", "conical")


# the y data of legend entry ``label`` in whichever figure holds it, and that figure's y range
SPAN_JS = """(label) => {
  for (const fig of Bokeh.documents[0].all_models) {
    if (fig.type !== 'Figure') continue;
    const legend = [...fig.center, ...fig.right].find(m => m.type === 'Legend');
    const item = legend && legend.items.find(it => (it.label.value || it.label.field) === label);
    if (item) {
      const r = item.renderers[0];
      return {title: fig.title.text, y: Array.from(r.data_source.data[r.glyph.y.field]),
              start: fig.y_range.start, end: fig.y_range.end};
    }
  }
  return null;
}"""


def test_every_direction_draws_each_stiffness_on_its_own_axes(page, explorer_url):
    """Item 13: in Every direction, each direction's |K| fills most of its plot's height (radial
    is several times axial: on a shared axis axial was squashed into a few per cent of it)."""
    open_explorer(page, explorer_url + "?" + urlencode(LINK))
    page.get_by_text("Every direction", exact=True).click()
    page.get_by_text("Ratios").wait_for()
    for mode in ("axial", "radial", "torsion", "conical"):
        page.wait_for_function(f"(label) => ({SPAN_JS})(label) !== null", arg=mode)
        shown = page.evaluate(SPAN_JS, mode)
        span = max(shown["y"]) - min(shown["y"])
        assert span >= 0.5 * (shown["end"] - shown["start"]), (mode, shown["title"], span, shown["start"], shown["end"])


def test_the_pinned_reference_is_drawn_in_every_plot_of_the_same_quantity(page, explorer_url):
    """Item 13: pinned, then the design changed: the reference is drawn dashed in Slices,
    Fletcher–Gent and Every direction too, and it is the core's stiffness of the pinned design."""
    open_explorer(page, explorer_url + "?" + urlencode(LINK))
    page.get_by_role("button", name="Pin as reference").click()
    page.get_by_text("No reference pinned").wait_for(state="detached")
    field = page.get_by_label("Shear modulus µ (MPa)")
    field.fill("2.6")
    field.press("Enter")
    pinned = link_design(LINK, "axial")
    checks = {"Slices": ("|K|: single modulus, slices and continuum", lambda x: stiffness(pinned, LINK["f_Hz"], x)
                         .magnitude[:, 0]),
              "Fletcher–Gent, branch by branch": ("Re K, branch by branch (stacked)",
                                                  lambda x: stiffness(pinned, LINK["f_Hz"], x).stiffness.real[:, 0]),
              "Every direction": ("|K| axial",
                                  lambda x: stiffness(pinned.replace(shape="long"), LINK["f_Hz"], x).magnitude[:, 0])}
    for tab, (title, exact) in checks.items():
        page.get_by_text(tab, exact=True).click()
        wait_plot(page, title, "p.legends.includes('reference')")
        ref = curve(page, title, "reference")
        assert ref["float64"]
        assert_allclose(ref["y"], exact(np.asarray(ref["x"]) * 1e-3) * PER_SI["kN/mm"], rtol=1e-12)
