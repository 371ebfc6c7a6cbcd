"""Bokeh figures that update by replacing data only.

Why not HoloViews DynamicMaps here: measured in Chromium on this machine, re-rendering the
explorer's five plots through DynamicMaps took a median 0.6 s from a widget change to the last
plot drawn (each update re-sent layout properties, and every one re-laid the page out). These
figures are built once per session; an update replaces the data of their ColumnDataSources
(batched in one message) and never touches layout, so the browser only redraws. Axes carry a
name, label and unit once (:class:`Axis`); figures that share a quantity share a Bokeh range,
so their axes are linked.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from bokeh import events
from bokeh.core.properties import value
from bokeh.models import (
    ColorBar,
    ColumnDataSource,
    DataRange1d,
    HoverTool,
    Legend,
    LegendItem,
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
        x_range=None,
        y_range=None,
        height: int = 300,
        png: str = "bushing-plot",
        legend: str | None = "right",
        marker: bool = False,
        hover: bool = True,
    ):
        self.x, self.y = x, y
        self.fig = figure(
            title=title,
            x_axis_type="log" if x_log else "linear",
            y_axis_type="log" if y_log else "linear",
            x_range=x_range if x_range is not None else DataRange1d(),
            y_range=y_range if y_range is not None else DataRange1d(),
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
        self.sources: dict[str, ColumnDataSource] = {}
        self.renderers = {}
        self._line_colors: dict[str, list[str]] = {}
        self.legend = None
        if legend:
            self.legend = Legend(items=[], location="top_left" if legend == "inside" else "center",
                                 click_policy="hide", label_text_font_size="11px",
                                 spacing=0, padding=4, margin=4)
            self.fig.add_layout(self.legend, "right" if legend == "right" else "center")
        self.marker = None
        if marker:
            self.marker = Span(location=0.0, dimension="height", line_color="#e6550d",
                               line_dash="dotted", line_width=1.5)
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
            self.legend.items.append(LegendItem(label=value(label), renderers=[self.renderers[key]]))
        return self.renderers[key]

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
        """Several lines in one glyph and one source (one patch per update), each in the legend."""
        renderer = self._glyph(key, ("xs", "ys", "color"), lambda src: self.fig.multi_line(
            "xs", "ys", source=src, line_color="color", **style), None)
        self._line_colors[key] = list(colors)
        if self.legend is not None:
            for i, label in enumerate(labels):
                self.legend.items.append(LegendItem(label=value(label), renderers=[renderer], index=i))
        return renderer

    def set_lines(self, key: str, x, ys, labels: list[str]):
        """Replace the lines of :meth:`lines` (all on the same x) and relabel them if needed."""
        colors = self._line_colors[key]
        x = np.asarray(x, dtype=float)
        self.sources[key].data = {
            "xs": [x] * len(ys),
            "ys": [np.asarray(y, dtype=float) for y in ys],
            "color": [colors[i % len(colors)] for i in range(len(ys))],
        }
        items = [it for it in self.legend.items if self.renderers[key] in it.renderers]
        for item, label in zip(items, labels):
            if getattr(item.label, "value", item.label) != label:
                item.label = value(label)

    def set(self, key: str, **columns):
        """Replace one glyph's data (numbers; a ``color`` column stays text)."""
        self.sources[key].data = {k: list(v) if k == "color" else np.asarray(v, dtype=float)
                                  for k, v in columns.items()}

    def clear(self, key: str):
        self.set(key, **{k: [] for k in self.sources[key].data})

    def set_axes(self, x: Axis, y: Axis):
        """Change the axis titles (the mode changes units); sent only when they change."""
        if self.fig.xaxis[0].axis_label != x.title:
            self.fig.xaxis.axis_label = x.title
        if self.fig.yaxis[0].axis_label != y.title:
            self.fig.yaxis.axis_label = y.title
        self.x, self.y = x, y

    def set_marker(self, value: float):
        if self.marker is not None and self.marker.location != value:
            self.marker.location = float(value)

    def on_tap(self, callback):
        """``callback(x)`` with the data x of a tap (click) on the plot."""
        self.fig.on_event(events.Tap, lambda event: callback(event.x))
