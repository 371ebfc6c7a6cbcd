"""The one place where the app uses a library's private internals (each measured to matter).

Checked against Panel 1.9, HoloViews 1.23 and Bokeh 3.9 (``pyproject.toml`` pins ``panel<1.10``,
``holoviews<1.24`` and ``bokeh<3.10``); ``tests/test_app_page.py`` fails if an internal is gone or no
longer takes effect.

Importing this module changes nothing: :func:`install` (called by :func:`app.main.create_app`,
once per session; it installs each hook once) puts the process-wide hooks in place and the
BokehJS patches in the session's page. A notebook that imports the plotting API gets none of them.

**Model recomputation** (:mod:`app.patches.model_graph`). Every HoloViews plot update freezes
the Bokeh document's models, and Bokeh recomputes the set of models (a walk over every model)
whenever the last freeze ends, whether or not the model graph changed: 24 ms per walk of the
explorer's page, a fifth of the server's time per change. :func:`frozen_models` freezes the
models for a whole change and recomputes them at its end only if Bokeh asked for it
(``invalidate``: models added or removed), and a change that only added models attaches those,
without the walk (35–50 ms per report plot made ready in the diagnosis tab). Upstream, Bokeh's
``DocumentModelManager`` could remember an ``invalidate`` while frozen.

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

**A drop area's loop at rest while nobody uses it** (:data:`IDLE_PAINTER`). FilePond 4.32 (Panel's
FileDropper) runs one loop for its drop areas' animations and work that asks for every frame
from the moment its script loads (pqina/filepond#243): Chromium draws 60 frames a second on a
page where nothing moves. While no drop area has been used for two seconds, the loop's next frame
is asked 250 ms later; anything done at a drop area wakes it at once. Chromium's CPU per second
at rest (``benchmarks/idle_page.py``, headless): renderer 0.067–0.070 s and other processes
0.025–0.027 s without, 0.010 s and 0.003–0.010 s with; the rest is the server's and its worker's
when they share the machine. A browser test counts the loop's steps at rest and after a pointer.

**One set of stylesheets per component** (:class:`PageDesign`). Panel's Bootstrap template
styles the components of the page it builds with its design's stylesheets for a part of a page
(Panel's ``isolated=False``). A component whose model is made later (a tab opened, the report's
plots added) or a text pane whose text changes asks the design again through ``Design.params``,
which styles it as if it stood alone (``isolated``): Bootstrap's whole stylesheet
(``bootstrap.min.css``, 220 kB) and the theme's, in its shadow root. After a diagnosis 36
components carried it, and Chromium weighs those rules at every stylesheet change in the page
(BokehJS writes a view's stylesheet at each layout and paint): one change and the style
recalculation it forces took 1.0–2.2 ms with them, 0.22–0.42 ms without (in the page after a
diagnosis). :class:`PageDesign` styles every component as the template does at page build
(``Design._get_modifiers``, its ``isolated`` flag off); the Explorer's components look as before.

**Data-only updates** (:mod:`app.patches.data_writes`): a plot's next frame of the same
shape written into the Bokeh models HoloViews made, through HoloViews' plot handles.
"""

from __future__ import annotations

import inspect
import os
import re
import weakref
from pathlib import Path

from bokeh.core.property.bases import Property
from bokeh.core.property.descriptors import PropertyDescriptor
from bokeh.core.property.wrappers import PropertyValueDict, PropertyValueList, PropertyValueSet
from panel.io import resources as panel_resources
from panel.io.document import hold as panel_hold
from panel.io.server import DocHandler, WSHandler
from panel.models.markup import HTML as PanelHTML
from panel.reactive import Syncable
from panel.theme import Bootstrap

from .data_writes import holoviews_plots, written  # noqa: F401 - the package's names (app.live, tests)
from .model_graph import frozen_models, track_reference_changes  # noqa: F401 - frozen_models: app.live's

MATH_DELIMITERS = re.compile(r"\$\$|\\\(|\\\[")
# the Panel internals the hooks replace or extend are there (a test fails if not)
PATCHED = (hasattr(panel_resources, "_panel_use_mathjax") and hasattr(Syncable, "_priority_changes")
           and hasattr(Syncable, "_change_event") and "isolated" in inspect.signature(Bootstrap._get_modifiers).parameters)
_installed = False
_pages = weakref.WeakSet()  # documents that have the BokehJS patches


def install(doc=None) -> None:
    """Put the hooks of this module in place, each once however often it is called: the process-wide
    ones, and in the page of ``doc`` (if given) the BokehJS paint patches (unless
    ``BUSHING_BOKEHJS_PATCHES=0``), :data:`BOKEHJS_SERVER_MODELS`, :data:`LABEL_CLICKS`, :data:`UPLOAD_AT_ONCE`,
    :data:`IDLE_PAINTER`."""
    global _installed
    if not _installed:
        if hasattr(panel_resources, "_panel_use_mathjax"):
            panel_resources._panel_use_mathjax = holds_math
        from ..inputs import IMMEDIATE

        send_values_at_once(IMMEDIATE)
        hold_each_change()
        cache_immutable_defaults()
        selection_glyphs_auto()
        track_reference_changes()
        _installed = True
    if doc is not None and doc not in _pages:
        if os.environ.get("BUSHING_BOKEHJS_PATCHES", "1") == "1":
            install_bokehjs_patches(doc)
        from bokeh.models import CustomJS

        doc.js_on_event("document_ready", CustomJS(code=BOKEHJS_SERVER_MODELS))
        doc.js_on_event("document_ready", CustomJS(code=LABEL_CLICKS))
        doc.js_on_event("document_ready", CustomJS(code=UPLOAD_AT_ONCE))
        doc.js_on_event("document_ready", CustomJS(code=IDLE_PAINTER))
        local_stylesheets(doc)
        _pages.add(doc)


class PageDesign(Bootstrap):
    """Panel's Bootstrap design, each component styled as a part of the page however late its
    model is made or its text changes (see the module)."""

    @classmethod
    def _get_modifiers(cls, viewable, theme=None, isolated=True):
        return super()._get_modifiers(viewable, theme, isolated=False)


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


JS = Path(__file__).parents[1] / "js"  # the scripts the pages run, each in its own file


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
# _process_upload (then FilePond sends the file itself, after its animations); it also turns off
# FilePond's minimum upload duration, so that a file sent is shown complete
UPLOAD_AT_ONCE = _script("upload_at_once.js")
# window.bushingIdlePainter: "on" once FilePond's painter is found and throttled while idle
IDLE_PAINTER = _script("idle_painter.js")


def install_bokehjs_patches(doc):
    """Run :data:`BOKEHJS_PAINT_PATCHES` in the page of ``doc`` once it is ready."""
    from bokeh.models import CustomJS

    doc.js_on_event("document_ready", CustomJS(code=BOKEHJS_PAINT_PATCHES))
