"""The Bushing Explorer application: a factory that builds one session, and the server."""

from __future__ import annotations

import logging
import os
import signal
import sys

import panel as pn
from tornado.ioloop import PeriodicCallback

from . import admission, collector, patches, work
from .diagnosis_state import DiagnosisState
from .export import ExportView
from .fit_state import FitState
from .inputs import DesignInputs, status_banner
from .link import URL_DELAY_MS, UrlLink
from .state import ExplorerState
from .tabs.about import ABOUT
from .tabs.every_direction import CardView
from .tabs.explorer import CompareView, ExplorerPlots
from .tabs.find_the_missing_effect import DiagnosisView
from .tabs.fletcher_gent import TeachingView
from .tabs.measured_data_and_fit import MeasuredView
from .tabs.slices import SlicesView
from .tabs.what_ifs import WhatIfView
from .views import PlotView

pn.extension("filedropper", throttled=False)  # the upload areas (app.uploads) are in lazy tabs


TITLE = "Bushing Explorer"

# the tab bar wraps onto a second row when its headers do not fit the width (Bokeh's own bar
# hides the headers past its right edge: at 1280 px two tabs were unreachable). A tab not shown is
# a Spacer in the page (Panel's dynamic tabs) until the server sends its content, the first time
# after building its view (the Slices tab: 1.3-1.9 s, the page blank meanwhile): the Spacer says
# the tab is opening, with a moving bar, drawn by the browser as soon as the tab is clicked. The
# bar moves only in the tab shown: the others' Spacers are laid out hidden (inline visibility:
# hidden), and their bars moving restyled the page at every frame (240 style recalculations in 4 s
# at rest, 0.3 s of the page's main thread)
TAB_BAR_CSS = """
.bk-headers-wrapper { flex-wrap: wrap; row-gap: 2px; }
.bk-Spacer { min-height: 60px; }
.bk-Spacer::before { content: "Opening the tab…"; display: block; padding: 16px 4px 6px; color: #555; font-style: italic; }
.bk-Spacer::after { content: ""; display: block; height: 6px; width: 240px; margin-left: 4px; border-radius: 3px;
  background: linear-gradient(90deg, #dde7ef 0%, #1f5f8b 50%, #dde7ef 100%); background-size: 200% 100%; }
.bk-Spacer:not([style*="hidden"])::after { animation: bushing-opening 1s linear infinite; }
@keyframes bushing-opening { from { background-position: 100% 0; } to { background-position: -100% 0; } }
"""

# uploads travel in chunks of app.uploads.CHUNK_BYTES (base64 in JSON: 4/3 of it); no other
# message comes near this
UPLOAD_MESSAGE_BYTES = 16 * 1024 * 1024
# a session whose page is closed (or never connected) is discarded, with its memory, after
# SESSION_LIFETIME_S; the server looks every SESSION_CHECK_S
SESSION_LIFETIME_S = 15
SESSION_CHECK_S = 5
# the server's options for them (tests/test_sessions_cleaned.py serves with these)
SESSION_OPTIONS = {"unused_session_lifetime_milliseconds": SESSION_LIFETIME_S * 1000,
                   "check_unused_sessions_milliseconds": SESSION_CHECK_S * 1000}


class Page(pn.template.BootstrapTemplate):
    """Panel's Bootstrap template, its session document built under one freeze of the document's
    models (Bokeh's public ``doc.models.freeze()``): the set of models is computed once, when the
    page is built, instead of after each root added, the theme, and each linked axis (a walk over
    every model of the page each time: measured, 12 to 15 walks of the 536 models per session opened,
    a fifth to a third of the server's CPU per open)."""

    def server_doc(self, doc=None, title=None, location=True):
        doc = doc if doc is not None else pn.state.curdoc
        if doc is None:
            return super().server_doc(doc, title, location)
        with doc.models.freeze():
            return super().server_doc(doc, title, location)


def flat(view: pn.viewable.Viewer) -> list:
    """The items of a view's column, to be placed straight into a tab's column: a HoloViews
    grid nested two columns deep in a tab was laid out with no width (Panel 1.9)."""
    return list(view.__panel__().objects)


class App(pn.viewable.Viewer):
    """One session of the explorer: its own state, inputs, plots and URL.

    The views of the other tabs are built when their tab is first opened (or when code asks
    for them): a page load builds only what it shows. Measured on this machine, building every
    tab's figures took about half of the server's time to answer a first request."""

    # tab title, attribute, builder; the Explorer tab (0) and About are built at once
    LAZY_TABS = (
        ("Slices", "slices", lambda app: SlicesView(app.state)),
        ("Fletcher–Gent, branch by branch", "teaching", lambda app: TeachingView(app.state)),
        ("Measured data and fit", "measured", lambda app: MeasuredView(app.state, app.fit)),
        ("Find the missing effect", "diagnosis", lambda app: DiagnosisView(DiagnosisState(app.state))),
        ("Every direction", "card", lambda app: CardView(app.state, app.fit)),
        ("What-ifs", "whatif", lambda app: WhatIfView(app.state, app.fit)),
    )

    def __init__(self, state: ExplorerState | None = None, **params):
        super().__init__(**params)
        self.state = state or ExplorerState()
        self.fit = FitState(self.state)  # the fit of the session's measured data
        self.inputs = DesignInputs(self.state)
        self.plots = ExplorerPlots(self.state, self.fit)
        self.compare = CompareView(self.state)
        self.export = ExportView(self.state, self.fit)
        self._built: dict[str, pn.viewable.Viewer] = {}
        self._holders = {name: pn.Column(sizing_mode="stretch_width") for _title, name, _build in self.LAZY_TABS}
        self.tabs = pn.Tabs(
            ("Explorer", pn.Column(self.compare, *flat(self.plots), sizing_mode="stretch_width")),
            *((title, self._holders[name]) for title, name, _build in self.LAZY_TABS),
            ("About", pn.pane.Markdown(ABOUT, sizing_mode="stretch_width")),
            dynamic=True,
            sizing_mode="stretch_width",
            stylesheets=[TAB_BAR_CSS],
        )
        self.tabs.param.watch(self._on_tab, "active")
        self._on_tab()

    slices = property(lambda self: self.view("slices"))
    teaching = property(lambda self: self.view("teaching"))
    card = property(lambda self: self.view("card"))
    measured = property(lambda self: self.view("measured"))
    diagnosis = property(lambda self: self.view("diagnosis"))
    whatif = property(lambda self: self.view("whatif"))

    def view(self, name: str):
        """The view of a lazily built tab, built (and put in its tab) on first use."""
        if name not in self._built:
            build = next(b for _title, n, b in self.LAZY_TABS if n == name)
            self._built[name] = build(self)
            self._holders[name].objects = flat(self._built[name])
            self._on_tab()
        return self._built[name]

    def _on_tab(self, *_events):
        active = self.tabs.active
        if 1 <= active <= len(self.LAZY_TABS):
            self.view(self.LAZY_TABS[active - 1][1])
        self.plots.show(active == 0)
        self.compare.show(active == 0)
        for index, (_title, name, _build) in enumerate(self.LAZY_TABS, start=1):
            view = self._built.get(name)
            if isinstance(view, PlotView):
                view.show(index == active)

    def sync_url(self, delay_ms: int = URL_DELAY_MS):
        """Put the whole design in the URL, and read one from it (a shared link, the back
        button): :class:`app.link.UrlLink` on the session's Location."""
        location = pn.state.location
        if location is None:
            return
        self.link = UrlLink(self.state, location, pn.state.curdoc, delay_ms)

    def template(self):
        template = Page(
            title=TITLE,
            sidebar=[self.inputs, pn.Card(self.export, title="Export and share", sizing_mode="stretch_width")],
            main=[status_banner(self.state), self.tabs],
            sidebar_width=380,
            header_background="#1f5f8b",
            busy_indicator=None,  # its animation restyled the page on every change
            design=patches.PageDesign,  # every component styled alike, however late it is built
        )
        return template

    def __panel__(self):
        return pn.Row(pn.Column(self.inputs, self.export, width=360), pn.Column(status_banner(self.state), self.tabs))


def create_app():
    """Factory for one session (served per connection, so sessions never share state)."""
    patches.install(pn.state.curdoc)  # the library hooks (once) and the page's BokehJS patches
    work.quiet_closed_writes()  # a page that closes while a message is written to it: nothing logged
    app = App()
    app.sync_url()
    return app.template()


def _origins(address: str, port: int) -> list[str]:
    extra = [o for o in os.environ.get("BUSHING_ALLOWED_ORIGINS", "").split(",") if o]
    if address in ("0.0.0.0", "::", ""):
        return extra or ["*"]  # bound to every interface: reached by any host name
    return [f"localhost:{port}", f"127.0.0.1:{port}", f"{address}:{port}", *extra]


def serve(port: int = 5006, address: str = "localhost", show: bool = False,
          max_sessions: int = admission.MAX_SESSIONS):
    """Start the explorer (blocking); prints the URL. It builds one page at a time and takes at most
    ``max_sessions`` sessions; a page beyond is told the server is busy (:mod:`app.admission`)."""
    admission.ADMISSION.max_sessions = admission.Admission(max_sessions=max_sessions).max_sessions
    patches.route_sessions(admission.AdmittingDocHandler, admission.AdmittingWSHandler)
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
        websocket_max_message_size=UPLOAD_MESSAGE_BYTES,
        **SESSION_OPTIONS,
    )
    work.use_processes()  # long work (the diagnosis) in worker processes, off the pages' interpreter lock
    collector.freeze_startup_objects()
    host = "localhost" if address in ("0.0.0.0", "::", "") else address
    print(f"Bushing Explorer: http://{host}:{server.port}/", flush=True)
    sys.stdout.flush()
    server.start()
    # full garbage collections between two messages, when the server is quiet (app.collector)
    quiet = collector.collect_when_quiet(lambda look, ms: PeriodicCallback(look, ms).start())
    # SIGTERM (a container's or a service manager's stop) ends the loop as Ctrl-C does, as `bokeh
    # serve` has it: serve returns and the worker processes stop. By default it killed the process
    # and left the workers' forkserver and worker running, orphaned (the worker holds the pipe by
    # which the forkserver would see its parent gone)
    server.io_loop.asyncio_loop.add_signal_handler(signal.SIGTERM, server.io_loop.stop)
    try:
        server.io_loop.start()
    finally:
        quiet.stop()
        work.stop_processes()
