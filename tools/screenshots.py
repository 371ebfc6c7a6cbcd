"""Screenshots of every tab of the explorer at given window sizes, in the system Chromium.

    python tools/screenshots.py                                  # 1280x720 and 1600x1000 into shots/
    python tools/screenshots.py --out /tmp/shots --sizes 1280x720,1920x1080
    python tools/screenshots.py --url http://localhost:5006/     # a server already running

Without ``--url`` it starts ``bushing serve --port 0`` from this repository (the port the OS
picks, read from the line the server prints) and stops it at the end. For each size it opens the
page in a window of that size, selects each tab in turn (through the tab bar's model, so a tab
whose header is off screen is still shot), waits until every figure shown and every view has
painted, and writes ``<out>/<width>x<height>/<nn>-<tab>.png`` (the window, not the
whole page: what a user of that screen sees). The README's screenshots are made with it.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZES = ((1280, 720), (1600, 1000))
LOAD_TIMEOUT_MS = 90_000
DRAW_TIMEOUT_MS = 10_000

# the tab bar's model and its titles
TABS_JS = """() => {
  if (!(window.Bokeh && Bokeh.documents && Bokeh.documents.length > 0)) return null;
  const tabs = [...Bokeh.documents[0].all_models].find(m => m.type.endsWith('Tabs'));
  return tabs ? tabs.tabs.map(t => t.title) : null;
}"""

SELECT_JS = """(index) => {
  const tabs = [...Bokeh.documents[0].all_models].find(m => m.type.endsWith('Tabs'));
  tabs.active = index;
}"""

# the document idle, the selected tab's content sent (not Panel's placeholder) and laid out, and
# every figure shown (a figure view with a size on the page) painted
DRAWN_JS = """() => {
  if (!(window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle)) return false;
  const views = [...Bokeh.index.all_views()];
  const tabs = views.find(v => v.model.type.endsWith('Tabs'));
  if (!tabs) return false;
  const child = tabs.child_views[tabs.model.active];
  if (!child || child.model.type === 'Spacer') return false;  // Panel's placeholder of a tab not yet sent
  if (child.el.getBoundingClientRect().height < 150) return false;  // a lazy tab: not yet filled
  const shown = v => { const r = v.el.getBoundingClientRect(); return r.width > 0 && r.height > 0; };
  return views.filter(v => v.model.type === 'Figure' && shown(v)).every(v => v.has_finished());
}"""

# no drop area's words halfway through a fade: FilePond fades them in from its own frame loop, which
# runs slowly while no drop area is used (the shots caught them pale, as if disabled)
WORDS_JS = """() => {
  const labels = [];
  const walk = (root) => root.querySelectorAll('*').forEach(el => {
    if (el.classList.contains('filepond--drop-label')) labels.push(el);
    if (el.shadowRoot) walk(el.shadowRoot);
  });
  walk(document);
  // the words at rest: shown (opacity 1), or hidden while the area holds a file (0); FilePond writes
  // their opacity from its first frame on (none yet, then 0 and up to 1)
  const resting = el => el.style.opacity === '1' ||
    (el.style.opacity === '0' && el.closest('.filepond--root')?.querySelector('.filepond--item') != null);
  return labels.every(el => el.offsetWidth === 0 || resting(el));
}"""

SETTLE_JS = """() => Promise.all([...Bokeh.index.all_views()].map(v => v.ready))"""


def slug(title: str) -> str:
    """A file name's part for a tab title: lower case, words joined by hyphens."""
    return re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")


def parse_sizes(text: str) -> list[tuple[int, int]]:
    """``"1280x720,1600x1000"`` as ``[(1280, 720), (1600, 1000)]`` (pixels)."""
    sizes = []
    for part in text.split(","):
        match = re.fullmatch(r"\s*(\d+)\s*[x×]\s*(\d+)\s*", part)
        if not match:
            raise SystemExit(f"screenshots: a size is WIDTHxHEIGHT in pixels, got {part!r}")
        sizes.append((int(match[1]), int(match[2])))
    return sizes


def start_server() -> tuple[subprocess.Popen, str]:
    """``bushing serve --port 0`` from this repository, and the URL it printed."""
    module = "cli.main" if (ROOT / "cli" / "main.py").exists() else "app.cli"  # (older trees)
    server = subprocess.Popen([sys.executable, "-m", module, "serve", "--port", "0"], cwd=ROOT,
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    for line in server.stdout:
        match = re.search(r"(http://\S+)", line)
        if match:
            return server, match[1]
    server.kill()
    raise SystemExit("screenshots: the server stopped before printing its URL")


def shoot(url: str, out: Path, sizes, chromium: str) -> list[Path]:
    """Every tab at every size, written under ``out``; the files written."""
    from playwright.sync_api import sync_playwright

    written = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium,
                                    args=["--no-sandbox", "--disable-gpu", "--no-first-run"])
        for width, height in sizes:
            page = browser.new_page(viewport={"width": width, "height": height})
            page.goto(url)
            page.wait_for_function(TABS_JS, timeout=LOAD_TIMEOUT_MS)
            titles = page.evaluate(TABS_JS)
            folder = out / f"{width}x{height}"
            folder.mkdir(parents=True, exist_ok=True)
            for index, title in enumerate(titles):
                page.evaluate(SELECT_JS, index)
                try:
                    page.wait_for_function(DRAWN_JS, timeout=DRAW_TIMEOUT_MS if index else LOAD_TIMEOUT_MS)
                except Exception:  # noqa: BLE001 - a tab still drawing is shot as it is, said
                    print(f"screenshots: {title!r} at {width}x{height} was not drawn in time (shot as it is)", file=sys.stderr)
                try:
                    page.wait_for_function(WORDS_JS, timeout=DRAW_TIMEOUT_MS)
                except Exception:  # noqa: BLE001 - shot as it is, said
                    print(f"screenshots: {title!r} at {width}x{height}: a drop area's words still fading", file=sys.stderr)
                page.evaluate(SETTLE_JS)
                path = folder / f"{index + 1:02d}-{slug(title)}.png"
                page.screenshot(path=str(path))
                written.append(path)
                print(path, flush=True)
            page.close()
        browser.close()
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "shots", help="folder for <size>/<nn>-<tab>.png")
    parser.add_argument("--sizes", default=",".join(f"{w}x{h}" for w, h in SIZES),
                        help="window sizes, WIDTHxHEIGHT[,WIDTHxHEIGHT...] (default %(default)s)")
    parser.add_argument("--url", help="an explorer already served (default: serve one on a free port)")
    parser.add_argument("--chromium", default=shutil.which("chromium") or shutil.which("chromium-browser"),
                        help="the Chromium executable (default: the system's)")
    args = parser.parse_args(argv)
    if not args.chromium:
        raise SystemExit("screenshots: Chromium is not installed (apt-get install -y chromium)")
    sizes = parse_sizes(args.sizes)
    server = None
    url = args.url
    if url is None:
        server, url = start_server()
    try:
        shoot(url, args.out, sizes, args.chromium)
    finally:
        if server is not None:
            server.terminate()
            server.wait(30)
    return 0


if __name__ == "__main__":
    sys.exit(main())
