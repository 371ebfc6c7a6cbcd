"""Issue #27 items 1, 8, 14 and 16 in the browser: a measured file in the wrong units is refused at
upload with one message every tab shares; the data are drawn one colour per amplitude over the
model at those amplitudes; the residuals follow the fit; without data the tab says what to load
and Fit waits for data; a file is sent as soon as its drop area has it. The bad files are the example files with one column scaled."""

import json
import re
from pathlib import Path

import numpy as np
from playwright.sync_api import expect

from tests.ui.bokeh_page import (
    drop_into,
    open_explorer,
    plots,
    settle,
    wait_plot,
    wait_plot_changed,
)

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
TAB = "Measured data and fit"
FIT = "Fit the five material parameters"
DATA_TITLE = "|K|: data (dots), model (lines)"
RESIDUAL_TITLE = "|K| residual against frequency"

# every glyph of a figure: its kind, colour (line or fill) and data
GLYPHS_JS = """(title) => {
  const fig = [...Bokeh.documents[0].all_models].find(m => m.type === 'Figure' && m.title && m.title.text === title);
  if (!fig) return null;
  return fig.renderers.filter(r => r.glyph && r.data_source).map(r => {
    const g = r.glyph, d = r.data_source.data;
    const color = (g.type === 'Line' ? g.line_color : g.fill_color);
    return {type: g.type, color: (color && color.value !== undefined) ? color.value : color,
            x: Array.from(d[g.x.field] ?? []), y: Array.from(d[g.y.field] ?? [])};
  });
}"""


def scaled(tmp_path, source: str, name: str, column: str, factor: float) -> Path:
    """The example file ``source`` with ``column`` multiplied by ``factor``, as ``name``."""
    lines = (EXAMPLES / source).read_text().splitlines()
    header = lines[0].split(",")
    i = header.index(column)
    rows = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        cells[i] = repr(float(cells[i]) * factor)
        rows.append(",".join(cells))
    out = tmp_path / name
    out.write_text("\n".join(rows) + "\n")
    return out


def open_tab(page, url):
    open_explorer(page, url)
    page.get_by_text(TAB, exact=True).click()
    page.get_by_role("button", name=FIT).wait_for()


def test_a_stiffness_file_in_mm_is_refused_alike_in_both_tabs(page, explorer_url, tmp_path):
    """Amplitudes in mm (0.013–0.35 "m"): refused at upload, the message names the file, the
    column and the cause; the drop area does not say "Upload complete"; the Explorer draws no
    measured points and says the same; the diagnosis tab refuses the same file with the same
    message."""
    mm = scaled(tmp_path, "paper_b_stiffness.csv", "in_mm.csv", "amplitude", 1e3)
    open_tab(page, explorer_url)
    page.locator("#main input[type=file]").first.set_input_files(str(mm))
    error = page.locator(".data-error:visible")
    expect(error).to_contain_text("in_mm.csv")
    expect(error).to_contain_text("column amplitude")
    expect(error).to_contain_text("look like mm")
    said_all = error.inner_text()
    said = said_all.removeprefix("⚠").strip()
    # FilePond's "Upload complete" is not shown next to the refusal (the drop area says "Sent")
    expect(page.locator(".filepond--file-status-main").first).to_have_css("font-size", "0px")
    page.get_by_text("Explorer", exact=True).click()
    expect(page.locator(".explorer-error")).to_have_text(said_all)
    settle(page)
    assert "measured" not in plots(page)["|K| against frequency"]["legends"]
    page.get_by_text("Find the missing effect", exact=True).click()
    page.get_by_role("button", name="Diagnose").wait_for()
    drop_into(page, mm)
    expect(page.locator(".diagnosis-error")).to_contain_text(said)
    assert page.get_by_role("button", name="Diagnose").is_disabled()


def test_stiffness_in_kn_per_mm_and_a_torsion_file_in_axial_mode_are_refused(page, explorer_url, tmp_path):
    """|K| in kN/mm (the N/m values / 10⁶) and Table 1's torsion file (rad, N·m/rad) with the
    Paper B axial design: each refused, naming its column and the likely cause."""
    knmm = scaled(tmp_path, "paper_b_stiffness.csv", "in_kn_per_mm.csv", "magnitude", 1e-6)
    open_tab(page, explorer_url)
    inputs = page.locator("#main input[type=file]")
    inputs.first.set_input_files(str(knmm))
    error = page.locator(".data-error:visible")
    expect(error).to_contain_text("in_kn_per_mm.csv: column magnitude")
    expect(error).to_contain_text("look like kN/mm")
    inputs.first.set_input_files(str(EXAMPLES / "table1_torsion_stiffness.csv"))
    expect(error).to_contain_text("table1_torsion_stiffness.csv: column amplitude")
    expect(error).to_contain_text("torsion file")
    expect(page.get_by_text(re.compile(r"Stiffness: \d+ points"))).to_have_count(0)


def test_measured_points_one_colour_per_amplitude_over_the_model_there(page, explorer_url):
    """The synthetic example (five amplitudes): five colours of dots, each colour's line the
    model of the design shown at that amplitude (computed here through core)."""
    from core import PAPER_B
    from core.bushing import stiffness_points
    from core.synthetic import paper_b_example

    open_tab(page, explorer_url)
    page.get_by_role("button", name="Load the synthetic Paper B example").click()
    wait_plot(page, DATA_TITLE, "p.points > 0")
    glyphs = page.evaluate(GLYPHS_JS, DATA_TITLE)
    dots = [g for g in glyphs if g["type"] == "Scatter" and g["x"]]  # (the empty first frame's renderer stays)
    lines = [g for g in glyphs if g["type"] == "Line"]
    data, _ = paper_b_example(PAPER_B)
    amplitudes = np.unique(data.amplitude)
    assert len(dots) == len(lines) == amplitudes.size == 5
    assert len({d["color"] for d in dots}) == 5
    for dot, line, amp in zip(dots, lines, amplitudes):
        assert dot["color"] == line["color"]
        f = np.asarray(line["x"])
        model = np.abs(stiffness_points(PAPER_B, f, np.full(f.size, amp))) / 1e6  # kN/mm
        assert np.allclose(line["y"], model, rtol=1e-9)


def test_residuals_follow_the_fit(page, explorer_url, tmp_path):
    """After Fit the residuals are the fitted design's (its file, downloaded, gives them
    through core), not the starting design's."""
    open_tab(page, explorer_url)
    page.locator("#main input[type=file]").first.set_input_files(str(EXAMPLES / "paper_b_stiffness.csv"))
    wait_plot(page, RESIDUAL_TITLE, "p.points > 0")
    before = plots(page)[RESIDUAL_TITLE]
    page.get_by_role("button", name=FIT).click()
    page.get_by_text("Correlation between parameters").wait_for(timeout=120_000)
    wait_plot_changed(page, RESIDUAL_TITLE, before)
    with page.expect_download() as download:
        page.get_by_text("Fitted design file (JSON)").click()
    path = tmp_path / "fitted.json"
    download.value.save_as(path)
    json.loads(path.read_text())
    from core.bushing import stiffness_points
    from core.io.design_file import read_design
    from core.io.measured import parse_stiffness
    from core.response import magnitude_residual_pct

    fitted = read_design(path)
    data = parse_stiffness((EXAMPLES / "paper_b_stiffness.csv").read_text())
    expected = magnitude_residual_pct(stiffness_points(fitted, data.frequency_hz, data.amplitude), data.stiffness)
    shown = next(g for g in page.evaluate(GLYPHS_JS, RESIDUAL_TITLE) if g["type"] == "Scatter")
    assert len(shown["y"]) == len(expected)
    assert np.allclose(np.sort(shown["y"]), np.sort(expected), rtol=1e-6, atol=1e-9)


def test_without_data_a_how_to_and_fit_waits_for_data(page, explorer_url):
    """The first view: what to load (format, the example files), no empty plots, Fit disabled;
    data enable it, Clear disables it again. A loop that moves the operating point says so."""
    open_tab(page, explorer_url)
    expect(page.locator(".measured-how-to")).to_contain_text("paper_b_stiffness.csv")
    expect(page.locator(".measured-how-to")).to_contain_text("frequency_hz,amplitude,magnitude,loss_factor")
    fit = page.get_by_role("button", name=FIT)
    expect(fit).to_be_disabled()
    page.locator("#main input[type=file]").nth(1).set_input_files(str(EXAMPLES / "paper_b_loop.csv"))
    expect(page.locator(".data-note")).to_contain_text("operating point moved to the loop's 0.1 Hz")
    expect(fit).to_be_enabled()
    expect(page.locator(".measured-how-to")).to_be_hidden()
    page.get_by_role("button", name="Clear the data").click()
    expect(fit).to_be_disabled()
    expect(page.locator(".measured-how-to")).to_be_visible()


# the major ticks of every figure's log axis (x or y) whose label names the amplitude, and its range
LOG_AXES_JS = """() => {
  const out = [];
  for (const m of Bokeh.documents[0].all_models) {
    if (m.type !== 'Figure' || !m.title) continue;
    for (const [scale, axes, range, at] of [[m.x_scale, m.below, m.x_range, 0], [m.y_scale, m.left, m.y_range, 1]]) {
      const axis = axes[0];
      if (scale.type !== 'LogScale' || !axis || !String(axis.axis_label).startsWith('Amplitude')) continue;
      const view = Bokeh.index.find_one(axis);
      if (!view) continue;
      out.push({title: m.title.text, start: range.start, end: range.end, ticks: Array.from(view.tick_coords.major[at])});
    }
  }
  return out;
}"""


def assert_labelled_in_both_halves(axes):
    """A labelled tick in each half (log scale) of every axis."""
    for axis in axes:
        lo, hi = sorted((axis["start"], axis["end"]))
        middle = np.sqrt(lo * hi)
        ticks = [t for t in axis["ticks"] if lo <= t <= hi]
        assert any(t < middle for t in ticks) and any(t > middle for t in ticks), axis


def test_log_amplitude_axes_are_labelled_in_every_part_of_their_range(page, explorer_url):
    """The measured tab's residuals against amplitude (0.013–0.35 mm, under two decades): a
    labelled tick in each half (log scale) of the axis, not only at 0.1–0.4."""
    open_tab(page, explorer_url)
    page.locator("#main input[type=file]").first.set_input_files(str(EXAMPLES / "paper_b_stiffness.csv"))
    wait_plot(page, RESIDUAL_TITLE, "p.points > 0")
    settle(page)
    axes = page.evaluate(LOG_AXES_JS)
    assert len(axes) >= 2, axes
    assert_labelled_in_both_halves(axes)


def test_a_warned_file_is_a_warning_in_every_tab_and_goes_with_its_data(page, explorer_url, tmp_path):
    """|K| 30 times the model's (loaded, with a warning naming the file and the column): an amber
    note, no error, in the measured tab and the Explorer; the diagnosis tab, using those data,
    repeats the warning as a warning (not as a refusal) and can diagnose them."""
    far = scaled(tmp_path, "paper_b_stiffness.csv", "thirty_times.csv", "magnitude", 30.0)
    open_tab(page, explorer_url)
    page.locator("#main input[type=file]").first.set_input_files(str(far))
    note = page.locator(".data-note:visible")
    expect(note).to_contain_text("thirty_times.csv: column magnitude")
    said = note.inner_text()
    expect(page.locator(".data-error:visible")).to_have_count(0)
    page.get_by_text("Explorer", exact=True).click()
    expect(page.locator(".explorer-note")).to_have_text(said)
    page.get_by_text("Find the missing effect", exact=True).click()
    page.get_by_role("button", name="Use the data of “Measured data and fit”").click()
    expect(page.locator(".diagnosis-note")).to_contain_text(said.removeprefix("Note:").strip())
    expect(page.locator(".diagnosis-error")).to_have_count(0)
    expect(page.get_by_role("button", name="Diagnose")).to_be_enabled()


# in the page from now on: each file a drop area takes (FilePond's item, captured before any other
# listener), the FilePond status of each at every upload message the page sends, and how many
# files FilePond has finished processing (its "Sent" state)
UPLOADS_JS = """() => {
  const seen = window.bushingUploads = {files: [], atSend: [], processed: 0};
  const names = Object.fromEntries(Object.entries(window.FilePond.FileStatus).map(([k, v]) => [v, k]));
  window.addEventListener('FilePond:addfile', (e) => { if (e.detail.file) seen.files.push(e.detail.file); }, true);
  window.addEventListener('FilePond:processfile', () => { seen.processed += 1; }, true);
  const send = WebSocket.prototype.send;
  WebSocket.prototype.send = function (data) {
    if (typeof data === 'string' && data.includes('upload_event')) seen.atSend.push(seen.files.map(f => names[f.status]));
    return send.call(this, data);
  };
}"""


def test_a_file_is_sent_as_soon_as_its_drop_area_has_it(page, explorer_url):
    """A stiffness CSV leaves the page the moment the drop area has accepted it, while the drop
    area still holds it queued behind its animations (FilePond's PROCESSING_QUEUED), and once:
    the summary does not wait for the drop area's animations (issue #27 item 16: 1.5 s from the
    file to its summary, of which the file waited about a second in the page before it was sent,
    by FilePond's processing, PROCESSING)."""
    open_tab(page, explorer_url)
    page.evaluate(UPLOADS_JS)
    page.locator("#main input[type=file]").first.set_input_files(str(EXAMPLES / "paper_b_stiffness.csv"))
    page.get_by_text(re.compile(r"Stiffness: 150 points")).first.wait_for()
    page.wait_for_function("() => window.bushingUploads.processed >= 1")  # the drop area says it is sent
    seen = page.evaluate("() => window.bushingUploads")
    assert seen["atSend"] == [["PROCESSING_QUEUED"]], seen["atSend"]
    assert page.evaluate("() => window.bushingUploadAtOnce") == "on"  # app.patches.UPLOAD_AT_ONCE found its internals
    expect(page.locator(".filepond--item[data-filepond-item-state='processing-complete']")).to_have_count(1)
