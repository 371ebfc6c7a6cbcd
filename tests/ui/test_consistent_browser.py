"""A change is painted whole (issue 27, item 11): after a mode switch the page never paints the
old mode's amplitude under the new mode's unit, or the slider in one mode beside the operating
point's text in the other. Every animation frame of the page is sampled while the switch
arrives: each must show one mode's state, before or after."""

import pytest
from playwright.sync_api import expect

from tests.ui.bokeh_page import open_explorer

pytestmark = pytest.mark.usefixtures("console_errors", "no_server_tracebacks")

# what the page paints, sampled at each animation frame into window.painted: the amplitude
# slider's label, position and bounds, and the operating point's text
SAMPLE_JS = """() => {
  const doc = Bokeh.documents[0];
  const models = [...doc.all_models];
  const slider = models.find(m => typeof m.title === 'string' && m.title.startsWith('Drive amplitude'));
  const text = models.find(m => (m.css_classes || []).includes('operating-point'));
  window.painted = [];
  // the pane's text is escaped HTML: decoded, then the operating point's span read
  const decoded = (html) => new DOMParser().parseFromString(html, 'text/html').documentElement.textContent;
  const point = () => (decoded(text.text).match(/class="op-point">([^<]*)</) || [null, ''])[1];
  const sample = () => {
    window.painted.push([slider.title, slider.value, slider.start, slider.end, point()]);
    if (!window.stopSampling) requestAnimationFrame(sample);
  };
  requestAnimationFrame(sample);
}"""


def test_a_mode_switch_is_painted_in_one_piece(page, explorer_url):
    open_explorer(page, explorer_url)
    page.evaluate(SAMPLE_JS)
    page.wait_for_function("window.painted.length > 2")
    before = tuple(page.evaluate("window.painted[window.painted.length - 1]"))
    assert "(mm)" in before[0] and " mm," in before[4]
    page.get_by_role("button", name="torsion").click()
    expect(page.locator(".operating-point")).to_contain_text(" rad,")
    page.wait_for_function("""() => { const p = window.painted, n = p.length;
      return n > 10 && JSON.stringify(p[n - 1]) === JSON.stringify(p[n - 10]); }""")  # settled
    page.evaluate("window.stopSampling = true")
    painted = [tuple(p) for p in page.evaluate("window.painted")]
    after = painted[-1]
    assert "(rad)" in after[0] and " rad," in after[4] and after[1] != before[1]
    mixed = [p for p in painted if p not in (before, after)]
    assert mixed == [], f"painted between the two modes: {mixed[:3]}"
