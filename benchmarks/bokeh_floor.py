"""The floor under the explorer's latency: plain Bokeh, same protocol. Prints figures.

    python benchmarks/bokeh_floor.py [--figures 5] [--changes 30] [--sessions 10] [--explorer]

Serves a bare Bokeh document (no Panel, no template, no toolbars, legends, hover or text) with
``--figures`` plots laid out as the explorer's (one wide, then pairs), each five curves of 200
points on a log x-axis with ranges fitted by the server, and two sliders titled as the explorer's:
"Shear modulus" replaces every plot's data, "Drive amplitude" three plots' (as the explorer's
loop and its two plots against frequency). It then runs `app_latency.py`'s protocol on it in the
same Chromium, the same way. Whatever the explorer adds, it cannot be faster than this floor, so
the floor says which targets this machine allows for that many plots redrawn per change.

``--explorer`` then measures the explorer, back to back, and prints the ratio explorer / floor.
"""

from __future__ import annotations

import argparse
import asyncio
import sys

import numpy as np
from app_latency import free_port, measure, ratios, start_server

N_CURVES, N_POINTS = 5, 200


def floor_document(doc, n_figures: int):
    from bokeh.layouts import column, row
    from bokeh.models import Range1d, Slider
    from bokeh.plotting import figure

    mu = Slider(title="Shear modulus µ (MPa)", start=0.5, end=5.0, step=1e-4, value=2.0)
    amp = Slider(title="Drive amplitude (mm)", start=-3.0, end=0.0, step=1e-4, value=-1.5)
    x = np.logspace(-1, 2, N_POINTS)
    figs = [figure(x_axis_type="log", height=300, sizing_mode="stretch_width", tools="", toolbar_location=None,
                   x_range=Range1d(x[0], x[-1]), y_range=Range1d(0.0, 1.0)) for _ in range(n_figures)]
    sources = [f.multi_line("xs", "ys", source={"xs": [], "ys": []}).data_source for f in figs]

    def update(n_changed):
        ys_all = []
        for i, source in enumerate(sources[:n_changed]):
            ys = [mu.value * (1 + k) * np.log1p(x * (i + 1)) / (1 + 10**amp.value * x) for k in range(N_CURVES)]
            source.data = {"xs": [x] * N_CURVES, "ys": ys}
            ys_all.append(ys)
        for f, ys in zip(figs, ys_all):
            low, high = float(np.min(ys)), float(np.max(ys))
            f.y_range.update(start=low - 0.05 * (high - low), end=high + 0.05 * (high - low))

    update(n_figures)
    mu.on_change("value", lambda _a, _o, _n: update(n_figures))
    amp.on_change("value", lambda _a, _o, _n: update(min(3, n_figures)))
    pairs = [row(*figs[i:i + 2], sizing_mode="stretch_width") for i in range(1, n_figures, 2)]
    doc.add_root(row(column(mu, amp, width=360), column(figs[0], *pairs, sizing_mode="stretch_width"),
                     sizing_mode="stretch_width"))


def serve_floor(port: int, n_figures: int):
    from bokeh.application import Application
    from bokeh.application.handlers.function import FunctionHandler
    from bokeh.server.server import Server

    handler = FunctionHandler(lambda doc: floor_document(doc, n_figures))
    server = Server({"/": Application(handler)}, port=port, allow_websocket_origin=[f"localhost:{port}"])
    server.start()
    server.io_loop.start()


async def main(n_figures, n_changes, n_sessions, explorer):
    port = free_port()
    command = [sys.executable, __file__, "--serve", str(port), "--figures", str(n_figures)]
    server = start_server(port, command, probe="/")
    try:
        print(f"plain Bokeh, {n_figures} plots:")
        floor = await measure(f"http://localhost:{port}/", server.pid, n_changes, n_sessions, n_figures)
    finally:
        server.terminate()
        server.wait(10)
    if not explorer:
        return
    port = free_port()
    server = start_server(port)
    try:
        print("the explorer:")
        app = await measure(f"http://localhost:{port}/", server.pid, n_changes, n_sessions)
    finally:
        server.terminate()
        server.wait(10)
    ratios("explorer / floor", app, floor)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--figures", type=int, default=5)
    ap.add_argument("--changes", type=int, default=30)
    ap.add_argument("--sessions", type=int, default=10)
    ap.add_argument("--explorer", action="store_true")
    ap.add_argument("--serve", type=int, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.serve:
        serve_floor(a.serve, a.figures)
    else:
        asyncio.run(main(a.figures, a.changes, a.sessions, a.explorer))
