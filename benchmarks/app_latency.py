"""Explorer latency in real Chromium: prints figures, asserts nothing.

    python benchmarks/app_latency.py [--changes 40] [--sessions 10] [--query "tol=mu:10,L:1&bands=true"]

Starts `bushing serve` on a free port, opens the explorer in the system Chromium and measures:

* first page load: from navigation to every plot drawn and the document idle;
* one session: from a widget change (set on its Bokeh model, exactly as a user's edit reaches
  the server) to the last plot update painted (the last document change, then an animation
  frame), over many changes of the shear modulus and the drive amplitude;
* N sessions at once: N pages changing a widget at the same moment, round after round with a
  person's pause (0.5 s) between rounds; and, for reference, N pages each changing at its own
  pace (a pause of 0.5–1.5 s drawn for each change, so changes overlap as they happen to), and
  N pages changing back to back (each as soon as its last change is drawn), which saturates the
  machine.

All N pages run in one Chromium on this same 2-core machine as the server, so the pages'
rendering competes with the server for the CPU; users on their own machines would not. For the
simultaneous rounds the script also prints the CPU time per change of the server and of
Chromium's processes (page renderers, GPU/compositor, browser), read from /proc.

``--query`` opens the explorer with a link's query, e.g. the tolerance bands switched on (every
change then recomputes a 500-sample band as well).

Targets: median ≤ 150 ms and p95 ≤ 300 ms with one session; p95 ≤ 500 ms with 10 sessions;
first load ≤ 3 s.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import random
import shutil
import socket
import statistics
import subprocess
import sys
import time
import urllib.request

from playwright.async_api import async_playwright

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
# Ten users each look at their own page: background-tab throttling (timers, animation frames)
# would measure Chromium's tab scheduling, not the explorer, so it is switched off.
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run", "--disable-quic", "--disable-background-timer-throttling",
        "--disable-renderer-backgrounding", "--disable-backgrounding-occluded-windows"]

READY_JS = """(figures) => window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle &&
  [...Bokeh.documents[0].all_models].filter(m => m.type === 'Figure').length >= figures"""

# Change a widget's model and time until the last change to a plot (its data, ranges, marker,
# legend or axes) has been painted; the URL and text panes updating later do not count.
CHANGE_JS = """async ([title, value, quiet]) => {
  const doc = Bokeh.documents[0];
  const model = [...doc.all_models].find(m => m.title === title || m.label === title);
  const PLOT = new Set(['ColumnDataSource', 'DataRange1d', 'Range1d', 'Span', 'LegendItem', 'Legend', 'LinearAxis',
                        'LogAxis', 'Title', 'Figure']);
  let lastPaint = null, lastChange = null;
  const cb = (ev) => {
    if (!ev.model || !PLOT.has(ev.model.type)) return;
    lastChange = performance.now();
    requestAnimationFrame(() => { lastPaint = performance.now(); });
  };
  const t0 = performance.now();
  model.value = value;
  doc.on_change(cb);
  const ok = await new Promise(resolve => {
    const tick = () => {
      if (lastChange !== null && performance.now() - lastChange > quiet && lastPaint >= lastChange) resolve(true);
      else if (performance.now() - t0 > 20000) resolve(false);
      else setTimeout(tick, 10);
    };
    setTimeout(tick, 10);
  });
  doc.remove_on_change(cb);
  return ok ? lastPaint - t0 : null;
}"""


def cpu_seconds(pid) -> float:
    """User + system CPU time of one process (Linux /proc), 0 if it is gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def chromium_cpu() -> dict[str, float]:
    """CPU seconds of every Chromium process, by process type (renderer, gpu-process, …)."""
    out: dict[str, float] = {}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if "chrom" not in cmd.split(" ")[0]:
            continue
        kind = next((a[7:] for a in cmd.split(" ") if a.startswith("--type=")), "browser")
        out[kind] = out.get(kind, 0.0) + cpu_seconds(pid)
    return out


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(port, command=None, probe="/liveness"):
    """Start the explorer (or ``command``, another server) and wait until ``probe`` answers."""
    proc = subprocess.Popen(
        command or [sys.executable, "-m", "cli.main", "serve", "--port", str(port)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )
    deadline = time.time() + 60
    while time.time() < deadline:
        try:
            with urllib.request.urlopen(f"http://localhost:{port}{probe}", timeout=5):
                return proc
        except OSError:
            time.sleep(0.2)
    proc.kill()
    raise RuntimeError("the explorer did not start")


_RUN = iter(range(1, 10**6))


def changes(n):
    """Alternate a material change (every plot recomputed) and an operating-point change, with
    values never used before (a repeated value changes nothing)."""
    run = next(_RUN)
    out = []
    for i in range(n):
        if i % 2 == 0:
            out.append(("Shear modulus µ (MPa)", round(2.0 + 0.0001 * run + 0.013 * i, 6)))
        else:  # log10 of the amplitude in mm
            out.append(("Drive amplitude (mm)", round(-1.5 + 0.0001 * run + 0.02 * i, 6)))
    return out


async def open_page(browser, url, figures=5):
    page = await browser.new_page(viewport={"width": 1500, "height": 1300})
    t0 = time.perf_counter()
    await page.goto(url)
    await page.wait_for_function(READY_JS, arg=figures, timeout=60000, polling=20)
    return page, time.perf_counter() - t0


async def run_changes(page, n, quiet=150):
    out = []
    for title, value in changes(n):
        ms = await page.evaluate(CHANGE_JS, [title, value, quiet])
        if ms is None:
            raise RuntimeError(f"no plot updated within 20 s after setting {title} = {value}")
        out.append(ms)
    return out


def pct(values, q):
    values = sorted(values)
    return values[min(len(values) - 1, round(q / 100 * (len(values) - 1)))]


def report(name, ms, target):
    print(f"{name:<34} n={len(ms):>3}  median {statistics.median(ms):6.0f} ms   p95 {pct(ms, 95):6.0f} ms"
          f"   max {max(ms):6.0f} ms   ({target})")


async def measure(url, server_pid, n_changes, n_sessions, figures=5) -> dict:
    """Run the whole protocol on the page at ``url`` (``figures`` plots, served by process
    ``server_pid``), print each figure and return them (milliseconds; the load in seconds)."""
    out = {}
    async with async_playwright() as p:
        browser = await p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        loads = []
        for _ in range(3):
            page, seconds = await open_page(browser, url, figures)
            loads.append(seconds)
            await page.close()
        out["load"] = statistics.median(loads)
        print(f"{'first page load':<34} n={len(loads):>3}  median {out['load']:6.2f} s    "
              f"max {max(loads):.2f} s   (target ≤ 3 s)")
        page, _ = await open_page(browser, url, figures)
        await run_changes(page, 4)  # warm-up
        out["one"] = await run_changes(page, n_changes)
        report("one session, widget → all plots", out["one"], "target median ≤ 150 ms, p95 ≤ 300 ms")
        await page.close()
        pages = [(await open_page(browser, url, figures))[0] for _ in range(n_sessions)]
        for pg in pages:
            await run_changes(pg, 2)
        # rounds: every session changes a widget at the same moment, then a person's pause
        rounds = []
        server0, chromium0 = cpu_seconds(server_pid), chromium_cpu()
        for _ in range(max(10, n_changes // 2)):
            rounds += await asyncio.gather(*(run_changes(pg, 1) for pg in pages))
            await asyncio.sleep(0.5)
        server1, chromium1 = cpu_seconds(server_pid), chromium_cpu()
        out["many"] = [v for r in rounds for v in r]
        report(f"{n_sessions} sessions, simultaneous rounds", out["many"], "target p95 ≤ 500 ms")
        n = len(out["many"])
        out["cpu"] = {"server": 1000 * (server1 - server0) / n}
        out["cpu"].update({k: 1000 * (chromium1[k] - chromium0.get(k, 0.0)) / n for k in sorted(chromium1)
                           if chromium1[k] - chromium0.get(k, 0.0) > 0})
        print(f"{'  CPU per change (ms)':<34} " + ", ".join(f"{k} {v:.0f}" for k, v in out["cpu"].items()))
        # at a person's own pace: each session waits 0.5–1.5 s (its own seeded draws) between
        # changes, so changes overlap as they come, not all at one moment
        async def own_pace(page, rng):
            out = []
            for _ in range(max(5, n_changes // 4)):
                await asyncio.sleep(rng.uniform(0.5, 1.5))
                out += await run_changes(page, 1)
            return out

        paced = await asyncio.gather(*(own_pace(pg, random.Random(i)) for i, pg in enumerate(pages)))
        report(f"{n_sessions} sessions, each at its own pace", [v for r in paced for v in r], "for reference")
        # back to back: each session changes again as soon as its plots are drawn (saturation)
        results = await asyncio.gather(*(run_changes(pg, max(10, n_changes // 2)) for pg in pages))
        report(f"{n_sessions} sessions, back to back", [v for r in results for v in r], "saturation, for reference")
        await browser.close()
    return out


def ratios(name: str, a: dict, b: dict):
    """Print ``a`` / ``b`` for each figure of :func:`measure`."""
    print(f"{name}:")
    print(f"  first page load {a['load'] / b['load']:.2f}")
    for which in ("one", "many"):
        for label, f in (("median", statistics.median), ("p95", lambda v: pct(v, 95))):
            print(f"  {which} session{'s' if which == 'many' else ''} {label} {f(a[which]) / f(b[which]):.2f}")
    total = sum(a["cpu"].values()), sum(b["cpu"].values())
    print(f"  CPU per change {total[0]:.0f} / {total[1]:.0f} ms = {total[0] / total[1]:.2f}")


async def main(n_changes, n_sessions, query=""):
    port = free_port()
    server = start_server(port)
    try:
        await measure(f"http://localhost:{port}/" + (f"?{query}" if query else ""), server.pid, n_changes, n_sessions)
    finally:
        server.terminate()
        server.wait(10)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--changes", type=int, default=40)
    ap.add_argument("--sessions", type=int, default=10)
    ap.add_argument("--query", default="", help="a link's query, e.g. tol=mu:10,L:1&bands=true")
    a = ap.parse_args()
    asyncio.run(main(a.changes, a.sessions, a.query))
