"""How long a drop area calls a sent file "busy", and what Chromium spends meanwhile (issue #27,
items 12 and 16): prints figures, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/drop_area_busy.py [--uploads 8] [--still] [--tree PATH]

It serves the explorer of ``--tree`` (the working tree by default; ``git worktree add`` another
commit to measure it), opens it in the system Chromium (headless, no GPU) and ``--uploads`` times:
a new page, *Find the missing effect*, 1 s at rest, then the 150 points of diagnose_browser.py
handed to its drop area. Per upload: the data's line on the page and the drop area's file no
longer busy (FilePond's ``data-filepond-item-state`` "processing-complete"), in s from the
hand-over (Playwright's clock, a poll every 50 ms), and the CPU of every Chromium process over that
time (utime + stime, /proc), and how many progress rings turn when the data's line is shown.
``--still`` holds FilePond's progress ring still (a rule in each drop area): what a still ring
would save. The diagnosis started with the data runs
meanwhile on the server's worker process (docs/serving.md), as it does for a user.
"""

from __future__ import annotations

import argparse
import signal
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from app_latency import chromium_cpu  # CPU seconds of Chromium's processes, by type (/proc)
from diagnose_browser import CHROMIUM, data_file
from servers import start_explorer

# the document and every shadow root in it, each given to f (the page's components each have one)
ROOTS_JS = """const roots = (f) => { const walk = (root) => { f(root);
  for (const el of root.querySelectorAll('*')) if (el.shadowRoot) walk(el.shadowRoot); }; walk(document); };"""
# every drop area's items' states
STATES_JS = f"""() => {{ {ROOTS_JS} const out = [];
  roots(r => {{ for (const el of r.querySelectorAll('[data-filepond-item-state]')) out.push(el.getAttribute('data-filepond-item-state')); }});
  return out.join(','); }}"""
# the ring held still, a rule in every drop area's shadow root
STILL_JS = f"""() => {{ {ROOTS_JS} roots(r => {{ if (r !== document && r.querySelector('.filepond--root')) {{
  const s = new CSSStyleSheet(); s.replaceSync(".filepond--progress-indicator svg {{ animation: none !important; }}");
  r.adoptedStyleSheets = [...r.adoptedStyleSheets, s]; }} }}); }}"""
# how many of the page's animations turn a ring now
SPINS_JS = f"""() => {{ {ROOTS_JS} let n = 0;
  roots(r => {{ n += r.getAnimations().filter(a => a.animationName === 'spin' && a.playState === 'running').length; }});
  return n; }}"""


def browser_cpu() -> float:
    """CPU seconds of every Chromium process so far (app_latency.chromium_cpu, all types)."""
    return sum(chromium_cpu().values())


def upload(page, url: str, csv: Path, still: bool) -> dict:
    page.goto(url)
    page.wait_for_function("() => window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle",
                           timeout=120_000)
    page.get_by_text("Find the missing effect", exact=True).click()
    page.get_by_role("button", name="Diagnose").wait_for(timeout=60_000)
    if still:
        page.evaluate(STILL_JS)
    page.wait_for_timeout(1000)
    cpu, start = browser_cpu(), time.perf_counter()
    page.locator("#main input[type=file]").last.set_input_files(str(csv))
    page.get_by_text("150 points").first.wait_for(timeout=60_000)
    shown = time.perf_counter() - start
    spins = page.evaluate(SPINS_JS)
    page.wait_for_function(f"() => ({STATES_JS})().includes('processing-complete')", polling=50, timeout=60_000)
    return {"spins": spins, "shown": shown, "busy": time.perf_counter() - start, "cpu": browser_cpu() - cpu}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--uploads", type=int, default=8)
    parser.add_argument("--still", action="store_true", help="FilePond's ring held still")
    parser.add_argument("--tree", type=Path, default=HERE.parent)
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp:
        csv = Path(tmp) / "inertia.csv"
        data_file(csv)
        proc, url = start_explorer(args.tree)
        try:
            with sync_playwright() as p:
                browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"])
                page = browser.new_page(viewport={"width": 1500, "height": 1300})
                out = [upload(page, url, csv, args.still) for _ in range(args.uploads)]
                browser.close()
        finally:
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=30)
    for r in out:
        print(f"data's line {r['shown']:.2f} s ({r['spins']} ring(s) turning then), busy until {r['busy']:.2f} s, Chromium's CPU meanwhile {r['cpu']:.2f} s")
    print(f"medians of {len(out)}{' (ring held still)' if args.still else ''}: data's line "
          f"{statistics.median(r['shown'] for r in out):.2f} s, busy until {statistics.median(r['busy'] for r in out):.2f} s, "
          f"Chromium's CPU {statistics.median(r['cpu'] for r in out):.2f} s")


if __name__ == "__main__":
    main()
