"""Live HoloViews plots: DynamicMaps on a Pipe stream, updated with data only.

A :class:`LivePlot` shows a list of HoloViews overlays, one plot each. :meth:`LivePlot.show`
sends new overlays down its Pipe, and HoloViews updates the Bokeh models in place: data, ranges,
axis labels. An overlay that gains an element (a pinned reference, measured points) gets a new
glyph and legend entry from HoloViews; one that loses it hides them. The page is never laid out
again.

Three costs that were measured here and are avoided (explorer, Chromium, this machine):

* **Unchanged data are not re-sent.** An element whose data equal the previous frame's is
  replaced by the previous element itself; HoloViews then keeps the glyph's data source as it is
  (it compares the element's plot id), and the browser repaints only what changed.
* **One document freeze per change** (:func:`send`). Each HoloViews plot update freezes the
  Bokeh document, and every unfreeze walks the whole document to recompute its models (about a
  third of the server's time per change with five plots). Inside one outer freeze, the walk
  happens once, when the last plot has been updated; one ``hold`` sends every change in one
  message.
* **No WebGL** (:mod:`app.plots`).
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable

import holoviews as hv
import numpy as np
import panel as pn

log = logging.getLogger("bushing.app")


def _same_data(a: hv.Element, b: hv.Element) -> bool:
    """Whether two elements of the same kind hold the same values in the same columns."""
    if a is b:
        return True
    if type(a) is not type(b) or a.label != b.label or a.group != b.group:
        return False
    if isinstance(a, (hv.VLine, hv.HLine)):
        return a.data == b.data
    dims_a, dims_b = a.dimensions(), b.dimensions()
    if [(d.name, d.label, d.unit) for d in dims_a] != [(d.name, d.label, d.unit) for d in dims_b] or len(a) != len(b):
        return False
    for i in range(len(dims_a)):
        x, y = a.dimension_values(i), b.dimension_values(i)
        if x.dtype.kind == "f" and y.dtype.kind == "f":
            if not np.array_equal(x, y, equal_nan=True):
                return False
        elif not np.array_equal(x, y):
            return False
    return True


def reuse_unchanged(old: hv.Overlay | hv.Element | None, new: hv.Overlay | hv.Element):
    """``new``, with every element whose data equal the element at the same place in ``old``
    replaced by that old element (so that HoloViews sends none of its data again)."""
    if old is None:
        return new
    if not isinstance(new, hv.Overlay):
        return old if _same_data(old, new) else new
    if not isinstance(old, hv.Overlay) or len(old) != len(new):
        return new
    items = [o if _same_data(o, n) else n for o, n in zip(old.values(), new.values())]
    if all(i is o for i, o in zip(items, old.values())):
        return old
    return new.clone(items)


class LivePlot:
    """Overlays, each a DynamicMap on one shared Pipe, each in its own pane (its own toolbar:
    zoom, reset and a PNG of that plot).

    ``linked``: the plots' axes are linked by Panel's HoloViews pane to every other linked plot
    of the page with the same dimension (label and unit); plots of the same quantity then zoom
    and pan together. ``taps`` maps a plot's index to a callback ``f(x)`` called with the data
    x of a tap (click) on that plot (a HoloViews ``Tap`` stream)."""

    def __init__(self, overlays: list, *, taps: dict[int, Callable] | None = None, linked: bool = False):
        self.taps = dict(taps or {})
        self.panes = [pn.pane.HoloViews(dmap, sizing_mode="stretch_width", linked_axes=linked)
                      for dmap in self._build(list(overlays))]

    def _build(self, overlays: list) -> list:
        self.pipe = hv.streams.Pipe(data=overlays)
        self.dmaps = [hv.DynamicMap(lambda data, i=i: data[i], streams=[self.pipe]) for i in range(len(overlays))]
        self.tap_streams = []
        shown = list(self.dmaps)
        for index, callback in self.taps.items():
            # HoloViews links a Tap stream to an element's plot, not to a DynamicMap of overlays:
            # the stream's source is an empty element overlaid on the plot (no legend, no extent)
            first = overlays[index].get(0)
            anchor = hv.Scatter([], first.kdims, first.vdims)
            tap = hv.streams.Tap(source=anchor, transient=True)
            tap.add_subscriber(lambda x=None, y=None, callback=callback: callback(x))
            self.tap_streams.append(tap)
            options = {**hv.Store.lookup_options("bokeh", overlays[index], "plot").kwargs,
                       **hv.Store.lookup_options("bokeh", overlays[index], "norm").kwargs}
            shown[index] = (self.dmaps[index] * anchor).opts(clone=False, **options)  # the overlay's title, size…
        return shown

    @property
    def pane(self):
        """The pane of a single plot."""
        return self.panes[0]

    def grid(self, cols: int = 2) -> pn.GridBox:
        """The panes in a grid of ``cols`` columns."""
        return pn.GridBox(*self.panes, ncols=cols, sizing_mode="stretch_width")

    @property
    def current(self) -> list:
        """The overlays shown now."""
        return self.pipe.data

    def show(self, overlays: list):
        """Show ``overlays`` (as many as there are plots)."""
        overlays = list(overlays)
        if len(overlays) != len(self.pipe.data):
            raise ValueError(f"{len(overlays)} overlays for {len(self.pipe.data)} plots")
        self.pipe.send([reuse_unchanged(old, new) for old, new in zip(self.pipe.data, overlays)])


@contextlib.contextmanager
def one_change():
    """Hold the document (every change goes to the browser in one message) and freeze its
    models (recomputed once, at the end, instead of after each plot's update)."""
    doc = pn.state.curdoc
    if doc is None:
        yield
        return
    with pn.io.hold(doc), doc.models.freeze():
        yield


def update_or_keep(what: str, update) -> None:
    """Run ``update`` as :func:`one_change`. It never raises: an unexpected error keeps what is
    shown and is logged in one line, saying ``what`` was kept."""
    try:
        with one_change():
            update()
    except Exception as exc:  # noqa: BLE001 - keep the last view, say what happened
        log.warning("%s: %s: %s", what, type(exc).__name__, exc)
