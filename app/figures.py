"""Bokeh figures that update by replacing data only.

Why not HoloViews DynamicMaps here: measured in Chromium on this machine, re-rendering the
explorer's five plots through DynamicMaps took a median 0.6 s from a widget change to the last
plot drawn (each update re-sent layout properties, and every one re-laid the page out). These
figures are built once per session; an update replaces the data of their ColumnDataSources
(batched in one message) and never touches layout, so the browser only redraws. Axes carry a
name, label and unit once (:class:`Axis`); figures that share a quantity share a range
(:class:`AutoRange`), so their axes are linked.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from bokeh import events
from bokeh.core.properties import value
from bokeh.models import (
    CDSView,
    ColorBar,
    ColumnDataSource,
    CustomJS,
    HoverTool,
    IndexFilter,
    Legend,
    LegendItem,
    Range1d,
    SaveTool,
    Span,
)
from bokeh.plotting import figure


@dataclass(frozen=True)
class Axis:
    """A plotted quantity: its name, its label and its unit."""

    name: str
    label: str
    unit: str = ""

    @property
    def title(self) -> str:
        return f"{self.label} ({self.unit})" if self.unit else self.label


X_COLUMNS = ("x", "xs")
Y_COLUMNS = ("y", "ys", "y1", "y2")
RAGGED = ("xs", "ys")  # a list of arrays (multi_line)


def padded(low: float, high: float, log: bool) -> tuple[float, float]:
    """The range Bokeh's DataRange1d would give data from ``low`` to ``high``: 10 % more than the
    span (in log10 on a log axis), or a span of 2 (two decades) around a single value."""
    if log:
        low, high = np.log10(low), np.log10(high)
    centre = (low + high) / 2
    half = (high - low) * (1 + AutoRange.PADDING) / 2 if high > low else AutoRange.DEFAULT_SPAN / 2
    start, end = centre - half, centre + half
    return (float(10**start), float(10**end)) if log else (float(start), float(end))


class AutoRange:
    """A Bokeh Range1d that the server fits to the data of every figure sharing it, padded as a
    DataRange1d would be.

    Why not a DataRange1d: BokehJS fits those while it paints, and a range that changes then
    asks every plot on it to paint again and sends itself back to the server. Measured in
    Chromium, every plot of the explorer painted twice per material change. Fitted here, the
    ranges travel in the same message as the data and each plot paints once. A zoom or pan by the
    user is kept (later data do not move the view) until the plot's reset tool, which returns to
    the newest fit, or until the axis changes its quantity."""

    PADDING = 0.1
    DEFAULT_SPAN = 2.0

    def __init__(self, start: float | None = None, end: float | None = None):
        self.fixed = start is not None and end is not None
        self.range = Range1d(start=0.0 if start is None else start, end=1.0 if end is None else end)
        self.log: bool | None = None
        self.zoomed = False
        self._members: list[tuple[Figure, str]] = []
        self._fit = (self.range.start, self.range.end)
        self._setting = False
        self.range.on_change("start", self._moved)
        self.range.on_change("end", self._moved)

    def attach(self, fig: Figure, dim: str, log: bool):
        if self.log is not None and self.log != log:
            raise ValueError("figures that share a range must share its scale (linear or log)")
        self.log = log
        self._members.append((fig, dim))

    def _moved(self, _attr, _old, _new):
        """A change from the browser (zoom, pan or reset): zoomed unless back on the fit."""
        if not self._setting:
            self.zoomed = (self.range.start, self.range.end) != self._fit

    def fit(self):
        """Refit to the members' data (nothing to do for a fixed range or no data)."""
        if self.fixed:
            return
        extents = [e for fig, dim in self._members if (e := fig.extent(dim)) is not None]
        if not extents:
            return
        fit = padded(min(e[0] for e in extents), max(e[1] for e in extents), bool(self.log))
        if fit == self._fit and (self.zoomed or (self.range.start, self.range.end) == fit):
            return
        self._fit = fit
        changes = {"reset_start": fit[0], "reset_end": fit[1]}
        if not self.zoomed:
            changes.update(start=fit[0], end=fit[1])
        self._setting = True
        try:
            self.range.update(**changes)
        finally:
            self._setting = False

    def unzoom(self):
        self.zoomed = False
        self._fit = (None, None)
        self.fit()


def _range(spec) -> AutoRange:
    """An :class:`AutoRange` from None (a new one), a (start, end) pair (fixed) or itself."""
    if spec is None:
        return AutoRange()
    if isinstance(spec, AutoRange):
        return spec
    start, end = spec
    return AutoRange(start, end)


# After a legend click (the event comes before the legend toggles the proxy, hence the
# microtask): each glyph takes its proxy's visibility; a multi_line shows the lines whose
# proxies are visible.
FOLLOW_PROXIES = """
queueMicrotask(() => {
  proxies.forEach((proxy, i) => { if (targets[i].visible != proxy.visible) targets[i].visible = proxy.visible })
  filters.forEach((filter, i) => { filter.indices = line_proxies[i].flatMap((p, k) => p.visible ? [k] : []) })
})
"""


def _same_data(old: dict, new: dict) -> bool:
    """Whether two sources' data are the same columns of the same values (NaN equal to NaN)."""
    if old.keys() != new.keys():
        return False
    for name, b in new.items():
        a = old[name]
        if name in RAGGED:
            if len(a) != len(b) or not all(_same_column(x, y) for x, y in zip(a, b)):
                return False
        elif not _same_column(a, b):
            return False
    return True


def _same_column(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype.kind != b.dtype.kind:
        return False
    return bool(np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))


class Figure:
    """A titled Bokeh figure of named lines and bands, an optional operating-point marker and
    a legend; :meth:`set` replaces one glyph's data."""

    def __init__(
        self,
        title: str,
        x: Axis,
        y: Axis,
        *,
        x_log: bool = False,
        y_log: bool = False,
        x_range: AutoRange | tuple[float, float] | None = None,
        y_range: AutoRange | tuple[float, float] | None = None,
        height: int = 300,
        png: str = "bushing-plot",
        legend: str | None = "right",
        marker: bool = False,
        hover: bool = True,
    ):
        self.x, self.y = x, y
        self.ranges = {"x": _range(x_range), "y": _range(y_range)}
        self.fig = figure(
            title=title,
            x_axis_type="log" if x_log else "linear",
            y_axis_type="log" if y_log else "linear",
            x_range=self.ranges["x"].range,
            y_range=self.ranges["y"].range,
            height=height,
            sizing_mode="stretch_width",
            tools="pan,wheel_zoom,box_zoom,reset",
            toolbar_location="right",
            min_border_left=60,
        )
        self.fig.add_tools(SaveTool(filename=png))
        self.fig.title.text_font_size = "13px"
        self.fig.toolbar.logo = None
        self.fig.xaxis.axis_label = x.title
        self.fig.yaxis.axis_label = y.title
        for dim, rng in self.ranges.items():
            rng.attach(self, dim, {"x": x_log, "y": y_log}[dim])
        self.sources: dict[str, ColumnDataSource] = {}
        self.renderers = {}
        self._extents: dict[str, dict[str, tuple[float, float] | None]] = {}
        self._line_colors: dict[str, list[str]] = {}
        self._items: dict[str, list[LegendItem]] = {}
        self.legend = None
        # the one NaN point that every legend proxy of this figure draws (one source, not one each)
        self._proxy_source = ColumnDataSource({c: [np.nan] for c in ("x", "y", "y1", "y2")})
        if legend:
            self.legend = Legend(items=[], location="top_left" if legend == "inside" else "center",
                                 click_policy="hide", label_text_font_size="11px",
                                 spacing=0, padding=4, margin=4)
            self.fig.add_layout(self.legend, "right" if legend == "right" else "center")
            self._follow = {"proxies": [], "targets": [], "filters": [], "line_proxies": []}
            self._click = CustomJS(args=dict(self._follow), code=FOLLOW_PROXIES)
            self.legend.js_on_event("legend_item_click", self._click)
        self.marker = None
        if marker:
            # On the overlay layer: moving it repaints that layer alone, not the plot under it.
            self.marker = Span(location=0.0, dimension="height", line_color="#e6550d",
                               line_dash="dotted", line_width=1.5, level="overlay")
            self.fig.add_layout(self.marker)
        if hover:
            self.fig.add_tools(HoverTool(
                tooltips=[(x.label, f"$x{{%.4g}} {x.unit}"), (y.label, f"$y{{%.4g}} {y.unit}")],
                formatters={"$x": "printf", "$y": "printf"},
                mode="mouse",
            ))

    def _glyph(self, key: str, columns: tuple, draw, label: str | None):
        """``draw(source)`` on a new empty source of ``columns``, in the legend under ``label``."""
        src = ColumnDataSource({c: [] for c in columns})
        self.sources[key] = src
        self.renderers[key] = draw(src)
        if label is not None and self.legend is not None:
            proxy = draw(self._proxy_source)
            self._follow["proxies"].append(proxy)
            self._follow["targets"].append(self.renderers[key])
            self._add_item(key, label, proxy)
        return self.renderers[key]

    def _add_item(self, key: str, label: str, proxy):
        """A legend entry drawn by ``proxy``, a renderer styled like the real one whose one
        point is NaN: nothing in the plot, but a swatch in the legend (BokehJS draws none for
        a renderer without data).

        Why a proxy: BokehJS rebuilds a legend's entries whenever anything reachable from them
        changes, the data of their renderers included; measured in Chromium, that made the
        legends the largest cost of an update. A proxy's data never change, so the legend is
        built once; clicking an entry hides the proxy, and the legend's click callback (which
        the legend does not watch) makes the real glyphs follow their proxies."""
        item = LegendItem(label=value(label), renderers=[proxy])
        self.legend.items.append(item)
        self._items.setdefault(key, []).append(item)
        self._click.args = dict(self._follow)

    def line(self, key: str, label: str | None = None, **style):
        return self._glyph(key, ("x", "y"), lambda src: self.fig.line("x", "y", source=src, **style), label)

    def points(self, key: str, label: str | None = None, **style):
        """Markers (measured data)."""
        return self._glyph(key, ("x", "y"), lambda src: self.fig.scatter("x", "y", source=src, **style), label)

    def coloured_points(self, key: str, **style):
        """Markers each with its own colour (a ``color`` column), e.g. one colour per group."""
        return self._glyph(key, ("x", "y", "color"),
                           lambda src: self.fig.scatter("x", "y", source=src, color="color", **style), None)

    def mapped_points(self, key: str, mapper, title: str, **style):
        """Markers coloured by a ``value`` column through a Bokeh colour mapper, with a colour bar."""
        renderer = self._glyph(key, ("x", "y", "value"), lambda src: self.fig.scatter(
            "x", "y", source=src, fill_color={"field": "value", "transform": mapper}, line_color="#777777",
            line_width=0.5, **style), None)
        self.fig.add_layout(ColorBar(color_mapper=mapper, title=title, width=10, title_text_font_size="11px",
                                     major_label_text_font_size="10px"), "right")
        return renderer

    def band(self, key: str, label: str | None = None, **style):
        return self._glyph(key, ("x", "y1", "y2"),
                           lambda src: self.fig.varea("x", "y1", "y2", source=src, **style), label)

    def lines(self, key: str, labels: list[str], colors: list[str], **style):
        """Several lines in one glyph and one source (one patch per update), each in the legend;
        clicking an entry hides that line alone (an index filter on the glyph's view)."""
        renderer = self._glyph(key, ("xs", "ys", "color"), lambda src: self.fig.multi_line(
            "xs", "ys", source=src, line_color="color", **style), None)
        self._line_colors[key] = list(colors)
        if self.legend is not None and labels:
            shown = IndexFilter(indices=list(range(len(labels))))
            renderer.view = CDSView(filter=shown)
            proxies = [self.fig.line("x", "y", source=self._proxy_source, line_color=colors[i % len(colors)], **style)
                       for i in range(len(labels))]
            self._follow["filters"].append(shown)
            self._follow["line_proxies"].append(proxies)
            for label, proxy in zip(labels, proxies):
                self._add_item(key, label, proxy)
        return renderer

    def set_lines(self, key: str, x, ys, labels: list[str] = (), *, each_x=None):
        """Replace the lines of :meth:`lines`, all on ``x`` (or each on its own: ``each_x``, one
        array per line, with ``x`` None), and relabel them if needed."""
        colors = self._line_colors[key]
        xs = [np.asarray(v, dtype=float) for v in each_x] if each_x is not None else [np.asarray(x, dtype=float)] * len(ys)
        data = {
            "xs": xs,
            "ys": [np.asarray(y, dtype=float) for y in ys],
            "color": [colors[i % len(colors)] for i in range(len(ys))],
        }
        self._send(key, data)
        items = self._items.get(key, [])
        for item, label in zip(items, labels):
            if getattr(item.label, "value", item.label) != label:
                item.label = value(label)

    def set(self, key: str, **columns):
        """Replace one glyph's data (numbers; a ``color`` column stays text)."""
        data = {k: list(v) if k == "color" else np.asarray(v, dtype=float) for k, v in columns.items()}
        self._send(key, data)

    def _send(self, key: str, data: dict):
        """Give one glyph new data, unless they equal what it has: the browser repaints a plot
        whenever a source of it changes, even to the same numbers."""
        if _same_data(self.sources[key].data, data):
            return
        self.sources[key].data = data
        self._record(key, data)

    def _record(self, key: str, data: dict):
        """Keep the extent of one glyph's data and refit this figure's ranges to it."""
        self._extents[key] = {}
        for dim, names in (("x", X_COLUMNS), ("y", Y_COLUMNS)):
            parts = [np.ravel(np.asarray(v, dtype=float)) for n in names if n in data
                     for v in (data[n] if n in RAGGED else [data[n]])]
            values = np.concatenate(parts) if parts else np.empty(0)
            values = values[np.isfinite(values) & ((values > 0) if self.ranges[dim].log else True)]
            self._extents[key][dim] = (float(values.min()), float(values.max())) if values.size else None
        for rng in self.ranges.values():
            rng.fit()

    def extent(self, dim: str) -> tuple[float, float] | None:
        """The smallest and largest finite value (positive, on a log axis) of all this figure's
        data along ``dim`` ("x" or "y"), or None without data."""
        found = [e[dim] for e in self._extents.values() if e.get(dim) is not None]
        if not found:
            return None
        return min(lo for lo, _ in found), max(hi for _, hi in found)

    def clear(self, key: str):
        self.set(key, **{k: [] for k in self.sources[key].data})

    def set_axes(self, x: Axis, y: Axis):
        """Change the axis titles (the mode changes units); sent only when they change."""
        if self.fig.xaxis[0].axis_label != x.title:
            self.fig.xaxis.axis_label = x.title
            self.ranges["x"].unzoom()
        if self.fig.yaxis[0].axis_label != y.title:
            self.fig.yaxis.axis_label = y.title
            self.ranges["y"].unzoom()
        self.x, self.y = x, y

    def set_marker(self, value: float):
        if self.marker is not None and self.marker.location != value:
            self.marker.location = float(value)

    def on_tap(self, callback):
        """``callback(x)`` with the data x of a tap (click) on the plot."""
        self.fig.on_event(events.Tap, lambda event: callback(event.x))
