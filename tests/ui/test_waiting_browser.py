"""Waiting in the browser (issue #27, items 12 and 13): a wait shows its progress until the result
replaces it, the diagnosis names its candidates in words, and the two sensitivity charts list the
parameters in one order. Each test waits for the state it then checks, never for a time."""

import re
import threading

import numpy as np
import pytest
from playwright.sync_api import expect

from tests.ui.bokeh_page import FIGURE_JS, drop_into, open_explorer

pytestmark = pytest.mark.usefixtures("console_errors", "no_server_tracebacks")

# in the page, from now on: every painted frame's text (Panel's panes live in shadow roots, which
# neither innerText nor a MutationObserver sees into): whether progress was shown, whether a
# finished progress ("done…") was ever shown without the report, whether the report ever came
# with the progress still shown, and the report's first frame's text
WATCH_JS = """([progress, report]) => {
  const deepText = (node) => {
    let out = node.innerText ?? [...node.children].map(c => c.innerText ?? '').join(' ');
    for (const el of node.querySelectorAll('*')) if (el.shadowRoot) out += ' ' + deepText(el.shadowRoot);
    return out;
  };
  const seen = window.bushingWait = {progress: [], doneAlone: false, progressWithReport: false, report: null};
  const look = () => {
    const text = deepText(document.body);
    const shown = text.match(new RegExp(progress));
    const hasReport = new RegExp(report).test(text);
    if (shown && !seen.progress.includes(shown[0])) seen.progress.push(shown[0]);
    if (/\\bdone…/.test(text) && !hasReport) seen.doneAlone = true;
    if (hasReport) {
      if (shown) seen.progressWithReport = true;
      seen.report = text;
      return;
    }
    requestAnimationFrame(look);
  };
  requestAnimationFrame(look);
}"""


def watch(page, progress: str, report: str):
    page.evaluate(WATCH_JS, [progress, report])


def wait_report(page, timeout=120_000) -> dict:
    page.wait_for_function("() => window.bushingWait.report !== null", timeout=timeout)
    return page.evaluate("() => window.bushingWait")


def upload_150_points(page, tmp_path):
    from core import PAPER_B
    from core.synthetic import synthetic_stiffness

    # a hidden fixture mass of 0.5 kg: 30 frequencies × 5 amplitudes, 0.5 % noise
    hidden = PAPER_B.replace(effects={"inertia": {"mass": 0.5}})
    measured = tmp_path / "inertia.csv"
    synthetic_stiffness(hidden, np.linspace(1, 100, 30), [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3],
                        noise=0.005, seed=3).to_csv(measured)
    page.get_by_text("Find the missing effect", exact=True).click()
    page.get_by_role("button", name="Diagnose").wait_for()
    drop_into(page, measured)
    page.get_by_text("150 points").first.wait_for()


@pytest.fixture
def gated_diagnosis(monkeypatch):
    """The diagnosis held at its first step's second candidate until the test has seen the page
    say so: ``(reached, release)`` events (a fast machine may otherwise pass every candidate
    between two of the page's progress polls)."""
    from app.diagnosis_state import DiagnosisState
    from app.work import Task

    reached, release = threading.Event(), threading.Event()
    task = DiagnosisState.task

    def gated(self):
        work = task(self)

        def run(*args, progress=None, **kwargs):
            def say(fraction, message):
                if progress is not None:
                    progress(fraction, message)
                if message.startswith("step 1, candidate 2 of "):
                    reached.set()
                    release.wait(60)

            return work.function(*args, progress=say, **kwargs)

        return Task(run, work.args, work.kwargs)

    monkeypatch.setattr(DiagnosisState, "task", gated)
    return reached, release


def test_the_diagnosis_shows_its_progress_until_its_report_replaces_it(page, explorer_url, tmp_path,
                                                                        gated_diagnosis):
    """150 points diagnosed: the page shows which candidate of how many is being fitted, never a
    finished progress ("done…") without the report, and the report arrives with the progress
    gone (once: "done…" for 2.2 s before the report)."""
    reached, release = gated_diagnosis
    open_explorer(page, explorer_url)
    upload_150_points(page, tmp_path)
    watch(page, r"(fitting|trying|candidate \d+ of \d+|profiling|checking|describing)[^…]*…", "What is left is noise")
    page.get_by_role("button", name="Diagnose").click()
    try:
        expect(page.get_by_text(re.compile(r"step 1, candidate 2 of \d+: "))).to_be_visible(timeout=60_000)
        assert reached.is_set()  # shown while the diagnosis was held there
    finally:
        release.set()
    seen = wait_report(page)
    assert not seen["doneAlone"], seen["progress"]
    assert not seen["progressWithReport"]
    assert len(seen["progress"]) >= 2, seen["progress"]  # the steps reached the page as they came
    assert any(re.search(r"candidate \d+ of \d+: ", p) for p in seen["progress"]), seen["progress"]
    expect(page.locator(".diagnosis-progress")).to_have_count(0)


@pytest.fixture
def processes():
    """Long work in a worker process, as ``bushing serve`` runs it (app.work.use_processes)."""
    from app import work

    work.use_processes(1)
    yield work
    work.stop_processes()


def test_a_served_explorer_diagnoses_in_a_worker_process(page, explorer_url, tmp_path, processes):
    """With worker processes on (``bushing serve``), the diagnosis runs in one: its progress
    reaches the page through the workers' queue, and the report replaces it (never "done…"
    alone, never the report with the progress still shown)."""
    before = processes.relayed
    open_explorer(page, explorer_url)
    upload_150_points(page, tmp_path)
    watch(page, r"(fitting|trying|candidate \d+ of \d+|profiling|checking|describing)[^…]*…", "What is left is noise")
    page.get_by_role("button", name="Diagnose").click()
    seen = wait_report(page)
    assert not seen["doneAlone"] and not seen["progressWithReport"], seen["progress"]
    assert seen["progress"], "no progress shown"
    assert processes.relayed > before  # the steps came from the worker process
    expect(page.locator(".diagnosis-progress")).to_have_count(0)


def test_the_diagnosis_names_its_candidates(page, explorer_url, tmp_path):
    """The other candidates of a step are listed by their names, as the library titles them
    (once by their ids: "viscous 3.1, stiffening 0.4")."""
    from core.effects import EFFECTS

    open_explorer(page, explorer_url)
    upload_150_points(page, tmp_path)
    page.get_by_role("button", name="Diagnose").click()
    line = page.get_by_text("Other candidates' BIC drops:").first
    line.wait_for(timeout=120_000)
    listed = line.inner_text().split(":", 1)[1].strip().rstrip(".")
    # each with its drop, signed with a true minus sign where the candidate's BIC rose
    names = [re.sub(r"\s+[+−]?\d+(\.\d+)?$", "", item.strip()) for item in listed.split(", ")]
    titles = {e.title for e in EFFECTS.values()}
    assert names and all(n in titles for n in names), names


# the x factors of each bar chart of the What-ifs tab
FACTORS_JS = f"""(title) => {{ const m = ({FIGURE_JS})(title); return m === null ? null : Array.from(m.x_range.factors); }}"""
CHARTS = ("|K|: % per +1 % of the parameter", "Loss factor: change per unit ln p")


def test_the_sensitivity_charts_list_the_parameters_alike(page, explorer_url):
    """Both sensitivity charts list the parameters in the order of the one parameter table, and
    the sentence names them in words (once: each chart ranked by its own sizes; "|K| follows a
    most")."""
    from core.parameters import BY_NAME, NAMES

    open_explorer(page, explorer_url)
    page.get_by_text("What-ifs", exact=True).click()
    for title in CHARTS:
        page.wait_for_function(f"(title) => ({FACTORS_JS})(title)?.length > 0", arg=title, timeout=60_000)
    k, eta = (page.evaluate(FACTORS_JS, title) for title in CHARTS)
    assert k == eta == [BY_NAME[n].symbol for n in NAMES]
    expect(page.get_by_text(re.compile(r"\|K\| depends most on the [a-z]"))).to_have_count(1)


@pytest.fixture
def gated_search(monkeypatch):
    """*Find designs* held at its sixth start until the test has seen the page say so:
    ``(reached, release)`` events."""
    from app.targets_form import TargetsForm

    reached, release = threading.Event(), threading.Event()
    compute = TargetsForm.compute

    def gated(self, progress=None):
        def say(fraction, message):
            if progress is not None:
                progress(fraction, message)
            if message == "start 6 of 12":
                reached.set()
                release.wait(60)

        return compute(self, say)

    monkeypatch.setattr(TargetsForm, "compute", gated)
    return reached, release


def test_find_designs_shows_where_the_search_is_until_its_result(page, explorer_url, gated_search):
    """While *Find designs* runs, the page says which start of how many it has reached, and the
    result replaces that line (once: a spinning button only, whatever the wait)."""
    reached, release = gated_search
    open_explorer(page, explorer_url)
    page.get_by_text("What-ifs", exact=True).click()
    target = page.get_by_label("|K| target")
    target.fill("4.5")
    target.press("Enter")
    watch(page, r"Searching: start \d+ of \d+…", r"every target\.|cannot be met")
    page.get_by_role("button", name="Find designs").click()
    try:
        expect(page.get_by_text("Searching: start 6 of 12…")).to_be_visible(timeout=60_000)
        assert reached.is_set()  # shown while the search was held there
    finally:
        release.set()
    seen = wait_report(page)
    assert "Searching: start 6 of 12…" in seen["progress"]
    assert not seen["progressWithReport"]
    expect(page.get_by_text(re.compile("Searching: "))).to_have_count(0)


# (tab, button, the start of its description): buttons, and a button of each group of them
DESCRIBED = (
    ("Explorer", "torsion", "Axial: the sleeves moved apart"),
    ("Measured data and fit", "two-step", "Global: all five parameters"),
    ("Find the missing effect", "Load a mystery data set (demo)", "Synthetic data with an effect"),
    ("Find the missing effect", "fractional", "The branches the starting model has"),
    ("Find the missing effect", "Diagnose", "Fit the baseline and every candidate"),
)
SIZES = ((1280, 720), (1600, 1000))


def overlap(a: dict, b: dict) -> bool:
    return (a["x"] < b["x"] + b["width"] and b["x"] < a["x"] + a["width"]
            and a["y"] < b["y"] + b["height"] and b["y"] < a["y"] + a["height"])


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
@pytest.mark.parametrize(("tab", "button", "description"), DESCRIBED)
def test_a_buttons_description_covers_no_other_button(page, explorer_url, tab, button, description, size):
    """The pointer resting on a button shows its description wholly in the window, where it
    hides no other button nor any field of the button's row (once: to its right, over the next
    button of its row; the mode's ran past the window's edge over the explorer's buttons, the
    branches' covered *Diagnose*, the fit method's the *Fit on* field)."""
    page.set_viewport_size({"width": size[0], "height": size[1]})
    open_explorer(page, explorer_url)
    page.get_by_text(tab, exact=True).click()
    hovered = page.get_by_role("button", name=button, exact=True)
    hovered.wait_for()
    hovered.scroll_into_view_if_needed()
    hovered.hover(force=True)  # a disabled button shows its description too
    shown = page.get_by_text(description).first
    expect(shown).to_be_visible()
    box = shown.bounding_box()
    assert box["x"] >= 0 and box["y"] >= 0 and box["x"] + box["width"] <= size[0] and box["y"] + box["height"] <= size[1], box
    own = hovered.bounding_box()
    covered = [(b.inner_text() or b.evaluate("e => e.outerHTML.slice(0, 160)")) for b in page.get_by_role("button").all()
               if b.is_visible() and (other := b.bounding_box()) and other != own and overlap(box, other)]
    row = {**own, "x": 0, "width": size[0]}  # the fields level with the button
    covered += [f.evaluate("e => e.outerHTML.slice(0, 160)") for f in page.locator("input, select, textarea").all()
                if f.is_visible() and (other := f.bounding_box()) and overlap(row, other) and overlap(box, other)]
    assert covered == [], covered


FIT = "Fit the five material parameters"
HELD_AT = "start 3 of 8"  # the global fit's third start (fit_global: 8 starts)


class Gate:
    """A fit held until the test lets it go: at the progress message ``at``, or as it starts
    (``at`` None); ``ended`` set when the tab's handler of the Fit button has returned."""

    def __init__(self):
        self.at: str | None = HELD_AT
        self.reached, self.release, self.ended = threading.Event(), threading.Event(), threading.Event()

    def hold(self):
        self.reached.set()
        self.release.wait(60)


@pytest.fixture
def gated_fit(monkeypatch):
    """The measured-data fit held (:class:`Gate`), its progress passed on."""
    from app.fit_state import FitState
    from app.tabs.measured_data_and_fit import MeasuredView

    gate = Gate()
    compute, handler = FitState.compute_fit, MeasuredView._fit

    def gated(self, progress=None):
        def say(fraction, message):
            if progress is not None:
                progress(fraction, message)
            if message == gate.at:
                gate.hold()

        if gate.at is None:
            gate.hold()
        return compute(self, say)

    async def watched(self, event):
        try:
            await handler(self, event)
        finally:
            gate.ended.set()

    monkeypatch.setattr(FitState, "compute_fit", gated)
    monkeypatch.setattr(MeasuredView, "_fit", watched)
    return gate


def load_example_data(page):
    page.get_by_text("Measured data and fit", exact=True).click()
    page.get_by_role("button", name="Load the synthetic Paper B example").click()
    page.get_by_text(re.compile(r"Stiffness: \d+ points")).first.wait_for()
    expect(page.get_by_role("button", name=FIT)).to_be_enabled()


def test_the_fit_shows_where_it_is_until_its_result(page, explorer_url, gated_fit):
    """While the fit of the measured data runs, the page says which start of how many it has
    reached, with the Fit button disabled; the fitted parameters replace that line in one push
    (once: a spinning button only, whatever the wait)."""
    reached, release = gated_fit.reached, gated_fit.release
    open_explorer(page, explorer_url)
    load_example_data(page)
    watch(page, r"Fitting: [^…]*…", r"Correlation between parameters")
    page.get_by_role("button", name=FIT).click()
    try:
        expect(page.get_by_text(f"Fitting: {HELD_AT}…")).to_be_visible(timeout=60_000)
        assert reached.is_set()  # shown while the fit was held there
        expect(page.get_by_role("button", name=FIT)).to_be_disabled()
    finally:
        release.set()
    seen = wait_report(page)
    assert f"Fitting: {HELD_AT}…" in seen["progress"]
    assert not seen["progressWithReport"]
    expect(page.get_by_text(re.compile("Fitting: "))).to_have_count(0)
    expect(page.get_by_role("button", name=FIT)).to_be_enabled()


def test_a_page_closed_during_the_fit_leaves_no_traceback(page, context, explorer_url, gated_fit, server_log):
    """A page closed while its fit runs: the fit ends and nothing is written to the gone page
    (no WebSocketClosedError, no traceback in the server's log)."""
    gated_fit.at = None  # held as it starts
    reached, release, ended = gated_fit.reached, gated_fit.release, gated_fit.ended
    other = context.new_page()
    open_explorer(other, explorer_url)
    load_example_data(other)
    other.get_by_role("button", name=FIT).click()
    try:
        assert reached.wait(60)
        other.close()
    finally:
        release.set()
    assert ended.wait(120)
    assert server_log.tracebacks() == []
    assert not [r for r in server_log.records if "WebSocketClosed" in r.getMessage()]


# in the page: the placeholders of the tabs whose content the page does not hold (a Spacer each, in
# the tabs' shadow root; the inactive tabs' are laid out too, hidden): whether each is shown, the
# text its ::before writes, its height and the animation of its bar (::after)
PLACEHOLDERS_JS = """() => {
  const out = [];
  const visit = (root) => {
    for (const el of root.querySelectorAll('*')) {
      if (el.classList.contains('bk-Spacer')) {
        const box = el.getBoundingClientRect();
        out.push({shown: box.width > 0 && box.height > 0
                         && el.checkVisibility({visibilityProperty: true, opacityProperty: true}),
                  text: getComputedStyle(el, '::before').content, height: box.height,
                  moving: getComputedStyle(el, '::after').animationName});
      }
      if (el.shadowRoot) visit(el.shadowRoot);
    }
  };
  visit(document);
  return out;
}"""
SHOWN_PLACEHOLDERS_JS = f"() => ({PLACEHOLDERS_JS})().filter(p => p.shown)"


@pytest.fixture
def gated_tab(monkeypatch):
    """The Slices tab's view built only once the test releases it: ``(reached, release)``."""
    from app.main import App

    reached, release = threading.Event(), threading.Event()

    def held(build):
        def gated(app):
            reached.set()
            release.wait(60)
            return build(app)
        return gated

    monkeypatch.setattr(App, "LAZY_TABS", tuple((title, name, held(build) if name == "slices" else build)
                                                for title, name, build in App.LAZY_TABS))
    return reached, release


def test_a_tab_being_built_says_so_until_it_is_shown(page, explorer_url, gated_tab):
    """A tab opened for the first time is built on the server (the Slices tab: 1.3–1.9 s before
    its figures were drawn, a blank page meanwhile): until its content replaces it, the page says
    the tab is opening, with a moving bar (the only one that moves)."""
    reached, release = gated_tab
    open_explorer(page, explorer_url)
    page.get_by_text("Slices", exact=True).click()
    try:
        assert reached.wait(60)  # the server builds the tab now, and is held there
        page.wait_for_function(f"() => ({SHOWN_PLACEHOLDERS_JS})().length === 1")
        placeholders = page.evaluate(PLACEHOLDERS_JS)
        shown = [p for p in placeholders if p["shown"]]
        assert shown[0]["text"] == '"Opening the tab…"' and shown[0]["height"] >= 40
        assert shown[0]["moving"] == "bushing-opening"
        # the hidden tabs' bars stand still (moving, they restyled the page at every frame)
        assert {p["moving"] for p in placeholders if not p["shown"]} == {"none"}
    finally:
        release.set()
    expect(page.get_by_text("Paper A splits the rubber")).to_be_visible()
    assert page.evaluate(SHOWN_PLACEHOLDERS_JS) == []
