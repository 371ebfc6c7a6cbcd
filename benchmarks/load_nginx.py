"""A classroom through nginx: many sessions at a person's pace. Prints figures, asserts nothing.

    python benchmarks/load_nginx.py [--sessions 30] [--processes 1 2] [--changes 6]

For each number of server processes: starts that many `bushing serve` processes on this machine,
the Debian nginx in front of them (``deploy/nginx.conf.template``: sticky by a route cookie), and
one Chromium with ``--sessions`` pages, each its own context and route. Every page loads the
explorer through nginx, then changes a widget ``--changes`` times with a pause of 0.5–1.5 s
(seeded) before each change, as a person does. Prints the page loads, the p50/p95 time from a
change to every plot redrawn, the changes that never completed (errors) and the sessions that
lost their server (dropped), and which process served how many sessions.

Everything runs on this one two-core machine: the server processes, nginx and every page. The
figures measure this machine shared by all of them; users on their own machines would bring
their own browsers' CPU.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import random
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from app_latency import ARGS, CHANGE_JS, CHROMIUM, free_port, pct, start_server
from playwright.async_api import async_playwright

from app.deploy import nginx_config

NGINX = shutil.which("nginx") or "/usr/sbin/nginx"
TIME_LIMIT_S = 600  # per configuration: the script stops by itself


async def session(browser, url, route, n_changes, rng, out):
    context = await browser.new_context(viewport={"width": 1400, "height": 1100})
    await context.add_cookies([{"name": "bushing_route", "value": route, "url": url}])
    page = await context.new_page()
    t0 = time.perf_counter()
    try:
        await page.goto(url, timeout=120000)
        await page.wait_for_function("() => window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle",
                                     timeout=120000, polling=50)
    except Exception:  # noqa: BLE001 - a page that never loaded is a dropped session
        out["dropped"] += 1
        await context.close()
        return
    out["loads"].append(time.perf_counter() - t0)
    for i in range(n_changes):
        await asyncio.sleep(rng.uniform(0.5, 1.5))
        title, value = (("Shear modulus µ (MPa)", round(2.0 + 0.013 * i + rng.random() * 1e-3, 6)) if i % 2 == 0
                        else ("Drive amplitude (mm)", round(-1.5 + 0.02 * i + rng.random() * 1e-3, 6)))
        try:
            ms = await page.evaluate(CHANGE_JS, [title, value, 150])
        except Exception:  # noqa: BLE001 - the page or its connection is gone
            out["dropped"] += 1
            break
        if ms is None:
            out["errors"] += 1
        else:
            out["changes"].append(ms)
    await context.close()


async def run(n_processes, n_sessions, n_changes):
    with tempfile.TemporaryDirectory() as tmp:
        front = free_port()
        backs = [free_port() for _ in range(n_processes)]
        os.environ["BUSHING_ALLOWED_ORIGINS"] = f"127.0.0.1:{front},localhost:{front}"  # pages come via nginx
        servers = [start_server(p) for p in backs]
        conf = Path(tmp) / "nginx.conf"
        conf.write_text(nginx_config(front, backs, Path(tmp)))
        nginx = subprocess.Popen([NGINX, "-c", str(conf), "-p", tmp, "-g", "daemon off;"],  # noqa: ASYNC220 - returns at once
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        url = f"http://127.0.0.1:{front}/"
        out = {"loads": [], "changes": [], "errors": 0, "dropped": 0}
        try:
            await asyncio.sleep(1.0)  # nginx listening
            async with async_playwright() as p:
                browser = await p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
                tasks = [session(browser, url, f"route-{i}", n_changes, random.Random(i), out) for i in range(n_sessions)]
                await asyncio.wait_for(asyncio.gather(*tasks), TIME_LIMIT_S)
                await browser.close()
        finally:
            nginx.terminate()
            nginx.wait(10)
            for s in servers:
                s.terminate()
                s.wait(10)
        log = (Path(tmp) / "access.log").read_text().splitlines() if (Path(tmp) / "access.log").exists() else []
        per_process = Counter(line.split()[0] for line in log if "/ws" in line and line.split()[1] == "101")
    changes = out["changes"]
    print(f"{n_processes} process{'es' if n_processes > 1 else ''}, {n_sessions} sessions through nginx:")
    if out["loads"]:
        print(f"  page load            median {statistics.median(out['loads']):6.1f} s   max {max(out['loads']):6.1f} s")
    if changes:
        print(f"  change → plots drawn p50 {statistics.median(changes):6.0f} ms   p95 {pct(changes, 95):6.0f} ms   "
              f"n={len(changes)}")
    print(f"  errors (no redraw within 20 s): {out['errors']}   dropped sessions: {out['dropped']}")
    print(f"  websocket sessions per process: {dict(per_process)}")


async def main(sessions, processes, changes):
    for n in processes:
        await run(n, sessions, changes)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--sessions", type=int, default=30)
    ap.add_argument("--processes", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--changes", type=int, default=6)
    a = ap.parse_args()
    if CHROMIUM is None:
        sys.exit("Chromium is not installed (apt-get install -y chromium)")
    asyncio.run(main(a.sessions, a.processes, a.changes))
