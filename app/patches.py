"""The one place where the app uses a library's private internals (each measured to matter).

Checked against Panel 1.9, HoloViews 1.23 and Bokeh 3.9 (``pyproject.toml`` pins ``panel<1.10``,
``holoviews<1.24`` and ``bokeh<3.10``); ``tests/test_app_page.py`` fails if an internal is gone or no
longer takes effect.

Importing this module changes nothing: :func:`install` (called by :func:`app.main.create_app`,
once per session; it installs each hook once) puts the process-wide hooks in place and the
BokehJS patches in the session's page. A notebook that imports the plotting API gets none of them.

**Model recomputation.** Every HoloViews plot update freezes the Bokeh document's models, and
Bokeh recomputes the set of models (a walk over every model) whenever the last freeze ends,
whether or not the model graph changed: 24 ms per walk of the explorer's page, a fifth of the
server's time per change. :func:`frozen_models` freezes the models for a whole change and
recomputes them at its end only if Bokeh asked for it (``invalidate``: models added or removed).
Upstream, Bokeh's ``DocumentModelManager`` could remember an ``invalidate`` while frozen.

**Sessions admitted** (:func:`route_sessions`). Bokeh's server takes its per-app routes from the
module list ``bokeh.server.urls.per_app_patterns`` (which Panel rewrites on import); the explorer
routes pages and websockets to Panel's handlers with :mod:`app.admission`'s check in front: a burst
of new sessions is refused with a "busy" page instead of queueing on the server's one thread.

**Property defaults looked up once** (:func:`cache_immutable_defaults`). Bokeh 3.9 computes a
property's default at every read of a property never set: the class's overridden defaults
merged over its whole MRO, then the value validated (``Property.themed_default``), tens of
thousands of times per page built and serialised. Where the default is an immutable value and
no theme overrides it, the result is the same every time; it is kept per (property, class), and
so is whether a property's default is unstable (asked at every such read, with two imports); an
empty list, dict or set default (every model's ``tags``, ``js_event_callbacks``, ...) is a new one
of Bokeh's type per read, made without the merge. Measured (``benchmarks/page_cpu.py``): 744–782 ms
of CPU per page without, 633–650 ms with the immutable defaults; the empty ones then took Bokeh's
lookups from 5 500 to 950 per page. A test compares all with Bokeh's own answers.

**BokehJS paint** (:data:`BOKEHJS_PAINT_PATCHES`, run in the page when its document is
ready). Three costs BokehJS 3.9 pays on every paint: a plot component's stylesheet rewritten with
the text it already has (each rewrite makes Chromium recollect the page's styles); every visual
property read asking the CSS cascade for a ``--bk-*`` variable (cached here until the running
script returns, as bokeh/bokeh#15205 does after 3.9); a glyph renderer placing its empty element
by rewriting a stylesheet of its own (set here as the element's inline style). A method missing,
nothing is patched; a browser test checks all three are active and behave as Bokeh's own. Chromium's
renderer 59–60 ms per change with them, 71–82 ms without (``BUSHING_BOKEHJS_PATCHES=0``).

**Models from the server are known to it** (:data:`BOKEHJS_SERVER_MODELS`, run in every page).
BokehJS 3.9 counts a model that a server patch brings (a tab's content shown for the first time) as
new to the server until the page's next patch, which sends it again in full: the server warns
``reference already known`` (e.g. the first click in the diagnosis tab). The page takes the models
of each server patch as known: a model the page makes itself stays new.

**Stylesheets from this server** (:func:`local_stylesheets`). Panel addresses its stylesheets
against the document's ``dist_url`` (Bokeh's private ``Document._template_variables``), set only
when the page is rendered; a component built before that and first sent after an upload asked
the CDN for ``loading.css`` (a console error; nothing loaded offline). Set at session start to
:func:`panel.io.resources.get_dist_path` (this server's path unless the resources are the CDN).

**No selection glyph models** (:func:`selection_glyphs_auto`). HoloViews 1.23 makes a model of
every glyph renderer's ``"auto"`` selection glyph (``ElementPlot._update_glyph``): the glyph's
properties and the element's ``selection_*`` styles. With no such style, that is what BokehJS
clones for a renderer without one. 22 models fewer per page (536 to 514), 25 ms less CPU per page.

**MathJax.** Panel 1.9 sends Bokeh's MathJax bundle (1.8 MB) whenever the page holds an HTML pane
(holoviz/panel#8424); it is sent only to a page whose texts have math delimiters (0.1 s per load).

**Number edits without debounce** (:func:`send_values_at_once`). Panel holds every change of a
widget's property from the page for 50 ms (``Syncable._debounce``), except the properties a class
lists in its private ``_priority_changes`` (as Panel's Tabulator does for its data). The app's
number widgets (:data:`app.inputs.IMMEDIATE`) list ``value``: 50 ms less per edit, and a click right
after typing ("Find designs") is no longer processed before the typed value, on the old one.

**One message per change** (:func:`hold_each_change`). On a server, Panel processes a change from
the page (``Syncable._change_event``) without holding the document: each property set went as its
own message (a mode switch painted the slider's new unit beside the old one's text for some 13
frames; a browser test samples every frame). Held, a change arrives in one message.

**A file is sent as soon as its drop area has it** (:data:`UPLOAD_AT_ONCE`; issue #27 item 16).
FilePond processes (Panel's FileDropper sends from its ``server.process``) only once its animations
rest: a CSV left 1.1 s after the drop, of 1.9 s to its summary (``benchmarks/upload_speed.py``).
The page sends it at FilePond's ``addfile`` (type and size checked) through the view's
``_process_upload``; *Browse* hands the file to FilePond (``addFiles``) at once, not 250 ms later.
A browser test checks that the bytes leave, once, while FilePond still holds the file queued.

**Data-only updates** (:func:`holoviews_plots`, :func:`written`). HoloViews builds each plot
(its dimensions, styles, legend, linked axes, tap stream); a later frame with the same elements
(kinds, labels, styles, dimensions) differs only in its numbers, written into the Bokeh models
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

import contextlib
import os
import re
import weakref
from pathlib import Path

import numpy as np
from bokeh.core.property.bases import Property
from bokeh.core.property.descriptors import PropertyDescriptor
from bokeh.core.property.wrappers import PropertyValueDict, PropertyValueList, PropertyValueSet
from panel.io import resources as panel_resources
from panel.io.document import hold as panel_hold
from panel.io.server import DocHandler, WSHandler
from panel.models.markup import HTML as PanelHTML
from panel.reactive import Syncable

MATH_DELIMITERS = re.compile(r"\$\$|\\\(|\\\[")
# the Panel internals the hooks replace or extend are there (a test fails if not)
PATCHED = (hasattr(panel_resources, "_panel_use_mathjax") and hasattr(Syncable, "_priority_changes")
           and hasattr(Syncable, "_change_event"))
_installed = False
_pages = weakref.WeakSet()  # documents that have the BokehJS patches


def install(doc=None) -> None:
    """Put the hooks of this module in place, each once however often it is called: the process-wide
    ones, and in the page of ``doc`` (if given) the BokehJS paint patches (unless
    ``BUSHING_BOKEHJS_PATCHES=0``), :data:`BOKEHJS_SERVER_MODELS`, :data:`LABEL_CLICKS`, :data:`UPLOAD_AT_ONCE`."""
    global _installed
    if not _installed:
        if hasattr(panel_resources, "_panel_use_mathjax"):
            panel_resources._panel_use_mathjax = holds_math
        from .inputs import IMMEDIATE

        send_values_at_once(IMMEDIATE)
        hold_each_change()
        cache_immutable_defaults()
        selection_glyphs_auto()
        _installed = True
    if doc is not None and doc not in _pages:
        if os.environ.get("BUSHING_BOKEHJS_PATCHES", "1") == "1":
            install_bokehjs_patches(doc)
        from bokeh.models import CustomJS

        doc.js_on_event("document_ready", CustomJS(code=BOKEHJS_SERVER_MODELS))
        doc.js_on_event("document_ready", CustomJS(code=LABEL_CLICKS))
        doc.js_on_event("document_ready", CustomJS(code=UPLOAD_AT_ONCE))
        local_stylesheets(doc)
        _pages.add(doc)


def route_sessions(doc_handler, ws_handler) -> list:
    """Serve a new server's pages and websockets with ``doc_handler`` and ``ws_handler``
    (subclasses of Panel's, :mod:`app.admission`): Bokeh's server reads its routes from the module
    list ``bokeh.server.urls.per_app_patterns`` when it is made, which Panel itself rewrites with
    its handlers on import. Call before ``pn.serve``; a test checks that the routes were Panel's.
    Returns the routes before (to put back: ``urls.per_app_patterns[:] = previous``)."""
    from bokeh.server import urls

    previous = list(urls.per_app_patterns)
    replace = {DocHandler: doc_handler, WSHandler: ws_handler}
    urls.per_app_patterns[:] = [(route, replace.get(handler, handler), *rest)
                                for route, handler, *rest in urls.per_app_patterns]
    return previous


_IMMUTABLE = (type(None), bool, int, float, str)
_EMPTY = (PropertyValueList, PropertyValueDict, PropertyValueSet)


def _immutable(value) -> bool:
    return type(value) in _IMMUTABLE or (type(value) is tuple and all(_immutable(v) for v in value))


def cache_immutable_defaults() -> None:
    """Bokeh's ``Property.themed_default`` looked up once per (property, class) where no theme
    overrides it and the default is immutable (None, a number, a string, a tuple of them: kept) or
    an empty list, dict or set (its type kept: a new empty one per read), instead of at every read
    of a property never set (see the module); other defaults go to Bokeh's own code. And whether a
    property's default is unstable (``PropertyDescriptor.has_unstable_default``: the property's
    and the class's overridden defaults' answer), once per pair."""
    original = Property.themed_default
    if getattr(original, "cached_by_bushing", False):
        return
    cache: dict = {}
    empty: dict = {}

    def themed_default(self, cls, name, theme_overrides, *, no_eval=False):
        if theme_overrides is not None and name in theme_overrides:
            return original(self, cls, name, theme_overrides, no_eval=no_eval)
        key = (id(self), cls, name, no_eval)  # a Property lives as long as its class
        if key in cache:
            return cache[key]
        if key in empty:
            return empty[key]()
        value = original(self, cls, name, theme_overrides, no_eval=no_eval)
        if _immutable(value):
            cache[key] = value
        elif type(value) in _EMPTY and not value:
            empty[key] = type(value)
        return value

    themed_default.cached_by_bushing = True
    themed_default.original = original
    Property.themed_default = themed_default

    original_unstable = PropertyDescriptor.has_unstable_default
    unstable: dict = {}

    def has_unstable_default(self, obj):  # the property's and the class's: one answer per pair
        key = (id(self), type(obj))
        if key not in unstable:
            unstable[key] = original_unstable(self, obj)
        return unstable[key]

    has_unstable_default.original = original_unstable
    PropertyDescriptor.has_unstable_default = has_unstable_default


def selection_glyphs_auto() -> None:
    """The glyph renderers HoloViews makes, while not yet in a document, left without a selection
    glyph model unless their element has ``selection_*`` styles (see the module)."""
    from holoviews.plotting.bokeh.element import ElementPlot

    original = ElementPlot._update_glyph
    if getattr(original, "by_bushing", False):
        return

    def _update_glyph(self, renderer, properties, *args, **kwargs):
        if renderer is not None and renderer.document is None and renderer.selection_glyph == "auto" \
                and not any(str(k).startswith("selection_") for k in properties):
            renderer.selection_glyph = None  # BokehJS clones the glyph for it, as for "auto"
        return original(self, renderer, properties, *args, **kwargs)

    _update_glyph.by_bushing, _update_glyph.original = True, original
    ElementPlot._update_glyph = _update_glyph


def local_stylesheets(doc) -> None:
    """Panel's stylesheets of every component of ``doc`` from this server, also of those built
    before the page is rendered, as Panel sets it at render (see the module)."""
    doc._template_variables.setdefault("dist_url", panel_resources.get_dist_path())


def send_values_at_once(classes) -> None:
    """Panel widget classes (the app's own subclasses) whose ``value`` from the page is processed
    at once, without Panel's 50 ms debounce (see the module)."""
    for cls in classes:
        if "value" not in cls._priority_changes:
            cls._priority_changes = [*cls._priority_changes, "value"]  # the class's own list


def hold_each_change() -> None:
    """Every change of a widget's property from the page processed under one document hold
    (``Syncable._change_event``, where Panel processes them on a server): what the change sets
    anywhere (the widget's own label and bounds, the other widgets, the texts, the plots) goes to
    the page in one message, painted at once (see the module)."""
    original = Syncable._change_event
    if getattr(original, "held_by_bushing", False):
        return

    def _change_event(self, doc):
        with panel_hold(doc):
            original(self, doc)

    _change_event.held_by_bushing = True
    Syncable._change_event = _change_event


def holds_math(roots) -> bool:
    """Whether a Panel HTML model under ``roots`` has math delimiters (a page's roots: its document's
    set of models, not another walk of them, 17 ms per page served)."""
    roots = list(roots)
    doc = roots[0].document if roots else None
    whole = doc is not None and len(roots) == len(doc.roots) and all(r.document is doc for r in roots)
    models = doc.models if whole else (model for root in roots for model in root.references())
    return any(isinstance(model, PanelHTML) and MATH_DELIMITERS.search(model.text or "") for model in models)


@contextlib.contextmanager
def frozen_models(doc):
    """``doc.models`` frozen while the block runs, recomputed at its end only if the model graph
    changed in it (see the module). Nested inside another freeze, an ordinary freeze."""
    models = doc.models
    if models._freeze_count:
        with models.freeze():
            yield
        return
    changed = []

    def invalidate():
        changed.append(True)

    models.invalidate = invalidate  # shadows the method for this block
    models._push_freeze()
    try:
        yield
    finally:
        del models.invalidate
        models._freeze_count -= 1
        if changed and models._freeze_count == 0:
            models.recompute()


JS = Path(__file__).with_name("js")  # the scripts the pages run, each in its own file


def _script(name: str) -> str:
    """The text of the page script ``app/js/<name>``."""
    return (JS / name).read_text(encoding="utf-8")


BOKEHJS_PAINT_PATCHES = _script("paint_patches.js")
BOKEHJS_SERVER_MODELS = _script("server_models.js")
# A checkbox's or a switch's label toggles it (issue #27): BokehJS 3.9 draws the label as a <div>
# beside the box (a Checkbox's <input>, a Switch's .bk-body) in the widget's shadow root, not as a
# <label>, so a click on the words did nothing. One listener on the page: a click whose path (through
# open shadow roots) holds such a label and not the box itself clicks the box of the same root.
LABEL_CLICKS = _script("label_clicks.js")
# window.bushingUploadAtOnce: "on" once installed, "unpatched" if Panel's FileDropper view has no
# _process_upload (then FilePond sends the file itself, after its animations)
UPLOAD_AT_ONCE = _script("upload_at_once.js")


def install_bokehjs_patches(doc):
    """Run :data:`BOKEHJS_PAINT_PATCHES` in the page of ``doc`` once it is ready."""
    from bokeh.models import CustomJS

    doc.js_on_event("document_ready", CustomJS(code=BOKEHJS_PAINT_PATCHES))


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
