"""The explorer in a real browser: load, sliders, taps, links, bad input, comparison, exports."""

import json
import re
from pathlib import Path

import pytest

from core import loads_design

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

pytestmark = pytest.mark.usefixtures("console_errors", "no_server_tracebacks")

PLOTS_JS = """() => {
  const out = {};
  for (const m of Bokeh.documents[0].all_models) {
    if (m.type === 'Figure' && m.title) {
      let total = 0, points = 0;
      const legends = [];
      for (const r of m.renderers) {
        const src = r.data_source;
        if (src && src.data) {
          for (const col of Object.values(src.data)) {
            if (col && col.length !== undefined && typeof col[0] === 'number') {
              for (const v of col) { if (Number.isFinite(v)) { total += v; points++; } }
            }
          }
        }
      }
      const parts = [...m.renderers, ...m.center, ...m.left, ...m.right, ...m.above, ...m.below];
      for (const l of parts) {
        if (l.items) for (const it of l.items) legends.push(it.label && (it.label.value || it.label.field));
      }
      const spans = parts.filter(c => c.type === 'Span').map(s => s.location);
      out[m.title.text] = {signature: total, points, spans, legends};
    }
  }
  return out;
}"""


def plots(page):
    return page.evaluate(PLOTS_JS)


def open_explorer(page, url):
    page.goto(url)
    page.wait_for_function("() => window.Bokeh && Bokeh.documents.length > 0", timeout=30000)
    page.locator(".bk-Canvas").nth(4).wait_for(timeout=30000)
    wait_quiet(page)


def wait_quiet(page, ms=600):
    """Wait until the document has had no change for ``ms``: every update has arrived."""
    page.evaluate(
        """(ms) => new Promise(resolve => {
            const doc = Bokeh.documents[0];
            let last = performance.now();
            const cb = () => { last = performance.now(); };
            doc.on_change(cb);
            const tick = () => {
              if (performance.now() - last > ms) { doc.remove_on_change(cb); resolve(); }
              else setTimeout(tick, 50);
            };
            tick();
        })""",
        ms,
    )


def by_title(page, prefix):
    return {t: v for t, v in plots(page).items() if t.startswith(prefix)}


def test_page_loads_with_every_plot(page, explorer_url):
    open_explorer(page, explorer_url)
    titles = set(plots(page))
    assert {"|K| against frequency", "|K| against amplitude", "Loss factor against frequency",
            "Loss factor against amplitude"} <= titles
    assert "Hysteresis loop at the operating point" in titles
    assert page.get_by_text("0.1 mm, 10 Hz").count() >= 1
    assert page.get_by_text("VP 40/70120 (Paper B)").count() >= 1
    assert all(v["points"] > 0 for v in plots(page).values())


def test_moving_a_slider_changes_every_plot(page, explorer_url):
    open_explorer(page, explorer_url)
    before = plots(page)
    handle = page.locator(".noUi-handle").first  # the drive amplitude
    handle.focus()
    for _ in range(40):
        handle.press("ArrowRight")
    wait_quiet(page)
    after = plots(page)
    assert page.locator(".op-point").inner_text().find("0.1 mm,") == -1
    assert after["Hysteresis loop at the operating point"] != before["Hysteresis loop at the operating point"]
    for title in ("|K| against frequency", "Loss factor against frequency"):
        assert after[title]["signature"] != before[title]["signature"], title  # the operating curve
    for title in ("|K| against amplitude", "Loss factor against amplitude"):
        assert after[title]["spans"][0] > before[title]["spans"][0], title  # the marker


def tap(page, canvas, x_fraction, moved):
    """Tap ``canvas`` at ``x_fraction`` of its width until ``moved(plots)`` (a tap landing while
    the page is still busy after loading is dropped by the browser; three tries)."""
    box = canvas.bounding_box()
    for _ in range(3):
        canvas.click(position={"x": box["width"] * x_fraction, "y": box["height"] * 0.5})
        wait_quiet(page)
        if moved(plots(page)):
            return
        page.wait_for_timeout(1000)


def test_tap_moves_the_operating_point_in_every_plot(page, explorer_url):
    open_explorer(page, explorer_url)
    tap(page, page.locator(".bk-Canvas").nth(1), 0.6,  # |K| against frequency
        lambda p: p["|K| against frequency"]["spans"][0] != 10)
    p = plots(page)
    f_k = p["|K| against frequency"]["spans"][0]
    f_eta = p["Loss factor against frequency"]["spans"][0]
    assert f_k == pytest.approx(f_eta) and 20 < f_k < 100 and f_k != 10
    assert f"{f_k:.3g} Hz" in page.locator(".op-point").inner_text()
    # and an amplitude tap moves the amplitude everywhere
    canvas = page.locator(".bk-Canvas").nth(4)  # loss factor against amplitude
    box = canvas.bounding_box()
    canvas.click(position={"x": box["width"] * 0.3, "y": box["height"] * 0.5})
    wait_quiet(page)
    p = plots(page)
    x = p["Loss factor against amplitude"]["spans"][0]
    assert x == pytest.approx(p["|K| against amplitude"]["spans"][0]) and x != 0.1
    assert f"{x:.3g} mm" in page.locator(".op-point").inner_text()


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
    wait_quiet(page)
    page.wait_for_url(re.compile(r"L_mm=30"))


def test_invalid_value_shows_its_message_and_keeps_the_plots(page, explorer_url):
    open_explorer(page, explorer_url)
    before = plots(page)
    field = page.get_by_label("Outer radius b (mm)")
    field.fill("15")
    field.press("Enter")
    message = page.locator(".field-error")
    message.wait_for(timeout=10000)
    assert "Must be larger than the inner radius a." in message.inner_text()
    page.get_by_text("The plots show the last valid design").first.wait_for(timeout=10000)
    wait_quiet(page)
    after = plots(page)
    for title in ("|K| against frequency", "|K| against amplitude"):
        assert after[title]["signature"] == pytest.approx(before[title]["signature"])
    field.fill("40")  # the session goes on
    field.press("Enter")
    page.locator(".field-error").wait_for(state="detached", timeout=10000)
    wait_quiet(page)
    assert plots(page)["|K| against frequency"] != before["|K| against frequency"]


def test_comparison_overlay_appears(page, explorer_url):
    open_explorer(page, explorer_url)
    page.get_by_role("button", name="Pin as reference").click()
    wait_quiet(page)
    field = page.get_by_label("Length L (mm)")
    field.fill("99")
    field.press("Enter")
    wait_quiet(page)
    p = plots(page)
    assert "reference" in p["|K| against frequency"]["legends"]
    page.get_by_text("+10.00 %").first.wait_for(timeout=10000)


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


def test_slices_tap_and_teaching_play(page, explorer_url):
    open_explorer(page, explorer_url)
    page.get_by_text("Slices", exact=True).click()
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].some(m => m.type === 'Figure' && m.title && m.title.text.startsWith('|K|: single'))",
        timeout=20000,
    )
    wait_quiet(page)
    canvas = page.locator(".bk-Canvas").first
    box = canvas.bounding_box()
    canvas.click(position={"x": box["width"] * 0.25, "y": box["height"] * 0.5})
    wait_quiet(page)
    spans = plots(page)["|K|: single modulus, slices and continuum"]["spans"]
    assert spans and spans[0] != 0.1
    assert page.get_by_text("3 slices").count() >= 1
    page.get_by_text("Fletcher–Gent, branch by branch", exact=True).click()
    page.wait_for_function(
        "() => [...Bokeh.documents[0].all_models].some(m => m.type === 'Figure' && m.title && m.title.text.startsWith('Loop shape during'))",
        timeout=20000,
    )
    wait_quiet(page)

    first = page.locator(".frame-point").inner_text()
    before = plots(page)["Loop shape during the amplitude sweep"]["signature"]
    page.locator("button.play").click()
    page.wait_for_timeout(1500)
    assert page.locator(".frame-point").inner_text() != first
    assert plots(page)["Loop shape during the amplitude sweep"]["signature"] != before


def test_upload_fit_and_use(page, explorer_url, tmp_path):
    from core import PAPER_B
    from core.synthetic import paper_b_example

    data, _ = paper_b_example(PAPER_B)
    good = tmp_path / "measured.csv"
    data.to_csv(good)
    bad = tmp_path / "bad.csv"
    bad.write_text("frequency_hz,amplitude,magnitude,loss_factor\n10,1e-4,,0.1\n")
    open_explorer(page, explorer_url)
    page.get_by_text("Measured data and fit", exact=True).click()
    page.get_by_role("button", name="Fit the five material parameters").wait_for(timeout=20000)
    inputs = page.locator("input[type=file]")
    inputs.first.set_input_files(str(bad))
    page.locator(".data-error").wait_for(timeout=10000)
    assert "line 2: magnitude is missing" in page.locator(".data-error").inner_text()
    inputs.first.set_input_files(str(good))  # the drop area holds both: the good one loads
    page.get_by_text("150 points").first.wait_for(timeout=10000)
    assert "bad.csv: line 2" in page.locator(".data-error").inner_text()
    assert "not loaded; the other files are" in page.locator(".data-error").inner_text()
    # removing the bad file from the drop area clears its message
    item = page.locator(".filepond--item").filter(has_text="bad.csv")
    item.locator(".filepond--action-revert-item-processing").click()  # "tap to undo" once uploaded
    page.locator(".data-error").wait_for(state="detached", timeout=10000)
    page.get_by_role("button", name="Fit the five material parameters").click()
    page.get_by_text("Correlation between parameters").wait_for(timeout=20000)
    page.get_by_role("button", name="Use the fitted design in the explorer").click()
    page.get_by_text("VP 40/70120 (Paper B) (fitted)").first.wait_for(timeout=10000)
    page.get_by_text("Explorer", exact=True).click()
    wait_quiet(page)
    measured = plots(page)["|K| against frequency"]
    assert measured["points"] > 150 * 2  # curves and the 150 measured points


def test_an_oversized_file_is_refused_in_the_browser(page, explorer_url, tmp_path, server_log):
    """A 21 MB file (valid rows) is refused by the drop area with the limit in its message,
    before anything is sent; the session goes on and takes the next file."""
    from core.data import MAX_BYTES

    row = "10,0.0001,4200000.0000000000,0.1400000000000000\n"
    big = tmp_path / "big.csv"
    big.write_text("frequency_hz,amplitude,magnitude,loss_factor\n" + row * (MAX_BYTES // len(row) + 20_000))
    assert big.stat().st_size > MAX_BYTES
    logged = len(server_log.records)
    open_explorer(page, explorer_url)
    page.get_by_text("Measured data and fit", exact=True).click()
    page.get_by_role("button", name="Fit the five material parameters").wait_for(timeout=20000)
    inputs = page.locator("input[type=file]")
    inputs.first.set_input_files(str(big))
    page.get_by_text("File is too large").first.wait_for(timeout=10000)
    assert page.get_by_text("Maximum file size is 20 MB").count() >= 1
    page.wait_for_timeout(1000)
    assert page.get_by_text("No measured data loaded.").count() == 1  # nothing reached the server
    inputs.nth(1).set_input_files(str(EXAMPLES / "paper_b_loop.csv"))  # the session goes on
    page.get_by_text("400 samples at 0.1 Hz").wait_for(timeout=10000)
    # what the server logged meanwhile (an earlier test's page closing mid-write makes tornado
    # log a WebSocketClosedError: a closed page, not this upload)
    new = [r for r in server_log.records[logged:] if r.exc_info or "Traceback" in r.getMessage()]
    assert not [r for r in new if "WebSocketClosedError" not in r.getMessage()], new


def test_diagnose_a_hidden_effect_and_use_the_final_model(page, explorer_url, tmp_path):
    import numpy as np

    from core import PAPER_B
    from core.synthetic import synthetic_stiffness

    hidden = PAPER_B.replace(effects={"inertia": {"mass": 0.5}})
    measured = tmp_path / "inertia.csv"
    synthetic_stiffness(hidden, np.linspace(1, 100, 30), [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3],
                        seed=3).to_csv(measured)
    open_explorer(page, explorer_url)
    page.get_by_text("Find the missing effect", exact=True).click()
    page.get_by_role("button", name="Diagnose").wait_for(timeout=20000)
    page.locator("input[type=file]").last.set_input_files(str(measured))
    page.get_by_text("150 points").first.wait_for(timeout=10000)
    page.get_by_role("button", name="Diagnose").click()
    page.get_by_text("Step 1: add Apparent mass seen by the force sensor").wait_for(timeout=30000)
    page.get_by_text("What is left is noise", exact=True).wait_for(timeout=5000)
    wait_quiet(page)
    shown = plots(page)
    gaps = shown["Gap (relative RMS misfit of complex stiffness) after each step"]
    assert gaps["points"] == 2 and len(gaps["spans"]) == 1  # baseline and + inertia; the noise line
    assert shown["Final: |K| misfit (%)"]["points"] >= 150
    page.get_by_role("button", name="Use the final model in the explorer").click()
    page.get_by_text("effects: inertia").first.wait_for(timeout=10000)
    page.get_by_text("(diagnosed)").first.wait_for(timeout=10000)


def test_mystery_demo_reveals_its_truth(page, explorer_url):
    open_explorer(page, explorer_url)
    page.get_by_text("Find the missing effect", exact=True).click()
    page.get_by_role("button", name="Load a mystery data set (demo)").click()
    page.get_by_text("mystery data set").first.wait_for(timeout=10000)
    page.get_by_role("button", name="Diagnose").click()
    page.get_by_role("button", name="Reveal the truth").wait_for(timeout=30000)
    page.get_by_role("button", name="Reveal the truth").click()
    page.get_by_text(re.compile("Hidden in the data|Nothing was hidden")).wait_for(timeout=10000)
    assert page.get_by_text("The diagnosis found exactly that.").count() == 1


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
    # hidden lines stay hidden through an update, and come back on a second click
    page.get_by_label("Shear modulus µ (MPa)").fill("3")
    page.get_by_label("Shear modulus µ (MPa)").press("Enter")
    wait_quiet(page)
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
    page.wait_for_url(re.compile(r"mu_MPa=2\.8"))
    wait_quiet(page)
    assert page.evaluate("() => history.length") - before <= 2
    page.goto(page.url)
    page.locator(".bk-Canvas").nth(4).wait_for(timeout=30000)
    wait_quiet(page)
    assert page.get_by_label("Shear modulus µ (MPa)").input_value() == "2.8"


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
    """The three BokehJS patches of app/patches.py are active, and what they change still behaves
    as Bokeh's own code: glyph elements sit on their data's box, CSS theming still applies."""
    open_explorer(page, explorer_url)
    assert page.evaluate("() => [window.bushingStyleWrites, window.bushingCssReads, window.bushingGlyphPosition]") \
        == ["skip-unchanged", "cached-per-task", "inline-style"]
    page.get_by_label("Shear modulus µ (MPa)").fill("2.7")
    page.get_by_label("Shear modulus µ (MPa)").press("Enter")
    wait_quiet(page)
    boxes = page.evaluate(GLYPH_BOXES_JS)
    # with data on screen: the loop's three branches and total; against frequency four sweeps and
    # the operating curve, against amplitude three and the operating curve
    assert sum(b["expected"][4] == "" for b in boxes) == 4 + 2 * 5 + 2 * 4
    assert [b for b in boxes if not same_box(b["shown"], b["expected"])] == []
    assert all(b["sheet"].strip() == "" for b in boxes)  # the box is in the inline style only
    before, themed, after = page.evaluate(CSS_THEME_JS, "|K| against frequency")
    assert themed == "rgb(1, 2, 3)"
    assert before == after != themed


def test_every_direction_from_a_link(page, explorer_url):
    """A link to a radial, finite-length design: the mode and the switch come back, and the
    Every direction tab draws its card."""
    open_explorer(page, explorer_url + "?mode=radial&finite=true")
    assert page.get_by_role("button", name="radial").get_attribute("class").count("bk-active") == 1
    page.get_by_text("Finite-length S is 0.482 of the long-bushing formula").wait_for(timeout=10000)
    page.get_by_text("Every direction", exact=True).click()
    page.get_by_text("radial (finite)").wait_for(timeout=20000)
    page.get_by_text("Ratios").wait_for(timeout=5000)
    wait_quiet(page)
    shown = plots(page)
    assert shown["|K| along and across the axis"]["points"] >= 2 * 60
    assert shown["Loss factor, turning and tilting"]["points"] >= 2 * 60


def test_what_ifs_bands_sensitivities_and_a_design_from_targets(page, explorer_url):
    """Tolerances switched on draw a band on every stiffness plot; the sensitivity bars are
    drawn; a |K| target finds a design that the explorer takes."""
    open_explorer(page, explorer_url)
    page.get_by_text("What-ifs", exact=True).click()
    page.get_by_role("button", name="Find designs").wait_for(timeout=20000)
    wait_quiet(page)
    shown = plots(page)
    assert shown["|K|: % per +1 % of the parameter"]["points"] == 8
    box = page.get_by_label("Shear modulus µ ± %")
    box.fill("10")
    box.press("Enter")
    page.locator(".band-switch input[type=checkbox]").check()
    wait_quiet(page)
    page.get_by_text("Explorer", exact=True).click()
    page.get_by_text("Tolerance band (5–95 %").wait_for(timeout=20000)
    wait_quiet(page)
    for title in ("|K| against frequency", "Loss factor against amplitude"):
        assert "5–95 % band" in plots(page)[title]["legends"], title
    page.get_by_text("What-ifs", exact=True).click()
    target = page.get_by_label("|K| target")
    target.fill("4.5")
    target.press("Enter")
    page.get_by_role("button", name="Find designs").click()
    page.get_by_text("1 design meets every target").wait_for(timeout=20000)
    page.get_by_role("button", name="Take it into the explorer").click()
    page.get_by_text("VP 40/70120 (Paper B) (from targets)").first.wait_for(timeout=10000)
    page.get_by_text("Explorer", exact=True).click()
    page.get_by_text("|K| = 4.5 kN/mm").wait_for(timeout=20000)


def test_a_link_brings_the_tolerance_bands(page, explorer_url):
    open_explorer(page, explorer_url + "?tol=mu:10,L:1&bands=true")
    page.get_by_text("Tolerance band (5–95 %").wait_for(timeout=20000)
    wait_quiet(page)
    assert "5–95 % band" in plots(page)["|K| against frequency"]["legends"]
    page.get_by_text("What-ifs", exact=True).click()
    field = page.get_by_label("Shear modulus µ ± %")
    field.wait_for(timeout=20000)
    assert field.input_value() == "10"
    field.fill("12")
    field.press("Enter")
    page.wait_for_url(re.compile(r"tol=L(%3A|:)1(%2C|,)mu(%3A|:)12"), timeout=10000)
