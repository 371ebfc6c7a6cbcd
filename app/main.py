"""The Bushing Explorer application: a factory that builds one session, and the server."""

from __future__ import annotations

import logging
import os
import re
import sys

import panel as pn
import param
from bokeh.models import CustomJS
from panel.io import resources as panel_resources
from panel.models.markup import HTML as PanelHTML

from .diagnosis import DiagnosisView
from .diagnosis_state import DiagnosisState
from .measured import MeasuredView
from .state import ExplorerState
from .views import (
    URL_NAMES,
    CompareView,
    DesignInputs,
    ExplorerPlots,
    ExportView,
    PlotView,
    SlicesView,
    TeachingView,
    status_banner,
)

pn.extension(throttled=False)


# Panel 1.9 sends Bokeh's MathJax bundle (1.8 MB, the largest script of the page) whenever the
# page holds an HTML pane, in case one holds math (holoviz/panel#8424; holoviz/panel#8179 would
# load it late instead). The explorer's texts hold none: the bundle is sent only to a page whose
# texts have math delimiters. Measured here: about 0.1 s of each page load.
MATH_DELIMITERS = re.compile(r"\$\$|\\\(|\\\[")


def holds_math(roots) -> bool:
    """Whether any Panel HTML model under ``roots`` has text with math delimiters."""
    return any(isinstance(model, PanelHTML) and MATH_DELIMITERS.search(model.text or "")
               for root in roots for model in root.references())


if hasattr(panel_resources, "_panel_use_mathjax"):
    panel_resources._panel_use_mathjax = holds_math

TITLE = "Bushing Explorer"

ABOUT = """
### Bushing Explorer

Dynamic stiffness of carbon-black-filled rubber bushings, axially and in torsion, over frequency
and amplitude, with the Fletcher–Gent (Payne) effect: the engineering formulas of M.-J. García
Tárrago (KTH, 2006). Set the geometry and the five material parameters on the left, pick the
operating point (drive amplitude and loop frequency), and read the loop, the stiffness magnitude
|K| and the loss factor. **Tap** any frequency or amplitude plot to move the operating point
there; every plot follows. All numbers come from the closed-form steady state, which the tests
check against the thesis' time-domain simulation.

**Units.** Radii and length in mm; µ and m in MPa (m in MPa·s^α); σ_fmax in kPa; ε½ and α
plain numbers; the drive in mm (axial) or rad (torsion), as peak values. |K| in kN/mm (= MN/m)
axially and N·m/rad in torsion. Files and the command line use SI.
"""


URL_DELAY_MS = 300

# Three BokehJS costs paid on every paint, measured in Chromium on this machine (Bokeh 3.9; each
# method is looked up first, and nothing is patched if it is not there; a browser test checks
# that all three are active and that what they change still behaves as Bokeh's own code):
#  * a plot component's stylesheet text is rewritten on every paint, nearly always with the text
#    it already has, and each rewrite makes Chromium recollect the page's styles (about a fifth
#    of the page's work per update). A rewrite that changes nothing is skipped.
#  * every visual property read asks the CSS cascade for a `--bk-*` variable (three reads per
#    `doit`, per tick label). The answers are kept until the running script returns (a
#    microtask clears them): one paint asks once per property, the next paint asks again. This
#    is the caching of bokeh/bokeh#15205 (after Bokeh 3.9); see also bokeh/bokeh#15286.
#  * a glyph renderer places its (empty) DOM element over its data's bounding box by rewriting
#    a stylesheet of its own; new data, new text, and Chromium re-parses the sheet and
#    invalidates the styles of its whole tree scope: about 15 ms of style work per update. The
#    same box is set as the element's inline style, which Chromium applies to that element
#    alone.
BOKEHJS_PAINT_PATCHES = """
// window[flag] says what happened: `done` if the method was found and wrapped, else "unpatched".
const patch = (flag, done, module, cls, method, wrap) => {
  if (window[flag] != null) return
  const mod = Bokeh.require(module)
  const proto = mod != null && mod[cls] != null ? mod[cls].prototype : null
  if (proto != null && typeof proto[method] === "function") {
    proto[method] = wrap(proto[method])
    window[flag] = done
  } else {
    window[flag] = "unpatched"
  }
}
patch("bushingStyleWrites", "skip-unchanged", "core/dom", "InlineStyleSheet", "_update", (update) =>
  function (css) { if (this.el.textContent !== css) update.call(this, css) })
patch("bushingCssReads", "cached-per-task", "core/visuals/visual", "VisualProperties", "_get_css_value", (read) =>
  function (name) {
    if (this._bushing_css == null) {
      this._bushing_css = new Map()
      queueMicrotask(() => { this._bushing_css = null })
    }
    let value = this._bushing_css.get(name)
    if (value === undefined) {
      value = read.call(this, name)
      this._bushing_css.set(name, value)
    }
    return value
  })
patch("bushingGlyphPosition", "inline-style", "models/renderers/glyph_renderer", "GlyphRendererView", "update_position", (update) =>
  function () {
    if (this.panel != null || this.position == null) {
      return update.call(this)
    }
    if (this._bushing_inline == null) {
      this.position.replace("")  // once: what an earlier paint wrote there no longer applies
      this._bushing_inline = true
    }
    const { bbox } = this
    const style = this.el.style
    if (bbox != null && bbox.is_valid) {
      style.removeProperty("display")
      style.position = "absolute"
      style.left = `${bbox.left}px`
      style.top = `${bbox.top}px`
      style.width = `${bbox.width}px`
      style.height = `${bbox.height}px`
    } else {
      style.display = "none"
    }
  })
"""


class ShareLink(param.Parameterized):
    """The design as the address bar shows it: the state's linked parameters, untouched by
    validation (the state judges them). A link opened (or the browser's back button) applies
    at once; the state's changes reach the address bar after a pause, so a slider drag is one
    history entry and one URL write, not one per step."""

    mode = param.Selector(objects=["axial", "torsion"], default="axial")


for _name in URL_NAMES:
    if _name != "mode":
        ShareLink.param.add_parameter(_name, param.Number(default=None, allow_None=True))


class App(pn.viewable.Viewer):
    """One session of the explorer: its own state, inputs, plots and URL.

    The views of the other tabs are built when their tab is first opened (or when code asks
    for them): a page load builds only what it shows. Measured on this machine, building every
    tab's figures took about half of the server's time to answer a first request."""

    # tab title, attribute, builder; the Explorer tab (0) and About are built at once
    LAZY_TABS = (
        ("Slices", "slices", lambda app: SlicesView(app.state)),
        ("Fletcher–Gent, branch by branch", "teaching", lambda app: TeachingView(app.state)),
        ("Measured data and fit", "measured", lambda app: MeasuredView(app.state)),
        ("Find the missing effect", "diagnosis", lambda app: DiagnosisView(DiagnosisState(app.state))),
    )

    def __init__(self, state: ExplorerState | None = None, **params):
        super().__init__(**params)
        self.state = state or ExplorerState()
        self.inputs = DesignInputs(self.state)
        self.plots = ExplorerPlots(self.state)
        self.compare = CompareView(self.state)
        self.export = ExportView(self.state)
        self._built: dict[str, pn.viewable.Viewer] = {}
        self._holders = {name: pn.Column(sizing_mode="stretch_width") for _title, name, _build in self.LAZY_TABS}
        self.tabs = pn.Tabs(
            ("Explorer", pn.Column(self.compare, self.plots, sizing_mode="stretch_width")),
            *((title, self._holders[name]) for title, name, _build in self.LAZY_TABS),
            ("About", pn.pane.Markdown(ABOUT, sizing_mode="stretch_width")),
            dynamic=True,
            sizing_mode="stretch_width",
        )
        self.tabs.param.watch(self._on_tab, "active")
        self._on_tab()

    slices = property(lambda self: self.view("slices"))
    teaching = property(lambda self: self.view("teaching"))
    measured = property(lambda self: self.view("measured"))
    diagnosis = property(lambda self: self.view("diagnosis"))

    def view(self, name: str):
        """The view of a lazily built tab, built (and put in its tab) on first use."""
        if name not in self._built:
            build = next(b for _title, n, b in self.LAZY_TABS if n == name)
            self._built[name] = build(self)
            self._holders[name].objects = [self._built[name]]
            self._on_tab()
        return self._built[name]

    def _on_tab(self, *_events):
        active = self.tabs.active
        if 1 <= active <= len(self.LAZY_TABS):
            self.view(self.LAZY_TABS[active - 1][1])
        self.plots.show(active == 0)
        for index, (_title, name, _build) in enumerate(self.LAZY_TABS, start=1):
            view = self._built.get(name)
            if isinstance(view, PlotView):
                view.show(index == active)

    def sync_url(self, delay_ms: int = URL_DELAY_MS):
        """Put the whole design in the URL, and read one from it (a shared link)."""
        location = pn.state.location
        if location is None:
            return
        self.link = ShareLink(**{name: getattr(self.state, name) for name in URL_NAMES})
        self._copying = False
        self._pending = None
        self.link.param.watch(self._from_link, list(URL_NAMES))
        location.sync(self.link, URL_NAMES, on_error=self.state.apply_url_values)
        self.state.param.watch(lambda *_events: self._schedule_link(delay_ms), list(URL_NAMES))

    def _from_link(self, *events):
        if self._copying:
            return
        values = {e.name: e.new for e in events}
        try:
            self.state.param.update(values)
        except Exception:  # noqa: BLE001 - one bad value: apply the others, say which
            self.state.apply_url_values(values)

    def _schedule_link(self, delay_ms: int):
        doc = pn.state.curdoc
        if doc is None:
            return self._to_link()
        if self._pending is not None:
            try:
                doc.remove_timeout_callback(self._pending)
            except ValueError:
                pass  # it has just run
        self._pending = doc.add_timeout_callback(self._to_link, delay_ms)

    def _to_link(self):
        self._pending = None
        self._copying = True
        try:
            self.link.param.update({name: getattr(self.state, name) for name in URL_NAMES})
        finally:
            self._copying = False

    def template(self):
        template = pn.template.BootstrapTemplate(
            title=TITLE,
            sidebar=[self.inputs, pn.Card(self.export, title="Export and share", sizing_mode="stretch_width")],
            main=[status_banner(self.state), self.tabs],
            sidebar_width=380,
            header_background="#1f5f8b",
            busy_indicator=None,  # its animation restyled the page on every change
        )
        return template

    def __panel__(self):
        return pn.Row(pn.Column(self.inputs, self.export, width=360), pn.Column(status_banner(self.state), self.tabs))


def create_app():
    """Factory for one session (served per connection, so sessions never share state)."""
    app = App()
    app.sync_url()
    if pn.state.curdoc is not None:
        pn.state.curdoc.js_on_event("document_ready", CustomJS(code=BOKEHJS_PAINT_PATCHES))
    return app.template()


def _origins(address: str, port: int) -> list[str]:
    extra = [o for o in os.environ.get("BUSHING_ALLOWED_ORIGINS", "").split(",") if o]
    if address in ("0.0.0.0", "::", ""):
        return extra or ["*"]  # bound to every interface: reached by any host name
    return [f"localhost:{port}", f"127.0.0.1:{port}", f"{address}:{port}", *extra]


def serve(port: int = 5006, address: str = "localhost", show: bool = False):
    """Start the explorer (blocking); prints the URL."""
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    server = pn.serve(
        create_app,
        port=port,
        address=address,
        websocket_origin=_origins(address, port),
        show=show,
        start=False,
        title=TITLE,
        liveness=True,
        verbose=False,
    )
    host = "localhost" if address in ("0.0.0.0", "::", "") else address
    print(f"Bushing Explorer: http://{host}:{server.port}/", flush=True)
    sys.stdout.flush()
    server.start()
    server.io_loop.start()
