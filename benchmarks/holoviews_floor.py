"""The floor under the explorer with HoloViews: the same protocol on a bare HoloViews page.

    python benchmarks/holoviews_floor.py [--changes 30] [--sessions 10] [--explorer] [--bokeh]

Serves a bare Panel page of five HoloViews plots laid out as the explorer's (one wide, then
pairs), each an Overlay of five 200-point Curves on a log x-axis, and two sliders titled as the
explorer's: "Shear modulus" redraws every plot, "Drive amplitude" three (as the explorer's loop
and its two plots against frequency). It is built the fastest way found here, the way the
explorer is built (:mod:`app.live`): each plot a DynamicMap on a Pipe, canvas not WebGL,
framewise axes on the elements, every change inside one ``hold`` and one document freeze. No
legends, toolbars, hover, taps or text: whatever the explorer adds, it cannot be faster than this.

It then runs ``app_latency.py``'s protocol on it in the same Chromium. ``--explorer`` then
measures the explorer back to back and prints explorer / HoloViews floor; ``--bokeh`` also runs
``bokeh_floor.py``'s bare Bokeh page, so the three stand side by side.
"""

from __future__ import annotations

import argparse
import asyncio
import sys

import numpy as np
from app_latency import free_port, measure, ratios, start_server

N_CURVES, N_POINTS = 5, 200


def floor_session(n_figures: int):
    import holoviews as hv
    import panel as pn

    from app.live import one_change

    hv.renderer("bokeh").webgl = False
    mu = pn.widgets.FloatSlider(name="Shear modulus µ (MPa)", start=0.5, end=5.0, step=1e-4, value=2.0)
    amp = pn.widgets.FloatSlider(name="Drive amplitude (mm)", start=-3.0, end=0.0, step=1e-4, value=-1.5)
    x = np.logspace(-1, 2, N_POINTS)
    f = hv.Dimension("frequency_hz", label="Frequency", unit="Hz")
    options = {"logx": True, "framewise": True, "responsive": True, "height": 300, "toolbar": None,
               "show_legend": False}

    # styled once, cloned with new data per frame (a clone keeps its options: no lookup per frame)
    curve = hv.Curve([], f, "q").opts(framewise=True)
    plot = hv.Overlay([]).opts(**options)
    ys = [hv.Dimension(f"q{i}", label=f"Quantity {i}") for i in range(n_figures)]

    def overlay(i):
        curves = [curve.clone((x, mu.value * (1 + k) * np.log1p(x * (i + 1)) / (1 + 10**amp.value * x)),
                              kdims=[f], vdims=[ys[i]]) for k in range(N_CURVES)]
        return plot.clone(curves)

    pipes = [hv.streams.Pipe(data=overlay(i)) for i in range(n_figures)]
    panes = [pn.pane.HoloViews(hv.DynamicMap(lambda data: data, streams=[p]), sizing_mode="stretch_width",
                               linked_axes=False) for p in pipes]

    def send(n_changed):
        with one_change():
            for i, pipe in enumerate(pipes[:n_changed]):
                pipe.send(overlay(i))

    mu.param.watch(lambda _e: send(n_figures), "value")
    amp.param.watch(lambda _e: send(min(3, n_figures)), "value")
    pairs = [pn.Row(*panes[i:i + 2], sizing_mode="stretch_width") for i in range(1, n_figures, 2)]
    return pn.Row(pn.Column(mu, amp, width=360), pn.Column(panes[0], *pairs, sizing_mode="stretch_width"),
                  sizing_mode="stretch_width")


def serve_floor(port: int, n_figures: int):
    import panel as pn

    pn.extension(throttled=False)
    pn.serve(lambda: floor_session(n_figures), port=port, address="localhost", show=False,
             websocket_origin=[f"localhost:{port}"], liveness=True, verbose=False)


async def run(command, probe, url_note, n_changes, n_sessions, n_figures):
    port = free_port()
    server = start_server(port, [c.replace("PORT", str(port)) for c in command] if command else None, probe=probe)
    try:
        print(url_note)
        return await measure(f"http://localhost:{port}/", server.pid, n_changes, n_sessions, n_figures)
    finally:
        server.terminate()
        server.wait(10)


async def main(n_figures, n_changes, n_sessions, explorer, bokeh):
    here = [sys.executable, __file__, "--figures", str(n_figures), "--serve", "PORT"]
    floor = await run(here, "/liveness", f"bare HoloViews page, {n_figures} plots:", n_changes, n_sessions, n_figures)
    if bokeh:
        bare = [sys.executable, str(__file__).replace("holoviews_floor", "bokeh_floor"), "--figures", str(n_figures),
                "--serve", "PORT"]
        plain = await run(bare, "/", f"bare Bokeh page, {n_figures} plots:", n_changes, n_sessions, n_figures)
        ratios("HoloViews floor / Bokeh floor", floor, plain)
    if explorer:
        app = await run(None, "/liveness", "the explorer:", n_changes, n_sessions, 5)
        ratios("explorer / HoloViews floor", app, floor)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--figures", type=int, default=5)
    ap.add_argument("--changes", type=int, default=30)
    ap.add_argument("--sessions", type=int, default=10)
    ap.add_argument("--explorer", action="store_true")
    ap.add_argument("--bokeh", action="store_true")
    ap.add_argument("--serve", type=int, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.serve:
        serve_floor(a.serve, a.figures)
    else:
        asyncio.run(main(a.figures, a.changes, a.sessions, a.explorer, a.bokeh))
