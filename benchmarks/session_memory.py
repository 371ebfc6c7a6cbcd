"""Session hygiene: the server's memory over repeated cycles of sessions. Prints figures,
asserts nothing.

    python benchmarks/session_memory.py [--cycles 5] [--sessions 20]

Starts one `bushing serve` process. Each cycle opens ``--sessions`` pages at once in Chromium
(each its own context), changes the design three times on each, opens the "Measured data and
fit" tab and loads the example data there, then closes every page. It then waits the unused-
session lifetime and one check interval (app.main.SESSION_LIFETIME_S + SESSION_CHECK_S, plus
margin) so that the server discards the closed sessions, and reads the server's resident memory
(VmRSS). Memory on a plateau means the sessions' memory is given back: the growth per cycle
after the first cycles is what to read.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import time

from app_latency import ARGS, CHANGE_JS, CHROMIUM, free_port, start_server
from playwright.async_api import async_playwright

from app.main import SESSION_CHECK_S, SESSION_LIFETIME_S

MARGIN_S = 5


def rss_mb(pid: int) -> float:
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


async def one_session(browser, url: str, i: int, cycle: int, failures: list) -> None:
    context = await browser.new_context(viewport={"width": 1400, "height": 1100})
    page = await context.new_page()
    try:
        await page.goto(url, timeout=120000)
        await page.wait_for_function("() => window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle",
                                     timeout=120000, polling=100)
        for k in range(3):
            value = round(2.0 + 0.01 * k + 0.001 * i + 0.0001 * cycle, 6)
            if await page.evaluate(CHANGE_JS, ["Shear modulus µ (MPa)", value, 150]) is None:
                failures.append(f"session {i}: change {k} not drawn")
        await page.get_by_text("Measured data and fit", exact=True).click()
        await page.get_by_role("button", name="Load the synthetic Paper B example").click(timeout=60000)
        await page.get_by_text("150 points").first.wait_for(timeout=60000)
    except Exception as exc:  # noqa: BLE001 - reported, the cycle goes on
        failures.append(f"session {i}: {type(exc).__name__}")
    finally:
        await context.close()


async def main(cycles: int, sessions: int) -> None:
    port = free_port()
    server = start_server(port)
    url = f"http://localhost:{port}/"
    wait = SESSION_LIFETIME_S + SESSION_CHECK_S + MARGIN_S
    print(f"one server process; {cycles} cycles of {sessions} sessions; after each, {wait} s for closed "
          f"sessions to be discarded (lifetime {SESSION_LIFETIME_S} s, checked every {SESSION_CHECK_S} s)")
    try:
        print(f"  started:         RSS {rss_mb(server.pid):7.1f} MB")
        rows = []
        async with async_playwright() as p:
            browser = await p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            for cycle in range(1, cycles + 1):
                failures: list[str] = []
                t0 = time.perf_counter()
                await asyncio.gather(*(one_session(browser, url, i, cycle, failures) for i in range(sessions)))
                during = rss_mb(server.pid)
                seconds = time.perf_counter() - t0
                await asyncio.sleep(wait)
                after = rss_mb(server.pid)
                rows.append(after)
                print(f"  cycle {cycle}: {seconds:5.1f} s, RSS {during:7.1f} MB as the pages closed, {after:7.1f} MB "
                      f"after discarding; failures: {len(failures)}" + (f" ({'; '.join(failures[:3])})" if failures else ""))
            await browser.close()
        if len(rows) >= 3:
            tail = rows[1:]
            slope = (tail[-1] - tail[0]) / (len(tail) - 1)
            print(f"after cycle 1: {tail[0]:.1f} MB; after cycle {len(rows)}: {tail[-1]:.1f} MB; "
                  f"growth {slope:+.1f} MB per cycle of {sessions} sessions "
                  f"({slope / sessions * 1000:+.0f} kB per session)")
    finally:
        server.terminate()
        server.wait(10)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=5)
    ap.add_argument("--sessions", type=int, default=20)
    a = ap.parse_args()
    if CHROMIUM is None:
        sys.exit("Chromium is not installed (apt-get install -y chromium)")
    asyncio.run(main(a.cycles, a.sessions))
