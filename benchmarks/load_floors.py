"""The two floor pages of the protocol-level load client (``load_client.py``), each served by
its own process:

    python benchmarks/load_floors.py one|five

prints ``Floor: http://127.0.0.1:PORT/`` once listening (the OS picks the port) and serves
until stopped. Both pages have one Panel slider titled as the explorer's, "Drive amplitude (mm)"
(a log10 position from -3 to 0, as the explorer's slider), answering at once as the explorer's
does (its value a priority change: no 50 ms debounce):

* ``one``: the bare Panel page, the slider → one ``DynamicMap`` of one 400-point curve;
* ``five``: the plain HoloViews idiom for the explorer's shape, the slider → five ``DynamicMap``
  s, each an overlay of five 200-point curves (the widget bound to each map's callback, as the
  HoloViews and Panel docs show; no Pipe, no frames written into the Bokeh models).
"""

from __future__ import annotations

import sys

import numpy as np

PAGES = ("one", "five")


def _slider():
    import panel as pn

    return pn.widgets.FloatSlider(name="Drive amplitude (mm)", start=-3.0, end=0.0, step=0.005, value=-1.0)


def one_plot():
    """One slider → one DynamicMap curve of 400 points."""
    import holoviews as hv
    import panel as pn

    amp = _slider()
    x = np.logspace(-1, 2, 400)

    def curve(position):
        return hv.Curve((x, np.log1p(x) / (1 + 10**position * x)), "frequency_hz", "q").opts(logx=True)

    plot = hv.DynamicMap(pn.bind(curve, amp))
    return pn.Row(pn.Column(amp, width=360), pn.pane.HoloViews(plot, sizing_mode="stretch_width"))


def five_plots():
    """One slider → five DynamicMaps, each an overlay of five curves of 200 points."""
    import holoviews as hv
    import panel as pn

    amp = _slider()
    x = np.logspace(-1, 2, 200)

    def overlay(position, i):
        return hv.Overlay([hv.Curve((x, (1 + k) * np.log1p(x * (i + 1)) / (1 + 10**position * x)),
                                    "frequency_hz", f"q{i}") for k in range(5)]).opts(logx=True)

    maps = [pn.pane.HoloViews(hv.DynamicMap(pn.bind(overlay, amp, i)), sizing_mode="stretch_width")
            for i in range(5)]
    pairs = [pn.Row(*maps[i:i + 2], sizing_mode="stretch_width") for i in (1, 3)]
    return pn.Row(pn.Column(amp, width=360), pn.Column(maps[0], *pairs, sizing_mode="stretch_width"),
                  sizing_mode="stretch_width")


def serve(page: str):
    """Serve the floor ``page`` (one of PAGES) on 127.0.0.1 at a port the OS picks (blocking)."""
    import panel as pn

    pn.extension(throttled=False)
    pn.widgets.FloatSlider._priority_changes = ["value"]  # answers at once, as the explorer's slider
    build = {"one": one_plot, "five": five_plots}[page]
    server = pn.serve(build, port=0, address="127.0.0.1", show=False, start=False, liveness=True, verbose=False,
                      websocket_origin=["127.0.0.1", "localhost"])
    print(f"Floor: http://127.0.0.1:{server.port}/", flush=True)
    server.start()
    server.io_loop.start()


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in PAGES:
        sys.exit(f"usage: load_floors.py {'|'.join(PAGES)}")
    serve(sys.argv[1])
