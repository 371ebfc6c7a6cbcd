"""A plot's next frame of the same shape written into the Bokeh models HoloViews made (:func:`written`).

One of the library internals of :mod:`app.patches`. HoloViews builds each plot (its dimensions,
styles, legend, linked axes, tap stream); a later frame with the same elements (kinds, labels,
styles, dimensions) differs only in its numbers, written into the Bokeh models
HoloViews made: each changed element's columns (HoloViews' own ``get_data``) into its data source,
a marker's position, the axis ranges (and the Reset tool's), the dimensions' words (after a mode
switch) into the axis labels and tooltips, a bar chart's categories, a map's colour span; an axis
HoloViews ranged from the data is kept while their extent is. The diagnosis report is written
this way (``benchmarks/diagnosis_report_cpu.py``: 1 065 ms of server CPU and 560 new models per
report before, 79 ms and none after); an amplitude change of the explorer 82 ms before, 31 ms
after (``benchmarks/explorer_change.py``), HoloViews' per-update path skipped. Panel
keeps a pane's HoloViews plots in the private ``HoloViews._plots`` (one per root model); the plot's
``subplots``, ``handles`` and ``get_data`` are HoloViews' own (Panel uses them the same way).
"""

from __future__ import annotations

import numpy as np


def holoviews_plots(pane) -> list:
    """The HoloViews plots a Panel HoloViews pane has rendered (one per page showing it), each once
    (Panel files a plot under each root model it is rendered in: the template's, the pane's own)."""
    return list({id(plot): plot for plot, _model in getattr(pane, "_plots", {}).values()}.values())


def _has(model, name: str) -> bool:
    """Whether the Bokeh model ``model`` has the property ``name``, looked up on its class (``hasattr``
    has Bokeh list similar names with difflib before it fails: 0.1 ms each, ten per change)."""
    return getattr(type(model), name, None) is not None


def _axis_range(dim) -> tuple[float, float] | None:
    rng = tuple(dim.range)
    if len(rng) != 2 or not all(isinstance(v, (int, float)) and np.isfinite(v) for v in rng):
        return None
    return float(rng[0]), float(rng[1])


def _element_data(subplot, element) -> dict | None:
    """The columns HoloViews would put in ``subplot``'s data source for ``element``, or None if they
    are not the columns it has."""
    static, subplot.static_source = subplot.static_source, False  # get_data leaves a static source out
    try:
        data, _mapping, _style = subplot.get_data(element, {}, {})
    finally:
        subplot.static_source = static
    for key, expr in subplot.handles.items():  # a style mapped from a dimension: its column (HoloViews' own dim)
        column = key[: -len("_color_dim")] if key.endswith("_color_dim") else None
        if column and column not in data and hasattr(expr, "apply"):
            data[column] = np.asarray(expr.apply(element, flat=True))
    source = subplot.handles.get("source")
    if source is None or set(data) != set(source.data):
        return None
    return data


def _words(old, new) -> dict | None:
    """Each dimension label (with its unit, as HoloViews prints it) of overlay ``old`` → that of
    the dimension of the same name at the same place in ``new``; None if one label would become
    two."""
    out = {}
    for a, b in zip(old.values(), new.values()):
        for da, db in zip(a.dimensions(), b.dimensions()):
            if da.name != db.name or out.setdefault(da.pprint_label, db.pprint_label) != db.pprint_label:
                return None
    return out


def _labels_written(plot, was: tuple, now: tuple, words: dict | None) -> list | None:
    """The writes that put the words of dimensions ``now`` (x, y) where HoloViews drew those of
    ``was``: the axis labels and the hover tooltips' labels (:data:`app.plotting.style.CURVE_TIP`
    and one ``(label, "@{name}")`` per dimension). None if the plot's axes or tooltips do not
    show ``was`` as expected (then HoloViews must draw the new words itself)."""
    if words is None:
        return None
    writes = []
    for handle, before, after in zip(("xaxis", "yaxis"), was, now):
        axis = plot.handles.get(handle)
        if axis is None or not _has(axis, "axis_label") or axis.axis_label != before.pprint_label:
            return None
        if after.pprint_label != before.pprint_label:
            writes.append((axis, {"axis_label": after.pprint_label}))
    for tool in plot.state.toolbar.tools:
        if tool.__class__.__name__ != "HoverTool":
            continue
        tips = tool.tooltips
        if not isinstance(tips, list) or not all(isinstance(t, tuple) and len(t) == 2 for t in tips):
            return None
        renamed = [(words.get(label, label), field) for label, field in tips]
        if renamed != list(tips):
            writes.append((tool, {"tooltips": renamed}))
    return writes


def _xy(element) -> tuple:
    """The dimensions on ``element``'s x and y axes: its two key dimensions (points, a map), else
    its key and first value dimension (a curve, bars)."""
    return (element.kdims[0], element.kdims[1]) if len(element.kdims) > 1 else (element.kdims[0], element.vdims[0])


def _colors_written(sub, element) -> list | None:
    """The writes that put the range of each dimension ``sub`` colours by (its ``Dimension.range``:
    what HoloViews' colour mapper spans when no ``clim`` is set) into its colour mapper (the colour
    bar shows that mapper); None if a range is not a finite pair."""
    writes = []
    for key, mapper in sub.handles.items():
        if not key.endswith("_color_mapper") or not _has(mapper, "low"):
            continue
        expr = sub.handles.get(key[: -len("_color_mapper")] + "_color_dim")
        dim = element.get_dimension(getattr(getattr(expr, "dimension", None), "name", None))
        rng = None if dim is None else _axis_range(dim)
        if rng is None:
            return None
        if (mapper.low, mapper.high) != rng:
            writes.append((mapper, {"low": rng[0], "high": rng[1]}))
    return writes


def _extent(overlay, name: str) -> tuple | None:
    """The smallest and largest finite value of dimension ``name`` over the elements of ``overlay``
    that have it (what HoloViews ranges an axis by when the dimension sets no range); None if none."""
    values = [np.asarray(el.dimension_values(name), dtype=float) for el in overlay.values()
              if el.get_dimension(name) is not None and el.__class__.__name__ not in ("VLine", "HLine")]
    values = np.concatenate(values) if values else np.empty(0)
    values = values[np.isfinite(values)]
    return (float(values.min()), float(values.max())) if values.size else None


def _factors(sub, element) -> list | None:
    """The categories HoloViews puts on ``element``'s x axis (its own ``_get_factors``), or None."""
    try:
        xfactors, _y = sub._get_factors(element, {})
    except Exception:  # noqa: BLE001 - not an element with categories HoloViews can list alone
        return None
    return [str(f) for f in xfactors]


def written(plot, old, new):
    """A function that writes the numbers of overlay ``new`` into ``plot`` (HoloViews' plot of the
    overlay ``old``, the same elements with other numbers), the elements that are ``old``'s own
    objects left as they are; None if ``plot`` does not draw ``old``'s elements the way expected
    (then HoloViews must update it). Nothing is written before the function is called. Besides
    columns, markers, numeric axis ranges and words: a categorical x axis' categories (bars) and
    the span of a colour mapper (a map coloured by a dimension with a range)."""
    subplots = getattr(plot, "subplots", None) or {}
    writes = []
    for before, (key, after) in zip(old.values(), new.data.items()):
        sub = subplots.get(key)
        if sub is None or "source" not in sub.handles:
            return None
        if after is before:
            continue
        if after.__class__.__name__ in ("VLine", "HLine"):
            glyph = sub.handles.get("glyph")
            if glyph is None or not _has(glyph, "location"):
                return None
            writes.append((glyph, {"location": float(after.data)}))
            continue
        data, colors = _element_data(sub, after), _colors_written(sub, after)
        if data is None or colors is None:
            return None
        writes += [(sub.handles["source"], {"data": data}), *colors]
    index = next((i for i, el in enumerate(new.values()) if el.__class__.__name__ not in ("VLine", "HLine")), None)
    if index is not None:
        first, was = new.values()[index], old.values()[index]
        for axis, dim in zip(("x_range", "y_range"), _xy(first)):
            model = plot.handles.get(axis)
            if model is not None and _has(model, "factors"):  # categories (bars)
                factors = _factors(subplots.get(list(new.data)[index]), first)
                if factors is None:
                    return None
                if list(model.factors) != factors:
                    writes.append((model, {"factors": factors}))
                continue
            rng = _axis_range(dim)
            if rng is None and _extent(old, dim.name) == _extent(new, dim.name) is not None:
                continue  # a range of HoloViews' own, from the data's extent: the same as drawn
            if rng is None or model is None or not _has(model, "start"):
                return None
            if (model.start, model.end) != rng or ((model.reset_start, model.reset_end) if _has(model, "reset_start") else (None, None)) != rng:
                # and where the Reset tool returns to, as HoloViews sets it (else the first frame's range)
                writes.append((model, {"start": rng[0], "end": rng[1], "reset_start": rng[0], "reset_end": rng[1]}))
        labels = _labels_written(plot, _xy(was), _xy(first), _words(old, new))
        if labels is None:
            return None
        writes += labels

    def write():
        for model, values in writes:
            model.update(**values)

    return write
