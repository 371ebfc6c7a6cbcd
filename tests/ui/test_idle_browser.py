"""A page at rest draws nothing for its drop areas (app.patches.IDLE_PAINTER): FilePond's loop,
which asks for every frame while the page is open, is slowed to one step per 250 ms while no drop
area is used, and runs at every frame again once one is. The page's own frames are the clock:
at rest, FilePond's loop does its work on at most a third of them (measured: 5 of 90; unslowed,
on all 90); after a pointer over a drop area, on at least a quarter (measured: 40 of 40)."""

import re
from pathlib import Path

from tests.ui.bokeh_page import drop_into, open_explorer

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

# over `frames` of the page's frames: how many steps FilePond's loop took (its readers, called at
# each step that does its work)
STEPS_JS = """(frames) => new Promise((resolve) => {
  const painter = window.__framePainter;
  let steps = 0, seen = 0;
  const count = () => { steps += 1; };
  painter.readers.push(count);
  const frame = () => {
    seen += 1;
    if (seen < frames) { requestAnimationFrame(frame); return; }
    painter.readers.splice(painter.readers.indexOf(count), 1);
    resolve(steps);
  };
  requestAnimationFrame(frame);
})"""


def test_the_drop_areas_loop_rests_while_no_drop_area_is_used(page, explorer_url):
    open_explorer(page, explorer_url)
    page.wait_for_function("() => window.__framePainter != null && window.bushingIdlePainter === 'on'")
    page.get_by_text("Find the missing effect", exact=True).click()
    area = page.locator(".filepond--root").first
    area.wait_for()
    area.hover()  # a pointer over the drop area: the loop runs at every frame
    awake = page.evaluate(STEPS_JS, 40)
    assert awake >= 10, awake
    page.mouse.move(5, 5)  # away from it; the loop rests two seconds after the last use
    page.wait_for_function("() => new Promise(r => setTimeout(() => r(true), 2100))")
    resting = page.evaluate(STEPS_JS, 90)
    assert resting <= 30, resting


def test_a_file_dropped_at_rest_is_loaded_and_shown_complete(page, explorer_url):
    """A file given to a drop area that rested: taken, sent and marked complete as before."""
    open_explorer(page, explorer_url)
    page.wait_for_function("() => true")
    page.get_by_text("Measured data and fit", exact=True).click()
    page.wait_for_function("() => new Promise(r => setTimeout(() => r(true), 2100))")  # the loop at rest
    page.locator("#main input[type=file]").first.set_input_files(str(EXAMPLES / "paper_b_stiffness.csv"))
    page.get_by_text(re.compile(r"Stiffness: 150 points")).first.wait_for()
    page.locator(".filepond--item[data-filepond-item-state='processing-complete']").first.wait_for()



def test_a_file_sent_is_complete_without_a_played_progress(page, explorer_url):
    """FilePond plays a file's progress over 0.75-1.5 s however fast it went ("minimum upload
    duration"), and kept the area saying "Uploading" while the file's data were on the page
    (app/js/upload_at_once.js turns it off): every progress it reports, if any, is the whole file
    (on 2e70b6c: 0.10, 0.21, 0.29, … played for a file sent at once)."""
    open_explorer(page, explorer_url)
    page.get_by_text("Find the missing effect", exact=True).click()
    page.get_by_role("button", name="Diagnose").wait_for()
    page.evaluate("""() => { window.bushingProgress = [];
      document.addEventListener('FilePond:processfileprogress', (e) => window.bushingProgress.push(e.detail.progress), true); }""")
    drop_into(page, EXAMPLES / "paper_b_stiffness.csv")
    page.locator(".filepond--item[data-filepond-item-state='processing-complete']").last.wait_for()
    reported = page.evaluate("() => window.bushingProgress")
    assert all(p == 1 for p in reported), reported
