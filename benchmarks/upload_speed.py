"""A stiffness CSV upload in Chromium, to its summary on the page (issue #27 item 16): prints
figures, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/upload_speed.py [--uploads 7] [--file examples/paper_b_stiffness.csv] [--before REV]

For the explorer of the working tree it starts ``bushing serve --port 0`` (explorer_change.py's
way), and ``--uploads`` times: opens a new page (a new session: a first upload, as a user makes
it), waits until the Explorer's plots are drawn and the document idle, opens the *Measured data
and fit* tab, waits until it is idle, then gives the file to the stiffness drop area and times,
in ms, from handing over the file to the summary "Stiffness: N points" shown, and to every view
of the page painted after it. Prints the median and the spread of each, and the server's CPU
time per upload (utime+stime of /proc/PID/stat around the upload).

``--before REV`` measures the explorer of commit REV the same way (a temporary ``git worktree``,
served with that tree as the working directory) and prints the ratios now / before.

Target of issue #27: upload to summary ≤ 0.5 s (measured at 1.5 s on 63e5360).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
from app_latency import cpu_seconds
from explorer_change import start_explorer, stop

from tests.ui.bokeh_page import EXPLORER_TITLES, READY_JS, SETTLE_JS

TAB = "Measured data and fit"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def settled(page):
    token = page.evaluate(SETTLE_JS)
    page.wait_for_function("(token) => window.bushingSettled >= token", arg=token, timeout=60_000)


def idle(page):
    page.wait_for_function("() => Bokeh.documents[0].is_idle", timeout=60_000)
    settled(page)


def measure(browser, url: str, pid: int, path: Path, n: int) -> dict:
    """``n`` uploads of ``path``, each on a new page: ms to the summary, ms to every view painted,
    server CPU ms."""
    out = {"summary": [], "painted": [], "cpu": []}
    for _ in range(n):
        page = browser.new_page(viewport={"width": 1500, "height": 1000})
        page.goto(url)
        page.wait_for_function(READY_JS, arg=list(EXPLORER_TITLES), timeout=120_000)
        settled(page)
        page.get_by_text(TAB, exact=True).click()
        page.get_by_role("button", name="Fit the five material parameters").wait_for(timeout=60_000)
        idle(page)
        summary = page.get_by_text("Stiffness:", exact=False).filter(has_text="points")
        cpu0, t0 = cpu_seconds(pid), time.perf_counter()
        page.locator("#main input[type=file]").first.set_input_files(str(path))
        summary.first.wait_for(timeout=60_000)
        t1 = time.perf_counter()
        idle(page)
        t2, cpu1 = time.perf_counter(), cpu_seconds(pid)
        out["summary"].append(1e3 * (t1 - t0))
        out["painted"].append(1e3 * (t2 - t0))
        out["cpu"].append(1e3 * (cpu1 - cpu0))
        page.close()
    return out


def start_old(tree: Path):
    """An explorer from before ``bushing`` moved to cli/ (63e5360: ``python -m app.cli serve``)."""
    import re
    import select
    import threading

    proc = subprocess.Popen([sys.executable, "-m", "app.cli", "serve", "--port", "0", "--address", "127.0.0.1"],
                            cwd=tree, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**{k: v for k, v in os.environ.items() if k != "PYTHONPATH"}, "PYTHONUNBUFFERED": "1"})
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        url = re.search(r"http://\S+/", proc.stdout.readline() if ready else "")
        if url:
            threading.Thread(target=lambda: [None for _ in proc.stdout], daemon=True).start()
            return proc, url.group(0)
    proc.kill()
    raise RuntimeError("the old explorer did not print its URL")


def run(tree: Path, path: Path, n: int) -> dict:
    from playwright.sync_api import sync_playwright

    proc, url = start_explorer(tree) if (tree / "cli" / "main.py").exists() else start_old(tree)
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"])
            try:
                return measure(browser, url, proc.pid, path, n)
            finally:
                browser.close()
    finally:
        stop(proc)


def show(name: str, figures: dict):
    print(f"{name}:")
    for key, label in (("summary", "upload → summary shown"), ("painted", "upload → every view painted"),
                       ("cpu", "server CPU per upload")):
        v = figures[key]
        print(f"  {label:30s} median {statistics.median(v):7.0f} ms  (min {min(v):.0f}, max {max(v):.0f}, n={len(v)})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--uploads", type=int, default=7)
    parser.add_argument("--file", type=Path, default=HERE.parent / "examples" / "paper_b_stiffness.csv")
    parser.add_argument("--before", help="a commit to measure the same way")
    args = parser.parse_args()
    path = args.file.resolve()
    now = run(HERE.parent, path, args.uploads)
    show("this tree", now)
    if args.before:
        with tempfile.TemporaryDirectory() as tmp:
            old = Path(tmp) / "before"
            subprocess.run(["git", "worktree", "add", "-q", "--detach", str(old), args.before], cwd=HERE.parent,
                           check=True)
            try:
                before = run(old, path, args.uploads)
            finally:
                subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=HERE.parent, check=False)
        show(f"before ({args.before})", before)
        for key in ("summary", "painted", "cpu"):
            print(f"  ratio now / before, {key}: {statistics.median(now[key]) / statistics.median(before[key]):.2f}")


if __name__ == "__main__":
    main()
