"""A mode switch is written into the plots the page has (issue 27, item 16: a switch took
0.41–0.56 s against a 300 ms target, most of it HoloViews drawing every plot again): the page
receives new data, ranges, markers and words (axis labels, tooltips) for the plots it has, and
nothing else of them changes. Counted in the page: each plot-model change the switch brings."""

import pytest
from playwright.sync_api import expect

from tests.ui.bokeh_page import EXPLORER_TITLES, open_explorer, settle

pytestmark = pytest.mark.usefixtures("console_errors", "no_server_tracebacks")

# every change of a model of the explorer's figures, from now on, into window.plotChanges as
# [model type, attribute, model id]
RECORD_JS = """(titles) => {
  const doc = Bokeh.documents[0];
  const figs = [...doc.all_models].filter(m => m.type === 'Figure' && m.title && titles.includes(m.title.text));
  const ids = new Set();
  for (const fig of figs) for (const m of fig.references()) ids.add(m.id);
  window.plotChanges = [];
  doc.on_change((ev) => {
    if (ev.model && ids.has(ev.model.id)) window.plotChanges.push([ev.model.type, ev.attr ?? ev.kind ?? '', ev.model.id]);
  });
}"""

# the words of every explorer figure: its axis labels and its hover tools' tooltips
WORDS_JS = """(titles) => [...Bokeh.documents[0].all_models]
  .filter(m => m.type === 'Figure' && m.title && titles.includes(m.title.text))
  .map(f => [f.title.text, f.below[0].axis_label, f.left[0].axis_label,
             f.toolbar.tools.filter(t => t.type === 'HoverTool').map(t => t.tooltips)])"""

# what a mode switch may change in a plot: the numbers and the words the server writes, and the
# layout the page itself computes for the new axis labels
WRITTEN = {("ColumnDataSource", "data"), ("Range1d", "start"), ("Range1d", "end"), ("Range1d", "reset_start"),
           ("Range1d", "reset_end"), ("Span", "location"),
           ("LinearAxis", "axis_label"), ("LogAxis", "axis_label"), ("HoverTool", "tooltips")}
LAYOUT = {"inner_width", "inner_height", "outer_width", "outer_height"}


def test_a_mode_switch_changes_only_the_numbers_and_words_of_the_plots(page, explorer_url):
    open_explorer(page, explorer_url)
    titles = list(EXPLORER_TITLES)
    page.evaluate(RECORD_JS, titles)
    page.get_by_role("button", name="torsion").click()
    expect(page.locator(".operating-point")).to_contain_text(" rad,")
    # the words of every plot in the new units (the loop's axes name the angle and the moment)
    page.wait_for_function(f"""(titles) => ({WORDS_JS})(titles).every(([t, x, y, tips]) =>
        (t.includes('amplitude') ? x === 'Amplitude (rad)' : true)
        && (t.startsWith('|K|') ? y === '|K| (N·m/rad)' : true)
        && (t.startsWith('Hysteresis') ? x === 'Angle (rad)' && y === 'Moment (N·m)' : true)
        && tips.length === 1 && tips[0].every(([label]) => !label.includes('mm') && !label.includes('(N)')))""",
                           arg=titles)
    settle(page)
    changes = page.evaluate("window.plotChanges")
    other = sorted({(kind, attr) for kind, attr, _id in changes
                    if (kind, attr) not in WRITTEN and not (kind == "Figure" and attr in LAYOUT)})
    assert other == [], f"a mode switch changed more of the plots than their numbers and words: {other}"
    sources = [model for kind, attr, model in changes if kind == "ColumnDataSource"]
    assert sources and len(sources) == len(set(sources))  # each data source sent once
