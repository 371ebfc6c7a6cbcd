"""What the page's Bokeh document holds, and waits on its conditions (never on the clock).

Every wait is ``page.wait_for_function`` on a condition read in the page: the document built and
idle, a figure's data, a span or a legend changed, a text shown. A test waits for the state it
then checks, never for a fixed time."""

import re

# the figure of the document with this title (or null)
FIGURE_JS = """(title) => [...Bokeh.documents[0].all_models].find(
    m => m.type === 'Figure' && m.title && m.title.text === title) ?? null"""

# what a figure shows: the sum and count of its finite data (a signature that any change of data
# changes), its spans' locations and its legends' labels
SUMMARY_JS = """(m) => {
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
  return {signature: total, points, spans, legends};
}"""

PLOTS_JS = f"""() => {{
  const summary = {SUMMARY_JS};
  const out = {{}};
  for (const m of Bokeh.documents[0].all_models) {{
    if (m.type === 'Figure' && m.title) out[m.title.text] = summary(m);
  }}
  return out;
}}"""

# the data of the renderers of a legend entry: x and y of each glyph, and whether every column
# arrived as float64 (Bokeh sends NumPy float64 arrays as binary float64 buffers)
CURVE_JS = f"""([title, label]) => {{
  const fig = ({FIGURE_JS})(title);
  const legend = [...fig.center, ...fig.right, ...fig.left, ...fig.above, ...fig.below].find(m => m.type === 'Legend');
  const item = legend.items.find(it => (it.label.value || it.label.field) === label);
  return item.renderers.map(r => {{
    const data = r.data_source.data, x = data[r.glyph.x.field], y = data[r.glyph.y.field];
    return {{x: Array.from(x), y: Array.from(y),
             float64: x instanceof Float64Array && y instanceof Float64Array}};
  }});
}}"""

EXPLORER_TITLES = ("Hysteresis loop at the operating point", "|K| against frequency", "|K| against amplitude",
                   "Loss factor against frequency", "Loss factor against amplitude")

# the document is built, every root's view has rendered (Bokeh's own "idle": the moment it tells
# the server DocumentReady), and these figures hold data
READY_JS = f"""(titles) => {{
  if (!(window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle)) return false;
  const summary = {SUMMARY_JS};
  return titles.every(t => {{ const m = ({FIGURE_JS})(t); return m !== null && summary(m).points > 0; }});
}}"""

# start waiting for every view's pending work: Bokeh chains each view's repaints and signal
# handlers on its `ready` promise; the page counts the waits that have ended
SETTLE_JS = """() => {
  const token = window.bushingSettleAsked = (window.bushingSettleAsked ?? 0) + 1;
  Promise.all([...Bokeh.index.all_views()].map(v => v.ready)).then(() => {
    window.bushingSettled = Math.max(window.bushingSettled ?? 0, token);
  });
  return token;
}"""

LOAD_TIMEOUT_MS = 60_000


def plots(page) -> dict:
    """Every titled figure of the page: ``{title: {signature, points, spans, legends}}``."""
    return page.evaluate(PLOTS_JS)


def drop_into(page, path, index: int = 0):
    """Give ``path`` to the ``index``-th drop area of the tab shown (in the main area: the
    sidebar's design-file area is shown as well). A tab's drop areas are made a moment after its
    buttons, and a hidden tab's areas stay in the page: the page's last file input was, under
    load, the sidebar's (the CSV refused there as "invalid type") or a hidden tab's."""
    area = page.locator("#main .filepond--root").filter(visible=True).nth(index)
    area.wait_for()
    area.locator("input[type=file]").set_input_files(str(path))


def settle(page, timeout=30_000):
    """Wait until every Bokeh view has painted what it had received when this was called."""
    token = page.evaluate(SETTLE_JS)
    page.wait_for_function("(token) => window.bushingSettled >= token", arg=token, timeout=timeout)


def wait_ready(page, titles=EXPLORER_TITLES, timeout=LOAD_TIMEOUT_MS):
    """Wait until the document is idle with ``titles`` drawn, and every view has painted: a tap
    then lands on a page at rest (a tap whose press and release are processed more than 300 ms
    apart, behind a busy main thread, is a press to Bokeh, not a tap)."""
    page.wait_for_function(READY_JS, arg=list(titles), timeout=timeout)
    settle(page)


def open_explorer(page, url, titles=EXPLORER_TITLES):
    page.goto(url)
    wait_ready(page, titles)


def wait_plot(page, title: str, condition: str, arg=None, timeout=30_000):
    """Wait until the figure ``title`` exists and ``condition`` holds: a JavaScript expression
    of ``p`` (the figure's summary, as :func:`plots` gives it), ``m`` (the figure model) and
    ``arg``."""
    page.wait_for_function(
        f"""([title, arg]) => {{
          const m = ({FIGURE_JS})(title);
          if (m === null) return false;
          const p = ({SUMMARY_JS})(m);
          return {condition};
        }}""",
        arg=[title, arg], timeout=timeout)


def wait_plot_changed(page, title: str, before: dict, timeout=30_000):
    """Wait until the data of figure ``title`` differ from ``before`` (its earlier summary)."""
    wait_plot(page, title, "p.signature !== arg", before["signature"], timeout)


def wait_figure(page, prefix: str, timeout=30_000):
    """Wait until a figure whose title starts with ``prefix`` holds data."""
    page.wait_for_function(
        f"""(prefix) => [...Bokeh.documents[0].all_models].some(
              m => m.type === 'Figure' && m.title && m.title.text.startsWith(prefix)
                   && ({SUMMARY_JS})(m).points > 0)""",
        arg=prefix, timeout=timeout)


def curve(page, title: str, label: str) -> dict:
    """The one glyph of legend entry ``label`` in figure ``title``: ``{x, y, float64}``."""
    (glyph,) = page.evaluate(CURVE_JS, [title, label])
    return glyph


def wait_curve_changed(page, title: str, label: str, before_y: list, timeout=30_000):
    """Wait until the y data of legend entry ``label`` of ``title`` are no longer ``before_y``."""
    page.wait_for_function(
        f"""([arg, before]) => {{
          const now = ({CURVE_JS})(arg)[0].y;
          return now.length !== before.length || now.some((v, i) => v !== before[i]);
        }}""",
        arg=[[title, label], before_y], timeout=timeout)


def wait_tappable(page, title: str, timeout=30_000):
    """Wait until figure ``title`` holds data and listens to taps (the server has subscribed to
    its tap events), and every view has painted: the page is at rest for a tap."""
    wait_plot(page, title, "p.points > 0 && m.subscribed_events.has('tap')", timeout=timeout)
    settle(page)


def tap(canvas, x_fraction: float):
    """One click on ``canvas`` at ``x_fraction`` of its width, half its height."""
    box = canvas.bounding_box()
    canvas.click(position={"x": box["width"] * x_fraction, "y": box["height"] * 0.5})


def mystery_demo(page, url):
    """Open the explorer, load the diagnosis tab's mystery data set, diagnose it and reveal its
    truth (waiting for each step's answer)."""
    open_explorer(page, url)
    page.get_by_text("Find the missing effect", exact=True).click()
    page.get_by_role("button", name="Load a mystery data set (demo)").click()
    page.get_by_text("mystery data set").first.wait_for()
    page.get_by_role("button", name="Diagnose").click()
    page.get_by_role("button", name="Reveal the truth").wait_for(timeout=60_000)
    page.get_by_role("button", name="Reveal the truth").click()
    page.get_by_text(re.compile("Hidden in the data|Nothing was hidden")).wait_for()
