"""Small helpers shared by tests that start a server."""

import socket
import time
import urllib.request


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(url: str, timeout: float = 30.0) -> bytes:
    """The body of ``url`` once it answers 200; fails after ``timeout`` seconds."""
    deadline = time.time() + timeout
    while True:
        try:
            with urllib.request.urlopen(url, timeout=5) as r:
                if r.status == 200:
                    return r.read()
        except OSError:
            if time.time() > deadline:
                raise
        time.sleep(0.2)


# ---- what a HoloViews plot holds ------------------------------------------------------------


def element(overlay, label: str):
    """The element of ``overlay`` with ``label`` (each plotted curve has its own)."""
    found = [el for el in overlay if el.label == label]
    assert len(found) == 1, f"{label!r} in {[el.label for el in overlay]}"
    return found[0]


def xy(overlay, label: str):
    """The x and y values of one labelled element of ``overlay``."""
    import numpy as np

    el = element(overlay, label)
    return np.asarray(el.dimension_values(0), dtype=float), np.asarray(el.dimension_values(1), dtype=float)


def marker_at(overlay) -> float:
    """Where the operating-point marker (the overlay's vertical line) stands."""
    import holoviews as hv

    (line,) = [el for el in overlay if isinstance(el, hv.VLine)]
    return float(line.data)


def rendered(viewable):
    """``viewable`` served into a new Bokeh document (as a session would be): the document."""
    from bokeh.document import Document
    from panel.io.state import set_curdoc

    doc = Document()
    with set_curdoc(doc):
        viewable.server_doc(doc)
    return doc


def figures(doc) -> dict:
    """The Bokeh figures of a document by title."""
    from bokeh.models import Plot

    return {m.title.text: m for m in doc.models if isinstance(m, Plot) and m.title is not None}
