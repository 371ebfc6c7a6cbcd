"""The other tabs in a real browser: slices and the branch-by-branch player, measured data and
the fit, the diagnosis, every direction, the what-ifs. Each step waits for the state it then
checks."""

import re
from pathlib import Path

import pytest
from playwright.sync_api import expect

from tests.ui.bokeh_page import (
    drop_into,
    mystery_demo,
    open_explorer,
    plots,
    tap,
    wait_figure,
    wait_plot,
    wait_plot_changed,
    wait_tappable,
)

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

pytestmark = pytest.mark.usefixtures("console_errors", "no_server_tracebacks")


def test_slices_tap_and_teaching_play(page, explorer_url):
    open_explorer(page, explorer_url)
    page.get_by_text("Slices", exact=True).click()
    title = "|K|: single modulus, slices and continuum"
    wait_tappable(page, title)
    tap(page.locator(".bk-Canvas").first, 0.25)
    wait_plot(page, title, "p.spans.length > 0 && p.spans[0] !== 0.1")
    assert page.get_by_text("3 slices").count() >= 1
    page.get_by_text("Fletcher–Gent, branch by branch", exact=True).click()
    loop = "Loop shape during the amplitude sweep"
    wait_figure(page, loop)
    frame = page.locator(".frame-point")
    expect(frame).to_contain_text("Loop shape at")  # the label comes in a message of its own
    first = frame.inner_text()
    before = plots(page)[loop]
    page.locator("button.play").click()
    expect(frame).not_to_have_text(first)  # the player moves on
    wait_plot_changed(page, loop, before)  # and the loop with it


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
    page.get_by_role("button", name="Fit the five material parameters").wait_for()
    inputs = page.locator("#main input[type=file]")  # the tab's drop areas (the sidebar opens design files)
    inputs.first.set_input_files(str(bad))
    expect(page.locator(".data-error")).to_contain_text("line 2: magnitude is missing")
    inputs.first.set_input_files(str(good))  # the drop area holds both: the good one loads
    page.get_by_text("150 points").first.wait_for()
    assert "bad.csv: line 2" in page.locator(".data-error").inner_text()
    assert "not loaded; the other files are" in page.locator(".data-error").inner_text()
    # removing the bad file from the drop area clears its message
    item = page.locator(".filepond--item").filter(has_text="bad.csv")
    item.locator(".filepond--action-revert-item-processing").click()  # "tap to undo" once uploaded
    page.locator(".data-error").wait_for(state="detached")
    page.get_by_role("button", name="Fit the five material parameters").click()
    page.get_by_text("Correlation between parameters").wait_for()
    page.get_by_role("button", name="Use the fitted design in the explorer").click()
    page.get_by_text("VP 40/70120 (Paper B) (fitted)").first.wait_for()
    page.get_by_text("Explorer", exact=True).click()
    wait_plot(page, "|K| against frequency", "p.legends.includes('measured')")
    assert plots(page)["|K| against frequency"]["points"] > 150 * 2  # curves and the 150 measured points


def test_an_oversized_file_is_refused_in_the_browser(page, explorer_url, tmp_path):
    """A 21 MB file (valid rows) is refused by the drop area with the limit in its message,
    before anything is sent; the session goes on and takes the next file."""
    from core.io.measured import MAX_BYTES

    row = "10,0.0001,4200000.0000000000,0.1400000000000000\n"
    big = tmp_path / "big.csv"
    big.write_text("frequency_hz,amplitude,magnitude,loss_factor\n" + row * (MAX_BYTES // len(row) + 20_000))
    assert big.stat().st_size > MAX_BYTES
    sent = []  # the size of every websocket frame the page sends
    page.on("websocket", lambda ws: ws.on("framesent", lambda payload: sent.append(len(payload))))
    open_explorer(page, explorer_url)
    page.get_by_text("Measured data and fit", exact=True).click()
    page.get_by_role("button", name="Fit the five material parameters").wait_for()
    inputs = page.locator("#main input[type=file]")  # the tab's drop areas (the sidebar opens design files)
    inputs.first.set_input_files(str(big))
    page.get_by_text("File is too large").first.wait_for()
    assert page.get_by_text("Maximum file size is 20 MB").count() >= 1
    loop = EXAMPLES / "paper_b_loop.csv"
    inputs.nth(1).set_input_files(str(loop))  # the session goes on
    page.get_by_text("400 samples at 0.1 Hz").wait_for()
    # the loop file went to the server (the frames counted hold it), and its answer came back,
    # after the refusal: nothing of the big file was sent on the way, no stiffness was loaded
    assert loop.stat().st_size <= sum(sent) < MAX_BYTES, sum(sent)
    assert page.get_by_text(re.compile(r"Stiffness: \d+ points")).count() == 0


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
    page.get_by_role("button", name="Diagnose").wait_for()
    drop_into(page, measured)
    page.get_by_text("150 points").first.wait_for()
    page.get_by_role("button", name="Diagnose").click()
    page.get_by_text("Step 1: add Apparent mass seen by the force sensor").wait_for(timeout=60_000)
    page.get_by_text("What is left is noise", exact=True).wait_for()
    gaps_title = "Gap (relative RMS misfit of complex stiffness) after each step"
    wait_plot(page, gaps_title, "p.spans.length > 0")  # the diagnosis' plots are drawn
    wait_plot(page, "Final: |K| misfit (%)", "p.points > 0")
    shown = plots(page)
    gaps = shown[gaps_title]
    assert gaps["points"] == 2 and len(gaps["spans"]) == 1  # baseline and + inertia; the noise line
    assert shown["Final: |K| misfit (%)"]["points"] >= 150
    page.get_by_role("button", name="Use the final model in the explorer").click()
    page.get_by_text("effects: inertia").first.wait_for()
    page.get_by_text("VP 40/70120 (Paper B) (fitted)").first.wait_for()  # one name: fitted or diagnosed


def test_mystery_demo_reveals_its_truth(page, explorer_url):
    mystery_demo(page, explorer_url)
    assert page.get_by_text("The diagnosis found exactly that.").count() == 1


def test_every_direction_from_a_link(page, explorer_url):
    """A link to a radial, finite-length design: the mode and the switch come back, and the
    Every direction tab draws its card."""
    open_explorer(page, explorer_url + "?mode=radial&finite=true")
    assert page.get_by_role("button", name="radial").get_attribute("class").count("bk-active") == 1
    page.get_by_text("Finite-length S is 0.482 of the long-bushing formula").wait_for()
    page.get_by_text("Every direction", exact=True).click()
    page.get_by_text("Shape factor: finite-length table, every direction.").wait_for()
    page.get_by_text("Ratios").wait_for()
    axial, radial = "|K| axial", "|K| radial"
    for title in (axial, radial, "Loss factor, turning and tilting"):
        wait_plot(page, title, "p.points > 0")
    shown = plots(page)
    assert shown[axial]["points"] >= 60 and shown[radial]["points"] >= 60
    assert shown["Loss factor, turning and tilting"]["points"] >= 2 * 60


def test_what_ifs_bands_sensitivities_and_a_design_from_targets(page, explorer_url):
    """Tolerances switched on draw a band on every stiffness plot; the sensitivity bars are
    drawn; a |K| target finds a design that the explorer takes."""
    open_explorer(page, explorer_url)
    page.get_by_text("What-ifs", exact=True).click()
    page.get_by_role("button", name="Find designs").wait_for()
    wait_plot(page, "|K|: % per +1 % of the parameter", "p.points > 0")
    assert plots(page)["|K|: % per +1 % of the parameter"]["points"] == 8
    box = page.get_by_label("Shear modulus µ ± %")
    box.fill("10")
    box.press("Enter")
    page.wait_for_url(re.compile(r"tol=mu(%3A|:)10"))  # the server took the tolerance
    page.locator(".band-switch input[type=checkbox]").check()
    page.wait_for_url(re.compile(r"bands=true"))  # and the switch
    page.get_by_text("Explorer", exact=True).click()
    page.get_by_text("Tolerance band (5–95 %").wait_for()
    for title in ("|K| against frequency", "Loss factor against amplitude"):
        wait_plot(page, title, "p.legends.includes('5–95 % band')")
    page.get_by_text("What-ifs", exact=True).click()
    target = page.get_by_label("|K| target")
    target.fill("4.5")
    target.press("Enter")
    page.get_by_role("button", name="Find designs").click()
    page.get_by_text("1 design meets every target").wait_for()
    page.get_by_role("button", name="Take it into the explorer").click()
    page.get_by_text("VP 40/70120 (Paper B) (from targets)").first.wait_for()
    page.get_by_text("Explorer", exact=True).click()
    page.get_by_text("|K| = 4.5 kN/mm").wait_for()


def test_a_link_brings_the_tolerance_bands(page, explorer_url):
    open_explorer(page, explorer_url + "?tol=mu:10,L:1&bands=true")
    page.get_by_text("Tolerance band (5–95 %").wait_for()
    wait_plot(page, "|K| against frequency", "p.legends.includes('5–95 % band')")
    page.get_by_text("What-ifs", exact=True).click()
    field = page.get_by_label("Shear modulus µ ± %")
    expect(field).to_have_value("10")
    field.fill("12")
    field.press("Enter")
    page.wait_for_url(re.compile(r"tol=L(%3A|:)1(%2C|,)mu(%3A|:)12"))
