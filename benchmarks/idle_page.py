"""What an open page costs while nobody uses it: Chromium's CPU per second at rest (issue #27,
item 16: the page's share of the machine that the server and its worker need). Prints figures,
asserts nothing.

    PYTHONPATH=$PWD python benchmarks/idle_page.py [--seconds 4] [--before REV]

It serves the explorer of the working tree (``bushing serve --port 0``), opens it in the system
Chromium (headless) and reads the CPU time of Chromium's processes (``/proc``: the renderer, which
runs the page, and the others) over ``--seconds`` at rest: on the Explorer once it is drawn, and
on *Find the missing effect* some seconds after 150 points were loaded there (its report's plots
made ready meanwhile). ``--before REV`` measures a temporary ``git worktree`` of REV the same way.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from app_latency import chromium_cpu  # CPU seconds of Chromium's processes, by type (/proc)
from diagnose_browser import CHROMIUM, data_file  # the same data and browser
from servers import start_explorer

SETTLE_S = 3.0  # after a page is drawn or data loaded, before the rest is measured


def at_rest(seconds: float) -> dict[str, float]:
    """Chromium's CPU seconds per second over ``seconds``: its renderers, and its other processes."""
    start = chromium_cpu()
    time.sleep(seconds)
    end = chromium_cpu()
    used = {kind: end[kind] - start.get(kind, 0.0) for kind in end}
    renderer = used.pop("renderer", 0.0)
    return {"renderer": renderer / seconds, "other": sum(used.values()) / seconds}


def measure(tree: Path, seconds: float, csv: Path) -> dict[str, dict[str, float]]:
    from playwright.sync_api import sync_playwright

    proc, url = start_explorer(tree)
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"])
            page = browser.new_page(viewport={"width": 1500, "height": 1300})
            page.goto(url)
            page.wait_for_function("() => window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle",
                                   timeout=120_000)
            time.sleep(SETTLE_S)
            out = {"Explorer": at_rest(seconds)}
            page.get_by_text("Find the missing effect", exact=True).click()
            page.locator("#main input[type=file]").last.set_input_files(str(csv))
            page.get_by_text("150 points").first.wait_for(timeout=60_000)
            time.sleep(2 * SETTLE_S)  # the report's plots made ready, the drop area's animations done
            out["diagnosis tab, data loaded"] = at_rest(seconds)
            browser.close()
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=20)
    return out


def show(name: str, figures: dict) -> None:
    for view, cpu in figures.items():
        print(f"  {name:<12} {view:<28} Chromium CPU per second at rest: renderer {cpu['renderer']:.3f} s, "
              f"other processes {cpu['other']:.3f} s")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=4.0)
    parser.add_argument("--before", help="a git revision to measure too")
    args = parser.parse_args()
    print(f"an open page at rest ({args.seconds:g} s each); load average {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        csv = Path(tmp) / "inertia.csv"
        data_file(csv)
        show("now", measure(HERE.parent, args.seconds, csv))
        if args.before:
            old = Path(tmp) / "before"
            subprocess.run(["git", "worktree", "add", "--detach", str(old), args.before], cwd=HERE.parent,
                           check=True, capture_output=True)
            try:
                show(args.before[:10], measure(old, args.seconds, csv))
            finally:
                subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=HERE.parent, check=False)


if __name__ == "__main__":
    main()
