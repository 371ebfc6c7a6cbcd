"""Small helpers shared by tests: the command line run in process, a server started."""

import asyncio
import concurrent.futures
import contextlib
import queue
import threading
import urllib.request


def run(argv, capsys):
    """``bushing argv`` run in process: (exit status, standard output, standard error)."""
    from cli.main import main  # the `bushing` entry point

    try:
        status = main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


def fetch(url: str, timeout: float = 60.0) -> bytes:
    """The body of ``url`` (one request, no retry): for a server whose socket already listens,
    the request waits in the listen backlog until the server answers."""
    with urllib.request.urlopen(url, timeout=timeout) as r:
        assert r.status == 200, (url, r.status)
        return r.read()


def off_the_loop(function, *args):
    """``function(*args)``; in a thread of its own when this thread runs an event loop (a test
    process that ran a browser test: Playwright's synchronous API keeps one running in the main
    thread), where ``asyncio.run`` and a second ``sync_playwright()`` refuse to start."""
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return function(*args)
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        return pool.submit(function, *args).result()


def run_async(coro):
    """``asyncio.run(coro)`` in any test process (:func:`off_the_loop`)."""
    return off_the_loop(asyncio.run, coro)


@contextlib.contextmanager
def served(app_factory, **kwargs):
    """``app_factory`` served by Panel on 127.0.0.1 at a port the OS picks, in a thread with its
    own event loop: yields the Bokeh server (``server.port``), stopped and its thread joined on
    exit. The socket is bound before this yields, so there is nothing to wait for (and no "find
    a free port, then bind it" race). Without ``websocket_origin``, Bokeh accepts pages from
    ``localhost:<port>``: open ``http://localhost:<port>/``."""
    import panel as pn
    from tornado.ioloop import IOLoop

    made = queue.Queue()

    def run():
        asyncio.set_event_loop(asyncio.new_event_loop())
        try:
            server = pn.serve(app_factory, port=0, address="127.0.0.1", show=False, start=False,
                              loop=IOLoop.current(), **kwargs)
        except BaseException as exc:  # noqa: BLE001 - handed to the test's thread
            made.put(exc)
            return
        made.put(server)
        server.start()
        server.io_loop.start()  # until stop() below
        server.io_loop.close(all_fds=True)

    thread = threading.Thread(target=run, name="served", daemon=True)
    thread.start()
    server = made.get(timeout=120)
    if isinstance(server, BaseException):
        raise server

    def stop():
        server.stop()
        server.io_loop.stop()

    try:
        yield server
    finally:
        server.io_loop.add_callback(stop)
        thread.join(60)
        assert not thread.is_alive(), "the server's thread did not stop"


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
