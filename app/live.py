"""Live HoloViews plots: built by HoloViews, then updated with data only.

A :class:`LivePlot` shows a list of HoloViews overlays, one plot each (a DynamicMap on a Pipe
stream). HoloViews builds each plot: its dimensions, styles, legend, linked axes and tap
stream. :meth:`LivePlot.show` then takes the next frames:

* a frame of the same shape as the one shown (the same elements, styles and dimension names;
  other numbers, and other dimension labels and units after a mode switch) is written straight
  into the Bokeh models HoloViews made (:func:`app.patches.written`: each changed element's
  columns, as HoloViews' own ``get_data`` makes them, a marker's position, the axis ranges, the
  axis labels and the hover tooltips' words), and the Pipe keeps it without an event.
  HoloViews' per-update path, which recomputes every subplot's ranges, styles, legend and axes,
  is not taken: measured on the explorer, the server's CPU per amplitude change fell from 82 ms
  to 31 ms, per mode switch from 95 ms to 30 ms (``benchmarks/mode_switch_cpu.py``);
* a frame of another shape (a pinned reference, measured points, bands switched on) goes down
  the Pipe: HoloViews updates the Bokeh models in place; an overlay that gains an element gets a
  new glyph and legend entry, one that loses it hides them.

The page is never laid out again. Three costs that were measured here and are avoided
(explorer, Chromium, this machine):

* **Unchanged data are not re-sent.** An element whose data equal the previous frame's is
  replaced by the previous element itself; HoloViews then keeps the glyph's data source as it is
  (it compares the element's plot id), and the browser repaints only what changed.
* **One document freeze per change, and no model walk after it unless models were added**
  (:func:`one_change`). Each HoloViews plot update freezes the Bokeh document, and every
  unfreeze walks the whole document to recompute its models (measured: a third of the server's
  time per change with five plots, each walk 24 ms). Inside one outer freeze
  (:func:`app.patches.frozen_models`) the plots' own freezes walk nothing, and the outer one
  walks only if the change added or removed models; one ``hold`` sends every change in one
  message.
* **No WebGL** (:func:`app.plotting.style.canvas`, a hook of every plot).
"""

from __future__ import annotations

import contextlib
import logging
import warnings
from collections.abc import Callable

import holoviews as hv
import numpy as np
import panel as pn

from . import patches
from .plotting.style import style_key

log = logging.getLogger("bushing.app")


def _axes(element: hv.Element) -> list:
    return [(d.name, d.label, d.unit, tuple(d.range)) for d in element.dimensions()]


def _same_data(a: hv.Element, b: hv.Element) -> bool:
    """Whether two elements of the same kind hold the same values in the same columns, on the same
    axes (names, units and ranges: the ranges are set per element, and an element kept with an
    earlier range would widen its plot's axis to it). The value columns are compared first: after a
    change of the design they differ, and the comparison stops there."""
    if a is b:
        return True
    if type(a) is not type(b) or a.label != b.label or a.group != b.group:
        return False
    if isinstance(a, (hv.VLine, hv.HLine)):
        return a.data == b.data and _axes(a) == _axes(b)
    dims_a = a.dimensions()
    if _axes(a) != _axes(b) or len(a) != len(b):
        return False
    for i in reversed(range(len(dims_a))):
        x, y = a.dimension_values(i), b.dimension_values(i)
        if x.dtype.kind == "f" and y.dtype.kind == "f":
            if not np.array_equal(x, y, equal_nan=True):
                return False
        elif not np.array_equal(x, y):
            return False
    return True


def _shape(overlay) -> tuple | None:
    """What HoloViews builds a plot from, numbers and words aside: each element's kind, key,
    style (:func:`app.plotting.style.style_key`: the elements are clones of styled templates) and
    dimension names. Two frames of one shape differ in their numbers (data, ranges, a marker) and
    in the words of their dimensions only (labels and units, after a mode switch: the axis labels
    and the tooltips' words)."""
    if not isinstance(overlay, hv.Overlay):
        return None
    return tuple((type(el), key, style_key(el), tuple(d.name for d in el.dimensions()))
                 for key, el in overlay.data.items())


def same_shape(old, new) -> bool:
    """Whether overlays ``old`` and ``new`` differ in their numbers and dimension words only
    (:func:`_shape`)."""
    shape = _shape(old)
    return shape is not None and shape == _shape(new)


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
    if all(i is n for i, n in zip(items, new.values())):
        return new  # nothing to take from old (unchanged elements came as the same objects): no new overlay
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
        self.dmaps, self.tap_streams = [], []
        for i in range(len(overlays)):
            streams = [self.pipe]
            if i in self.taps:
                # among the DynamicMap's own streams, HoloViews links the Tap to the plot of the
                # overlay the DynamicMap returns (a Tap with the DynamicMap as its source only,
                # it links to nothing)
                tap = hv.streams.Tap(transient=True)
                tap.add_subscriber(lambda x=None, y=None, callback=self.taps[i]: callback(x))
                self.tap_streams.append(tap)
                streams.append(tap)
            self.dmaps.append(hv.DynamicMap(lambda data, x=None, y=None, i=i: data[i], streams=streams))
        return self.dmaps

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

    @classmethod
    def shown(cls, live: LivePlot | None, overlays: list, **kwargs) -> LivePlot:
        """``live`` showing ``overlays``, or a new LivePlot of them (``kwargs`` as the
        constructor's) the first time."""
        if live is None:
            return cls(overlays, **kwargs)
        live.show(overlays)
        return live

    def show(self, overlays: list):
        """Show ``overlays`` (as many as there are plots)."""
        overlays = list(overlays)
        if len(overlays) != len(self.pipe.data):
            raise ValueError(f"{len(overlays)} overlays for {len(self.pipe.data)} plots")
        frames = [reuse_unchanged(old, new) for old, new in zip(self.pipe.data, overlays)]
        if self._write(frames):
            self.pipe.update(data=frames)  # silently: the DynamicMaps read it when next evaluated
        else:
            self.pipe.send(frames)

    def _write(self, frames: list) -> bool:
        """Write ``frames`` straight into the Bokeh models of the shown plots if each differs from
        the frame shown in its numbers only (:func:`app.patches.written`); False, with nothing
        written, if any plot must be updated by HoloViews (a new shape, or a plot not yet shown)."""
        pairs = []
        for pane, old, new in zip(self.panes, self.pipe.data, frames):
            if new is old:
                continue
            plots = patches.holoviews_plots(pane)
            if not plots or not same_shape(old, new):
                return False
            pairs += [(plot, old, new) for plot in plots]
        checked = [patches.written(plot, old, new) for plot, old, new in pairs]
        if not all(checked):
            return False
        for write in checked:
            write()
        return True


@contextlib.contextmanager
def one_change():
    """Hold the document (every change goes to the browser in one message) and freeze its
    models (recomputed at the end, once and only if models were added or removed, instead of
    after each plot's update)."""
    doc = pn.state.curdoc
    if doc is None:
        yield
        return
    with pn.io.hold(doc), patches.frozen_models(doc):
        yield


def update_or_keep(what: str, update) -> None:
    """Run ``update`` as :func:`one_change`. It never raises: an unexpected error keeps what is
    shown and is logged in one line, saying ``what`` was kept."""
    try:
        with one_change(), warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")  # numbers are checked where they are made; no warning in the log
            update()
    except Exception as exc:  # noqa: BLE001 - keep the last view, say what happened
        log.warning("%s: %s: %s", what, type(exc).__name__, exc)
