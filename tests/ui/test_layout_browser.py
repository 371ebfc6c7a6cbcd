"""The page at the two window sizes a user is likely to have (issue #27, item 3): every tab's
header is on screen and opens its tab, every tab's content takes the width, no text is cut (by the
window or by a box that clips it), every figure's title fits its figure, and the sidebar scrolls
rather than cuts. Each tab is also shot, at both sizes, into the test's folder."""

from pathlib import Path

import pytest

from tests.ui.bokeh_page import open_explorer, settle
from tests.ui.test_waiting_browser import upload_150_points
from tools.screenshots import DRAWN_JS, slug

SIZES = ((1280, 720), (1600, 1000))
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

# the tab bar's headers: text and box (page pixels)
HEADERS_JS = """() => {
  const tabs = [...Bokeh.index.all_views()].find(v => v.model.type.endsWith('Tabs'));
  return [...tabs.shadow_el.querySelectorAll('.bk-tab')].map(h => {
    const r = h.getBoundingClientRect();
    return {text: h.textContent.trim(), left: r.left, right: r.right, top: r.top, bottom: r.bottom,
            width: r.width, height: r.height};
  });
}"""

# the selected tab's content and the tab bar: widths (pixels)
CONTENT_JS = """() => {
  const tabs = [...Bokeh.index.all_views()].find(v => v.model.type.endsWith('Tabs'));
  const bar = tabs.el.getBoundingClientRect();
  const child = tabs.child_views[tabs.model.active].el.getBoundingClientRect();
  return {bar: bar.width, width: child.width, height: child.height};
}"""

# every visible piece of text that the window or a box that clips (overflow other than visible)
# cuts across its width: [text, left, right, what cuts it]
CLIPPED_TEXT_JS = """() => {
  const out = [];
  const parentOf = n => n.parentNode instanceof ShadowRoot ? n.parentNode.host : n.parentNode;
  const walk = root => {
    const it = document.createTreeWalker(root, NodeFilter.SHOW_ELEMENT | NodeFilter.SHOW_TEXT);
    for (let n = it.nextNode(); n; n = it.nextNode()) {
      if (n.nodeType === 1 && n.shadowRoot) walk(n.shadowRoot);
      if (n.nodeType !== 3 || !n.textContent.trim() || !n.parentElement) continue;
      const range = document.createRange();
      range.selectNodeContents(n);
      const r = range.getBoundingClientRect();
      if (r.width === 0 || r.height === 0) continue;
      if (getComputedStyle(n.parentElement).visibility === 'hidden') continue;
      let cut = (r.left < -1 || r.right > innerWidth + 1) ? 'the window' : null;
      let hidden = false;
      for (let a = n.parentElement; a instanceof Element && !cut; a = parentOf(a)) {
        if (getComputedStyle(a).overflowX === 'visible') continue;
        const b = a.getBoundingClientRect();
        // inside something not shown, or shown to screen readers only (a box of a pixel, as
        // FilePond's file names and button labels)
        if (b.width <= 1 || b.height <= 1) { hidden = true; break; }
        if (r.left < b.left - 1 || r.right > b.right + 1) cut = `${a.tagName.toLowerCase()}.${a.className}`;
      }
      if (cut && !hidden) out.push([n.textContent.trim().slice(0, 80), Math.round(r.left), Math.round(r.right), cut]);
    }
  };
  walk(document.body);
  return out;
}"""

# every figure shown whose title (drawn in its canvas) runs past the canvas or under its toolbar:
# [title, its width, the width it has] (pixels, measured with the title's own font)
TITLES_CUT_JS = """() => {
  const ctx = document.createElement('canvas').getContext('2d');
  const views = [...Bokeh.index.all_views()];
  const out = [];
  for (const v of views) {
    if (v.model.type !== 'Figure' || !v.model.title || !v.model.title.text) continue;
    if (v.el.getBoundingClientRect().width === 0) continue;
    const t = v.model.title;
    const title_view = v.renderer_views.get(t) ?? [...v.renderer_views.values()].find(r => r.model === t);
    const left = title_view ? title_view.bbox.x0 : v.frame_view.bbox.x0;
    let right = v.canvas_view.bbox.x1;
    const toolbar = views.find(u => u.model === v.model.toolbar && u.el.getBoundingClientRect().width > 0);
    if (toolbar && v.model.toolbar_location === 'right') {
      right = Math.min(right, toolbar.el.getBoundingClientRect().left - v.canvas_view.el.getBoundingClientRect().left);
    }
    ctx.font = `${t.text_font_style} ${t.text_font_size} ${t.text_font}`;
    const width = ctx.measureText(t.text).width;
    if (left + width > right + 1) out.push([t.text, Math.round(width), Math.round(right - left)]);
  }
  return out;
}"""

# the sidebar: its content's height, the height shown, and whether it scrolls
SIDEBAR_JS = """() => {
  const s = document.querySelector('#sidebar');
  const style = getComputedStyle(s);
  return {scroll: s.scrollHeight, client: s.clientHeight, overflow: style.overflowY,
          bottom: s.getBoundingClientRect().bottom};
}"""


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test_every_tab_reachable_and_nothing_cut(page, explorer_url, console_errors, tmp_path, size):
    width, height = size
    page.set_viewport_size({"width": width, "height": height})
    open_explorer(page, explorer_url)

    headers = page.evaluate(HEADERS_JS)
    assert len(headers) == 8, headers
    for h in headers:  # each header wholly on screen
        assert 0 <= h["left"] and h["right"] <= width and 0 <= h["top"] and h["bottom"] <= height, h
        assert h["width"] > 0 and h["height"] > 0, h

    problems = []
    for index, header in enumerate(headers):
        page.locator(".bk-tab").filter(has_text=header["text"]).first.click()
        page.wait_for_function(f"""() => {{
          const tabs = [...Bokeh.index.all_views()].find(v => v.model.type.endsWith('Tabs'));
          return tabs.model.active === {index};
        }}""")
        page.wait_for_function(DRAWN_JS, timeout=60_000)
        settle(page)
        page.screenshot(path=str(tmp_path / f"{width}x{height}-{index + 1:02d}-{slug(header['text'])}.png"))
        content = page.evaluate(CONTENT_JS)
        if content["width"] < 0.9 * content["bar"]:
            problems.append((header["text"], "content narrower than the tab bar", content))
        for cut in page.evaluate(CLIPPED_TEXT_JS):
            problems.append((header["text"], "text cut", cut))
        for cut in page.evaluate(TITLES_CUT_JS):
            problems.append((header["text"], "figure title cut", cut))
    assert problems == [], "\n".join(map(str, problems))

    sidebar = page.evaluate(SIDEBAR_JS)
    if sidebar["scroll"] > sidebar["client"]:  # more than it shows: it scrolls, within the window
        assert sidebar["overflow"] in ("auto", "scroll"), sidebar
        assert sidebar["bottom"] <= height + 1, sidebar


def cut(page) -> list:
    """What the window or a box cuts on the page as it is: texts, then figure titles."""
    return ([("text cut", c) for c in page.evaluate(CLIPPED_TEXT_JS)]
            + [("figure title cut", c) for c in page.evaluate(TITLES_CUT_JS)])


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test_nothing_cut_with_data_a_fit_and_a_report(page, explorer_url, console_errors, tmp_path, size):
    """The views that only data fill: the measured data over the fitted and the starting
    model, the fit's tables, the diagnosis' report and its maps (their plot titles were cut at
    1280×720: "|K|: measured (dots) and model (lines) at each amplitude" in 329 pixels)."""
    width, height = size
    page.set_viewport_size({"width": width, "height": height})
    open_explorer(page, explorer_url)
    page.get_by_text("Measured data and fit", exact=True).click()
    page.locator("#main input[type=file]").first.set_input_files(str(EXAMPLES / "paper_b_stiffness.csv"))
    page.get_by_role("button", name="Fit the five material parameters").click()
    page.get_by_text("Correlation between parameters").wait_for(timeout=120_000)
    page.wait_for_function(DRAWN_JS, timeout=60_000)
    settle(page)
    page.screenshot(path=str(tmp_path / f"{width}x{height}-fit.png"))
    problems = [("fit", *c) for c in cut(page)]

    upload_150_points(page, tmp_path)
    page.get_by_role("button", name="Diagnose").click()
    page.get_by_text("What is left is noise", exact=True).wait_for(timeout=120_000)
    page.wait_for_function(DRAWN_JS, timeout=60_000)
    settle(page)
    page.screenshot(path=str(tmp_path / f"{width}x{height}-report.png"))
    problems += [("report", *c) for c in cut(page)]
    page.get_by_text("Where they disagree: misfit maps", exact=True).click()
    page.wait_for_function(DRAWN_JS, timeout=60_000)
    settle(page)
    problems += [("maps", *c) for c in cut(page)]
    assert problems == [], "\n".join(map(str, problems))
