"""A stiffness CSV upload in Chromium, to its summary on the page (issue #27 item 16): prints
figures, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/upload_speed.py [--uploads 7] [--file examples/paper_b_stiffness.csv] [--before REV]

For the explorer of the working tree it starts ``bushing serve --port 0`` (explorer_change.py's
way), and ``--uploads`` times: opens a new page (a new session: a first upload, as a user makes
it), waits until the Explorer's plots are drawn and the document idle, opens the *Measured data
and fit* tab, waits until it is idle, then gives the file to the stiffness drop area and times,
in ms, from handing over the file to the summary "Stiffness: N points" shown (in the page's DOM
at an animation frame: the page's clock, not Playwright's polling, whose intervals grow to
half a second), and to every view of the page painted after it. Prints the median and the spread of each, and the server's CPU
time per upload (utime+stime of /proc/PID/stat around the upload).

Where the time goes, per upload (medians, ms from the file handed over): the drop area has the
file (FilePond's ``addfile``, type and size checked), its bytes leave the page (the websocket
frame carrying the ``upload_event``: Chromium's ``Network.webSocketFrameSent`` through CDP), the
server's first and summary messages arrive (``Network.webSocketFrameReceived``), the summary is in
the page's DOM (a requestAnimationFrame loop reading its text). The server's
own part is split in-process: parsing and judging the file (``app.state.read_stiffness``:
core.io.measured, core.plausibility) and the whole load into a session's state with its views.

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
from servers import start_explorer, stop

from tests.ui.bokeh_page import EXPLORER_TITLES, READY_JS, SETTLE_JS

TAB = "Measured data and fit"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def settled(page):
    token = page.evaluate(SETTLE_JS)
    page.wait_for_function("(token) => window.bushingSettled >= token", arg=token, timeout=60_000)


def idle(page):
    page.wait_for_function("() => Bokeh.documents[0].is_idle", timeout=60_000)
    settled(page)


# in the page, before the upload: when the drop area has the file, when the upload's frame is
# sent, when the summary is in the DOM (Panel's panes are in shadow roots: their text read through)
MARKS_JS = """() => {
  const t0 = performance.now();
  const marks = window.bushingMarks = {handed: t0};
  document.addEventListener('FilePond:addfile', () => { marks.addfile ??= performance.now(); });
  const send = WebSocket.prototype.send;
  WebSocket.prototype.send = function (data) {
    if (typeof data === 'string' && data.includes('upload_event')) marks.sent ??= performance.now();
    return send.call(this, data);
  };
  const deepText = (node) => {
    let out = node.innerText ?? [...node.children].map(c => c.innerText ?? '').join(' ');
    for (const el of node.querySelectorAll('*')) if (el.shadowRoot) out += ' ' + deepText(el.shadowRoot);
    return out;
  };
  const look = () => {
    if (/Stiffness: \\d+ points/.test(deepText(document.body))) { marks.dom = performance.now(); return; }
    requestAnimationFrame(look);
  };
  requestAnimationFrame(look);
}"""
STEPS = (("addfile", "the drop area has the file"), ("sent", "its bytes leave the page"),
         ("first_reply", "the server's first message"), ("summary_reply", "the summary's message"),
         ("dom", "the summary in the DOM"))


def frames(cdp) -> list:
    """Websocket frames of the page as CDP reports them: (direction, seconds, payload)."""
    out = []
    cdp.send("Network.enable")
    cdp.on("Network.webSocketFrameSent", lambda e: out.append(("sent", e["timestamp"], e["response"]["payloadData"])))
    cdp.on("Network.webSocketFrameReceived",
           lambda e: out.append(("received", e["timestamp"], e["response"]["payloadData"])))
    return out


def steps(marks: dict, log: list) -> dict:
    """ms from the file handed over to each of :data:`STEPS` (the frames' CDP clock put on the
    page's by the upload's frame, seen by both)."""
    out = {k: marks[k] - marks["handed"] for k in ("addfile", "sent", "dom") if k in marks}
    sent = next((t for d, t, data in log if d == "sent" and "upload_event" in data), None)
    if sent is not None and "sent" in marks:
        offset = marks["sent"] - 1e3 * sent
        replies = [(1e3 * t + offset - marks["handed"], data) for d, t, data in log if d == "received" and t >= sent]
        if replies:
            out["first_reply"] = replies[0][0]
        summary = [t for t, data in replies if "Stiffness" in data and "points" in data]
        if summary:
            out["summary_reply"] = summary[0]
    return out


def measure(browser, url: str, pid: int, path: Path, n: int) -> dict:
    """``n`` uploads of ``path``, each on a new page: ms to the summary, ms to every view painted,
    server CPU ms, and ms to each of :data:`STEPS`."""
    out = {"summary": [], "painted": [], "cpu": [], "steps": []}
    for _ in range(n):
        page = browser.new_page(viewport={"width": 1500, "height": 1000})
        log = frames(page.context.new_cdp_session(page))
        page.goto(url)
        page.wait_for_function(READY_JS, arg=list(EXPLORER_TITLES), timeout=120_000)
        settled(page)
        page.get_by_text(TAB, exact=True).click()
        page.get_by_role("button", name="Fit the five material parameters").wait_for(timeout=60_000)
        idle(page)
        summary = page.get_by_text("Stiffness:", exact=False).filter(has_text="points")
        page.evaluate(MARKS_JS)
        cpu0, t0 = cpu_seconds(pid), time.perf_counter()
        page.evaluate("() => { window.bushingMarks.handed = performance.now(); }")
        page.locator("#main input[type=file]").first.set_input_files(str(path))
        page.wait_for_function("() => window.bushingMarks.dom != null", polling="raf", timeout=60_000)
        summary.first.wait_for(timeout=60_000)  # and Playwright finds it (its polling backs off: not timed)
        idle(page)
        t2, cpu1 = time.perf_counter(), cpu_seconds(pid)
        marks = page.evaluate("() => window.bushingMarks")
        out["summary"].append(marks["dom"] - marks["handed"])
        out["painted"].append(1e3 * (t2 - t0))
        out["cpu"].append(1e3 * (cpu1 - cpu0))
        out["steps"].append(steps(marks, log))
        page.close()
    return out


def in_process(path: Path, n: int = 9) -> dict:
    """The server's part without a browser, ms (medians of ``n``): the file parsed and judged
    (:func:`app.state.read_stiffness`), and loaded into a session's state whose views exist
    (an :class:`app.main.App` and the Measured data tab's view)."""
    from app.main import App
    from app.state import read_stiffness
    from app.tabs.measured_data_and_fit import MeasuredView

    content = path.read_text()
    parse, load = [], []
    for _ in range(n):
        app = App()
        MeasuredView(app.state, app.fit)
        t0 = time.perf_counter()
        read_stiffness(content, path.name, app.state.design)
        t1 = time.perf_counter()
        app.state.load_measured_files({path.name: content})
        t2 = time.perf_counter()
        parse.append(1e3 * (t1 - t0))
        load.append(1e3 * (t2 - t1))
    return {"parse": statistics.median(parse), "load": statistics.median(load)}


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
    print("  where the time goes (median ms from the file handed over):")
    for key, label in STEPS:
        v = [s[key] for s in figures["steps"] if key in s]
        if v:
            print(f"    {label:34s} {statistics.median(v):7.0f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--uploads", type=int, default=7)
    parser.add_argument("--file", type=Path, default=HERE.parent / "examples" / "paper_b_stiffness.csv")
    parser.add_argument("--before", help="a commit to measure the same way")
    args = parser.parse_args()
    path = args.file.resolve()
    now = run(HERE.parent, path, args.uploads)
    show("this tree", now)
    part = in_process(path)
    print(f"  in-process: the file parsed and judged {part['parse']:.0f} ms; loaded into a session with its views "
          f"{part['load']:.0f} ms")
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
