"""The explorer tab in a real browser: load, sliders, taps, links, bad input, comparison, exports,
legends, the address bar, the BokehJS patches. Each step waits for the state it then checks."""

import json
import re

import pytest
from playwright.sync_api import expect

from core import loads_design
from tests.ui.bokeh_page import (
    EXPLORER_TITLES,
    open_explorer,
    plots,
    settle,
    tap,
    wait_plot,
    wait_plot_changed,
    wait_ready,
    wait_tappable,
)

pytestmark = pytest.mark.usefixtures("console_errors", "no_server_tracebacks")


def test_page_loads_with_every_plot(page, explorer_url):
    open_explorer(page, explorer_url)
    shown = plots(page)
    assert set(EXPLORER_TITLES) <= set(shown)
    assert page.get_by_text("0.1 mm, 10 Hz").count() >= 1
    assert page.get_by_text("VP 40/70120 (Paper B)").count() >= 1
    assert all(v["points"] > 0 for v in shown.values())


SLIDER_JS = """(label) => [...Bokeh.documents[0].all_models].find(
    m => m.type === 'Slider' && m.title && m.title.startsWith(label)).value"""


def test_moving_a_slider_changes_every_plot(page, explorer_url):
    open_explorer(page, explorer_url)
    before = plots(page)
    handle = page.locator(".noUi-handle").first  # the drive amplitude
    handle.focus()
    for _ in range(40):
        handle.press("ArrowRight")
    # where the slider stands (log10 of the amplitude), as the server takes it (4 digits): the
    # last move has been answered once the summary and the amplitude markers show it
    amplitude = float(f"{10 ** page.evaluate(SLIDER_JS, 'Drive amplitude'):.4g}")
    expect(page.locator(".op-point")).to_have_text(f"{amplitude:.3g} mm, 10 Hz")
    for title in ("|K| against amplitude", "Loss factor against amplitude"):
        wait_plot(page, title, "Math.abs(p.spans[0] - arg) <= 1e-9 * arg", amplitude)
    after = plots(page)
    assert amplitude > 0.1
    assert after["Hysteresis loop at the operating point"] != before["Hysteresis loop at the operating point"]
    for title in ("|K| against frequency", "Loss factor against frequency"):
        assert after[title]["signature"] != before[title]["signature"], title  # the operating curve


def test_tap_moves_the_operating_point_in_every_plot(page, explorer_url):
    open_explorer(page, explorer_url)
    wait_tappable(page, "|K| against frequency")
    tap(page.locator(".bk-Canvas").nth(1), 0.6)  # |K| against frequency
    for title in ("|K| against frequency", "Loss factor against frequency"):
        wait_plot(page, title, "p.spans[0] !== 10")
    p = plots(page)
    f_k = p["|K| against frequency"]["spans"][0]
    f_eta = p["Loss factor against frequency"]["spans"][0]
    assert f_k == pytest.approx(f_eta) and 20 < f_k < 100
    expect(page.locator(".op-point")).to_contain_text(f"{f_k:.4g} Hz")  # a frequency's four digits
    # the address bar follows (its update is the change's last message), then the page rests
    # (the link is written when the page opens, at 10 Hz: wait for the tap's frequency)
    page.wait_for_url(lambda url: re.search(r"f_Hz=([0-9.e+-]+)", url).group(1) != "10")
    assert float(re.search(r"f_Hz=([0-9.e+-]+)", page.url).group(1)) == pytest.approx(f_k)
    wait_tappable(page, "Loss factor against amplitude")
    # and an amplitude tap moves the amplitude everywhere
    tap(page.locator(".bk-Canvas").nth(4), 0.3)  # loss factor against amplitude
    for title in ("|K| against amplitude", "Loss factor against amplitude"):
        wait_plot(page, title, "p.spans[0] !== 0.1")
    p = plots(page)
    x = p["Loss factor against amplitude"]["spans"][0]
    assert x == pytest.approx(p["|K| against amplitude"]["spans"][0]) and x != 0.1
    expect(page.locator(".op-point")).to_contain_text(f"{x:.3g} mm")


def test_a_link_restores_a_design(page, explorer_url):
    open_explorer(page, explorer_url + "?mode=torsion&a_mm=5&b_mm=11&L_mm=22&mu_MPa=2&m_MPa=0.2"
                  "&alpha=0.4&sigma_kPa=4&eps_half=0.001&amp=0.013&f_Hz=50")
    assert "0.013 rad, 50 Hz" in page.locator(".op-point").inner_text()
    assert page.get_by_text("Table 1 torsion example (Paper A)").count() >= 1
    assert plots(page)["|K| against frequency"]["spans"] == [50]
    # and the URL follows the inputs
    field = page.get_by_label("Length L (mm)")
    field.fill("30")
    field.press("Enter")
    page.wait_for_url(re.compile(r"L_mm=30"))


def test_invalid_value_shows_its_message_and_keeps_the_plots(page, explorer_url):
    open_explorer(page, explorer_url)
    before = plots(page)
    field = page.get_by_label("Outer radius b (mm)")
    field.fill("15")
    field.press("Enter")
    expect(page.locator(".field-error")).to_contain_text("Must be larger than the inner radius a.")
    # the banner is set at the end of the same server callback that would have changed the
    # design: any plot update of this edit has reached the page before (or with) it
    page.get_by_text("The plots show the last valid design").first.wait_for()
    after = plots(page)
    for title in ("|K| against frequency", "|K| against amplitude"):
        assert after[title]["signature"] == pytest.approx(before[title]["signature"])
    field.fill("40")  # the session goes on: the message goes, the curves change
    field.press("Enter")
    page.locator(".field-error").wait_for(state="detached")
    wait_plot_changed(page, "|K| against frequency", before["|K| against frequency"])


def test_comparison_overlay_appears(page, explorer_url):
    open_explorer(page, explorer_url)
    page.get_by_role("button", name="Pin as reference").click()
    expect(page.locator(".comparison")).to_contain_text("this design")  # the table, once pinned
    field = page.get_by_label("Length L (mm)")
    field.fill("99")
    field.press("Enter")
    page.get_by_text("+10.00 %").first.wait_for()
    wait_plot(page, "|K| against frequency", "p.legends.includes('reference')")


def test_exports(page, explorer_url, tmp_path):
    open_explorer(page, explorer_url)
    with page.expect_download() as dl:
        page.get_by_role("button", name="Design file (JSON)").click()
    path = tmp_path / "d.json"
    dl.value.save_as(path)
    assert loads_design(path.read_text()).name == "VP 40/70120 (Paper B)"
    assert json.loads(path.read_text())["mode"] == "axial"
    with page.expect_download() as dl:
        page.get_by_role("button", name="Stiffness table (CSV)").click()
    dl.value.save_as(tmp_path / "k.csv")
    assert (tmp_path / "k.csv").read_text().startswith(
        "frequency_hz,amplitude,stiffness_real,stiffness_imag,magnitude,loss_factor")
    # PNG from a plot's toolbar save tool
    canvas = page.locator(".bk-Canvas").nth(1)
    canvas.hover()
    with page.expect_download() as dl:
        page.locator(".bk-tool-icon-save").nth(1).click()
    assert dl.value.suggested_filename == "bushing-magnitude-vs-frequency.png"
    dl.value.save_as(tmp_path / "plot.png")
    assert (tmp_path / "plot.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


SHOWN_JS = """(title) => {
  const fig = [...Bokeh.documents[0].all_models].find(m => m.type === 'Figure' && m.title && m.title.text === title);
  const out = {};
  const legend = [...fig.center, ...fig.right, ...fig.left, ...fig.above, ...fig.below].find(m => m.type === 'Legend');
  for (const item of legend.items) out[item.label.value] = item.renderers.every(r => r.visible && !r.muted);
  return out;
}"""


def test_legend_entries_hide_their_lines(page, explorer_url):
    open_explorer(page, explorer_url)
    title = "|K| against frequency"
    shown = page.evaluate(SHOWN_JS, title)
    labels = list(shown)
    assert labels[:4] == ["ε̂ = 0.01 ε½", "ε̂ = 0.1 ε½", "ε̂ = ε½", "ε̂ = 10 ε½"] and all(shown.values())
    # the first figure with these entries in the page is the top-left one, |K| against frequency
    page.locator(".bk-item", has_text=labels[1]).first.click()
    page.locator(".bk-item", has_text="operating point").first.click()
    page.wait_for_function(f"() => !({SHOWN_JS})({title!r})['operating point']")
    hidden = {labels[1], "operating point"}
    assert page.evaluate(SHOWN_JS, title) == {k: k not in hidden for k in labels}
    assert all(page.evaluate(SHOWN_JS, "Loss factor against frequency").values())
    # hidden lines stay hidden through an update (its new data, then the address bar, the
    # change's last message), and come back on a second click
    before = plots(page)[title]
    page.get_by_label("Shear modulus µ (MPa)").fill("3")
    page.get_by_label("Shear modulus µ (MPa)").press("Enter")
    wait_plot_changed(page, title, before)
    page.wait_for_url(re.compile(r"mu_MPa=3(&|$)"))
    settle(page)
    assert page.evaluate(SHOWN_JS, title) == {k: k not in hidden for k in labels}
    page.locator(".bk-item", has_text=labels[1]).first.click()
    page.locator(".bk-item", has_text="operating point").first.click()
    page.wait_for_function(f"() => ({SHOWN_JS})({title!r})['operating point']")
    assert all(page.evaluate(SHOWN_JS, title).values())


def test_a_slider_drag_is_one_history_entry(page, explorer_url):
    """The address bar follows the design after a pause: quick moves make one entry, and the
    link holds the last value."""
    open_explorer(page, explorer_url)
    before = page.evaluate("() => history.length")
    field = page.get_by_label("Shear modulus µ (MPa)")
    for value in ("2.5", "2.6", "2.7", "2.8"):
        field.fill(value)
        field.press("Enter")
    # the address bar is written once, after the last edit: when it shows 2.8, every entry the
    # edits made is in the history
    page.wait_for_url(re.compile(r"mu_MPa=2\.8"))
    assert page.evaluate("() => history.length") - before <= 2
    page.goto(page.url)
    wait_ready(page)
    expect(page.get_by_label("Shear modulus µ (MPa)")).to_have_value("2.8")


# For every glyph renderer of the page's plots: where its element is, and where Bokeh's own
# code would put it (the box of its data on screen, or hidden without valid data).
GLYPH_BOXES_JS = """() => {
  const out = [];
  for (const v of Bokeh.index.all_views()) {
    if (v.model == null || v.model.type !== 'GlyphRenderer' || v.el == null) continue;
    const box = v.bbox, style = v.el.style;
    const expected = box != null && box.is_valid
      ? [box.left, box.top, box.width, box.height, ''] : [null, null, null, null, 'none'];
    const px = (text) => text.endsWith('px') ? parseFloat(text) : text;
    const shown = style.display === 'none' ? [null, null, null, null, 'none']
      : [px(style.left), px(style.top), px(style.width), px(style.height), style.display];
    out.push({expected, shown, sheet: v.position.css ?? v.position.el?.textContent ?? ''});
  }
  return out;
}"""

# A `--bk-axis-line-color` variable on an axis' element is Bokeh's CSS theming: the cached
# reads must honour it at the next paint, and forget it once removed.
CSS_THEME_JS = """async (title) => {
  const fig = [...Bokeh.documents[0].all_models].find(m => m.type === 'Figure' && m.title && m.title.text === title);
  const line = Bokeh.index.find_one(fig.below[0]).visuals.axis_line, el = line.obj.el;
  const read = () => line.get_line_color();
  const frame = () => new Promise(r => requestAnimationFrame(() => setTimeout(r, 0)));
  const before = read();
  el.style.setProperty('--bk-axis-line-color', 'rgb(1, 2, 3)');
  await frame();
  const themed = read();
  el.style.removeProperty('--bk-axis-line-color');
  await frame();
  return [before, themed, read()];
}"""


def same_box(shown, expected):
    """The same box to the 0.001 px that the browser keeps of an inline length."""
    return shown[4] == expected[4] and all(
        a == b if a is None or b is None else abs(a - b) < 1e-3 for a, b in zip(shown[:4], expected[:4]))


def test_bokehjs_paint_patches_keep_bokehs_behaviour(page, explorer_url):
    """The three BokehJS patches of app/patches/ are active, and what they change still behaves
    as Bokeh's own code: glyph elements sit on their data's box, CSS theming still applies."""
    open_explorer(page, explorer_url)
    assert page.evaluate("() => [window.bushingStyleWrites, window.bushingCssReads, window.bushingGlyphPosition]") \
        == ["skip-unchanged", "cached-per-task", "inline-style"]
    before = plots(page)
    page.get_by_label("Shear modulus µ (MPa)").fill("2.7")
    page.get_by_label("Shear modulus µ (MPa)").press("Enter")
    for title in EXPLORER_TITLES:  # the new data arrived, then the change's last message
        wait_plot_changed(page, title, before[title])
    page.wait_for_url(re.compile(r"mu_MPa=2\.7"))
    settle(page)  # and every view has painted it
    boxes = page.evaluate(GLYPH_BOXES_JS)
    # with data on screen: the loop's three branches and total; against frequency four sweeps and
    # the operating curve, against amplitude three and the operating curve
    assert sum(b["expected"][4] == "" for b in boxes) == 4 + 2 * 5 + 2 * 4
    assert [b for b in boxes if not same_box(b["shown"], b["expected"])] == []
    assert all(b["sheet"].strip() == "" for b in boxes)  # the box is in the inline style only
    before, themed, after = page.evaluate(CSS_THEME_JS, "|K| against frequency")
    assert themed == "rgb(1, 2, 3)"
    assert before == after != themed
