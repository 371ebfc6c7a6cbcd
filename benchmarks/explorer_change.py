"""The server's cost of one change in the explorer, at the websocket level (issue #26): prints
figures, asserts nothing.

    PYTHONPATH=$PWD python benchmarks/explorer_change.py [--changes 40] [--before REV] [--chromium]

For the explorer of the working tree it starts ``bushing serve --port 0`` (reading the URL it
prints), opens a session with ``bokeh.client.pull_session`` (no browser), sends Panel's
``DocumentReady`` as a page does once it has rendered, and then, ``--changes`` times each:

* moves the drive-amplitude slider (sets its Bokeh model's ``value``, as the browser does),
  cycling over four positions inside its range;
* types a shear modulus into its field (sets the Spinner model's ``value``, as the field does on
  Enter; Panel's ``throttled=False`` answers that at once), cycling over four values.

After each change it waits, polling, until the operating-point text has changed and no document
change has arrived for ``--quiet`` seconds (default 0.4 s, longer than the explorer's 300 ms
debounce of the URL, so each change's URL update is its own); a change that has not answered in
30 s stops the run. Per change it prints, median and p90:

* **server CPU (answer)**: the server process's CPU time (every thread's run time from
  ``/proc/PID/task/*/schedstat``, in ns) from sending the change to the arrival of the last
  document change that answers it (the URL's Location update is not an answer);
* **server CPU (all)**: the same to the end of the quiet period, so the deferred URL update too;
  ``utime+stime`` of ``/proc/PID/stat`` over the whole series / N is printed beside it as a check;
* **answer latency**: ms from sending the change to the last answering document change received.

The session is a browser's as far as the server can tell: its socket sends without Nagle's delay
(TCP_NODELAY, as Chromium's), and the changes received are applied to its document only once the
change has answered, so that the client's own decoding does not delay the reading of the next
message (without these the bare Bokeh floor answered in 75 ms instead of 11 ms).

The floors are measured in the same run, the same way: ``bokeh_floor.py``'s bare Bokeh document
and ``holoviews_floor.py``'s bare HoloViews page (each served by its own script as a
subprocess), whose "Drive amplitude" slider redraws three plots and "Shear modulus" slider every
plot; the condition there is any document change. The HoloViews floor's Panel sliders are made
to answer at once, as the explorer's do (a priority change: no 50 ms debounce). Each explorer
figure is printed with its ratio to each floor's.

``--before REV`` makes a temporary ``git worktree`` of REV, measures that tree's explorer the
same way (served with that tree as the working directory, so its packages are imported), prints
its figures and the ratios now / before, and removes the worktree. ``--chromium`` adds the real
browser's medians: slider to the last plot painted and typed field to the operating-point text
painted (``app_latency.py``'s way: the change set on the page's Bokeh model), and the mode
switch axial ⇄ torsion (the mode buttons' model set, as a click does) to the operating-point text
and every plot painted, each change started once the page's document has been quiet for
``--quiet`` seconds. ``--chromium-only`` skips the websocket level and the floors.

Targets of issue #26: server CPU ≤ 60 ms per amplitude change; Chromium slider-to-screen median
≤ 100 ms; typed field to operating-point text median ≤ 150 ms. Of issue #27 (item 16): mode
switch to screen median ≤ 300 ms.

The figures of the issue come from the one command (REV: the commit before the work on #26,
7298e26; without ``--before`` only the working tree and the floors)::

    PYTHONPATH=$PWD /work/main/.venv/bin/python benchmarks/explorer_change.py --chromium --before REV

About five minutes on the 2-core machine; the figures move by some ±8 % between runs of one tree
(``--before HEAD`` measures that noise), more when another job shares the cores.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import glob
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from app_latency import cpu_seconds, pct
from servers import start_explorer, start_floor, stop

AMPLITUDE, SHEAR = "Drive amplitude", "Shear modulus"
KINDS = (("amplitude", AMPLITUDE, "slider"), ("field", SHEAR, "typed field"))
TIMEOUT_S = 30.0


def cpu_ns(pid: int) -> int:
    """Run time of every thread of process ``pid`` so far, in ns (Linux schedstat)."""
    total = 0
    for path in glob.glob(f"/proc/{pid}/task/*/schedstat"):
        try:
            with open(path) as f:
                total += int(f.read().split()[0])
        except (OSError, ValueError, IndexError):
            pass  # a thread that has just ended
    return total


def changes(message, model_id: str, attr: str) -> bool:
    """Whether a PATCH-DOC message sets ``attr`` of the model ``model_id``."""
    return any(e.get("kind") == "ModelChanged" and (e.get("model") or {}).get("id") == model_id
               and e.get("attr") == attr for e in message.content.get("events", []))


class Session:
    """One websocket session on ``url``, served by process ``pid``: its document as a browser
    would hold it, and every document change it receives, timed."""

    def __init__(self, url: str, pid: int, quiet: float, nodelay: bool = True):
        import panel.models  # noqa: F401 - Panel's models, so the document can be read
        from bokeh.client import pull_session
        from bokeh.events import DocumentReady

        self.pid, self.quiet = pid, quiet
        self.session = pull_session(url=url)
        self.doc = self.session.document
        self.conn = self.session._connection
        self.loop = self.conn.io_loop
        if nodelay:  # as a browser: Chromium sends every frame at once (no Nagle delay)
            self.conn._socket._socket.protocol.set_nodelay(True)
        # (time, only the URL, server CPU ns, message) of each document change received; applied to
        # the document only once the change has answered, so that the client's own work (NumPy
        # arrays decoded, models updated) does not delay the reading of the next message
        self.arrivals: list[tuple[float, bool, int, object]] = []
        self._apply = self.session._handle_patch
        # messages are read for as long as the loop runs (run_sync below), in a loop: Bokeh's own
        # reader recurses once per message and ends in a RecursionError after a few hundred
        self.loop.add_callback(self._read)
        self.doc.callbacks.send_event(DocumentReady())  # what a page sends once rendered
        t0 = time.perf_counter()
        self.loop.run_sync(lambda: self._settle(lambda: time.perf_counter() - t0 > 2 * quiet, t0))
        self._apply_received()

    def _apply_received(self):
        for *_figures, message in self.arrivals:
            self._apply(message)

    async def _read(self):
        while (message := await self.conn._pop_message()) is not None:
            if message.msgtype == "PATCH-DOC":
                self.arrivals.append((time.perf_counter(), self._only_url(message), cpu_ns(self.pid), message))

    def _only_url(self, message) -> bool:
        ids = {m.id for m in self.doc.models if type(m).__name__ == "Location"}
        events = message.content.get("events", [])
        return bool(events) and all((e.get("model") or {}).get("id") in ids for e in events)

    async def _settle(self, condition, t0: float):
        while True:
            now = time.perf_counter()
            last = max([t0] + [a[0] for a in self.arrivals])
            if condition() and now - last >= self.quiet:
                return
            if now - t0 > TIMEOUT_S:
                raise TimeoutError(f"no answer within {TIMEOUT_S:.0f} s")
            await asyncio.sleep(0.003)

    def model(self, label: str):
        """The widget model whose title (or label) starts with ``label``."""
        for m in self.doc.models:
            for attr in ("title", "label"):
                text = getattr(m, attr, None) if attr in m.properties() else None
                if isinstance(text, str) and text.startswith(label) and "value" in m.properties():
                    return m
        raise LookupError(f"no widget titled {label!r} in the document")

    def operating_text(self):
        """The operating-point text's model (the explorer's), or None (a floor)."""
        return next((m for m in self.doc.models if "operating-point" in (getattr(m, "css_classes", None) or [])),
                    None)

    def change(self, model, value) -> dict:
        """Set ``model.value`` as the page would and wait for the answer; CPU ms and latency ms."""
        text = self.operating_text()
        if text is not None:
            def answered():
                return any(changes(a[3], text.id, "text") for a in self.arrivals)
        else:
            def answered():
                return any(not a[1] for a in self.arrivals)
        self.arrivals = []
        c0, t0 = cpu_ns(self.pid), time.perf_counter()
        model.value = str(value) if isinstance(model.value, str) else value  # a typed field (TextInput) holds text
        self.loop.run_sync(lambda: self._settle(answered, t0))
        c1 = cpu_ns(self.pid)
        self._apply_received()
        answer = [a for a in self.arrivals if not a[1]]
        t_last, _url, c_last, _message = answer[-1]
        return {"cpu": (c_last - c0) / 1e6, "cpu_all": (c1 - c0) / 1e6, "latency": 1000 * (t_last - t0)}

    def close(self):
        self.session.close()


def positions(model, n: int) -> list[float]:
    """``n`` values cycling over four inside the widget's range, none equal to the last."""
    start = getattr(model, "start", None) if "start" in model.properties() else getattr(model, "low", None)
    end = getattr(model, "end", None) if "end" in model.properties() else getattr(model, "high", None)
    v = float(model.value)
    if start is None or end is None:  # an open field: around its value
        cycle = [v * f for f in (0.8, 0.9, 1.1, 1.2)]
    else:
        cycle = [start + f * (end - start) for f in (0.3, 0.45, 0.6, 0.75)]
    return [round(cycle[i % 4], 4) for i in range(n)]


def series(session: Session, label: str, n: int, warmup: int = 4) -> dict:
    """``n`` changes of the widget titled ``label`` (after ``warmup``), each figure a list."""
    model = session.model(label)
    values = positions(model, warmup + n)
    for v in values[:warmup]:
        session.change(model, v)
    s0 = cpu_seconds(session.pid)
    rows = [session.change(model, v) for v in values[warmup:]]
    out = {k: [r[k] for r in rows] for k in rows[0]}
    out["stat_ms"] = 1000 * (cpu_seconds(session.pid) - s0) / n
    return out


def measure_server(proc: subprocess.Popen, url: str, n: int, quiet: float) -> dict:
    """Both kinds of change on one fresh session of the server ``proc`` at ``url``."""
    try:
        session = Session(url, proc.pid, quiet)
        try:
            return {kind: series(session, label, n) for kind, label, _what in KINDS}
        finally:
            session.close()
    finally:
        stop(proc)


def line(name: str, r: dict):
    med, p90 = statistics.median, (lambda v: pct(v, 90))
    print(f"  {name:<26} CPU answer {med(r['cpu']):6.1f} ms (p90 {p90(r['cpu']):6.1f})   "
          f"CPU all {med(r['cpu_all']):6.1f} ms (stat/N {r['stat_ms']:5.1f})   "
          f"latency {med(r['latency']):6.1f} ms (p90 {p90(r['latency']):6.1f})")


EXPLORER_ROWS = ("drive amplitude slider", "shear modulus field")
FLOOR_ROWS = ("drive amplitude slider", "shear modulus slider")


def report(title: str, figures: dict, rows=EXPLORER_ROWS):
    print(title)
    for (kind, _label, _what), row in zip(KINDS, rows, strict=True):
        line(row, figures[kind])


def ratios(title: str, a: dict, b: dict):
    med = statistics.median
    print(title)
    for (kind, _label, _what), row in zip(KINDS, EXPLORER_ROWS, strict=True):
        x, y = a[kind], b[kind]
        print(f"  {row:<26} CPU answer {med(x['cpu']) / med(y['cpu']):5.2f}   "
              f"CPU all {med(x['cpu_all']) / med(y['cpu_all']):5.2f}   "
              f"latency {med(x['latency']) / med(y['latency']):5.2f}")


def explorer(cwd: Path, n: int, quiet: float) -> dict:
    proc, url = start_explorer(cwd)
    return measure_server(proc, url, n, quiet)


@contextlib.contextmanager
def worktree(rev: str):
    """A temporary ``git worktree`` of ``rev`` (detached), removed on leaving."""
    root = Path(subprocess.check_output(["git", "rev-parse", "--show-toplevel"], cwd=HERE, text=True).strip())
    tree = Path(tempfile.mkdtemp(prefix="explorer-before-"))
    subprocess.run(["git", "worktree", "add", "--detach", "--quiet", str(tree), rev], cwd=root, check=True)
    try:
        yield tree
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=root, check=False)
        shutil.rmtree(tree, ignore_errors=True)


# Chromium: the page's own clock, from setting the model to the operating-point text painted
TEXT_JS = """async ([title, value]) => {
  const doc = Bokeh.documents[0];
  const model = [...doc.all_models].find(m => m.title === title || m.label === title);
  const text = [...doc.all_models].find(m => (m.css_classes || []).includes('operating-point'));
  const before = text.text;
  const t0 = performance.now();
  model.value = typeof model.value === 'string' ? String(value) : value;  // a typed field (TextInput) holds text
  const t = await new Promise(resolve => {
    const tick = () => {
      if (text.text !== before) requestAnimationFrame(() => resolve(performance.now()));
      else if (performance.now() - t0 > 20000) resolve(null);
      else setTimeout(tick, 2);
    };
    tick();
  });
  return t === null ? null : t - t0;
}"""


# Chromium: a mode switch (the mode buttons' model set to ``index``, as a click does) to the
# operating-point text and every plot painted: the time of the later of the text's paint and the
# last plot change's paint (a plot change followed by ``quiet`` ms without one ends the wait)
MODE_JS = """async ([index, quiet]) => {
  const doc = Bokeh.documents[0];
  const buttons = [...doc.all_models].find(m => (m.labels || []).includes('torsion') && m.active !== undefined);
  const text = [...doc.all_models].find(m => (m.css_classes || []).includes('operating-point'));
  const PLOT = new Set(['ColumnDataSource', 'DataRange1d', 'Range1d', 'Span', 'LegendItem', 'Legend', 'LinearAxis',
                        'LogAxis', 'Title', 'Figure']);
  const before = text.text;
  let lastPaint = null, lastChange = null, textPaint = null;
  const cb = (ev) => {
    if (!ev.model || !PLOT.has(ev.model.type)) return;
    lastChange = performance.now();
    requestAnimationFrame(() => { lastPaint = performance.now(); });
  };
  doc.on_change(cb);
  const t0 = performance.now();
  buttons.active = index;
  const ok = await new Promise(resolve => {
    const tick = () => {
      if (textPaint === null && text.text !== before) {
        textPaint = -1;
        requestAnimationFrame(() => { textPaint = performance.now(); });
      }
      if (textPaint > 0 && lastChange !== null && performance.now() - lastChange > quiet && lastPaint >= lastChange)
        resolve(true);
      else if (performance.now() - t0 > 20000) resolve(false);
      else setTimeout(tick, 2);
    };
    tick();
  });
  doc.remove_on_change(cb);
  return ok ? Math.max(lastPaint, textPaint) - t0 : null;
}"""


# wait until the page's document has had no change for ``quiet`` ms (the last change's plots and
# its URL update drawn), then one animation frame: the next change starts on an idle page
QUIET_JS = """async (quiet) => {
  const doc = Bokeh.documents[0];
  let last = performance.now();
  const cb = () => { last = performance.now(); };
  doc.on_change(cb);
  await new Promise(resolve => {
    const tick = () => performance.now() - last > quiet ? requestAnimationFrame(resolve) : setTimeout(tick, 10);
    tick();
  });
  doc.remove_on_change(cb);
}"""


async def chromium(cwd: Path, n: int, quiet: float, modes: int | None = None) -> dict:
    """Medians in Chromium: the slider to the last plot painted (app_latency.py's CHANGE_JS),
    the typed shear modulus to the operating-point text painted, and ``modes`` (default ``n``)
    mode switches, axial ⇄ torsion, to the text and every plot painted (:data:`MODE_JS`)."""
    modes = n if modes is None else modes
    from app_latency import ARGS, CHANGE_JS, CHROMIUM, open_page
    from playwright.async_api import async_playwright

    proc, url = start_explorer(cwd)
    try:
        async with async_playwright() as p:
            browser = await p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            page, _load = await open_page(browser, url)
            titles = await page.evaluate("""() => [...Bokeh.documents[0].all_models].map(m => m.title)
                .filter(t => typeof t === 'string')""")
            slider = next(t for t in titles if t.startswith(AMPLITUDE))
            field = next(t for t in titles if t.startswith(SHEAR))
            lo, hi = await page.evaluate("""(t) => { const m = [...Bokeh.documents[0].all_models]
                .find(m => m.title === t); return [m.start, m.end]; }""", slider)
            amps = [round(lo + f * (hi - lo), 4) for f in (0.3, 0.45, 0.6, 0.75)]
            out = {"slider": [], "field": [], "mode": []}
            for i in range(n + 2):  # two warm-up changes of each
                ms = await page.evaluate(CHANGE_JS, [slider, amps[i % 4], 150])
                await page.evaluate(QUIET_JS, 1000 * quiet)
                typed = await page.evaluate(TEXT_JS, [field, round(2.0 + 0.1 * (i % 4), 3)])
                await page.evaluate(QUIET_JS, 1000 * quiet)
                if ms is None or typed is None:
                    raise RuntimeError("Chromium: no answer within 20 s")
                if i >= 2:
                    out["slider"].append(ms)
                    out["field"].append(typed)
            for i in range(modes + 2):  # axial → torsion → axial …, two warm-up switches
                switched = await page.evaluate(MODE_JS, [(i + 1) % 2, 150])
                await page.evaluate(QUIET_JS, 1000 * quiet)
                if switched is None:
                    raise RuntimeError("Chromium: no answer to a mode switch within 20 s")
                if i >= 2:
                    out["mode"].append(switched)
            await browser.close()
    finally:
        stop(proc)
    print(f"  slider to screen           median {statistics.median(out['slider']):6.1f} ms "
          f"(p90 {pct(out['slider'], 90):6.1f})   target ≤ 100 ms")
    print(f"  typed field to text        median {statistics.median(out['field']):6.1f} ms "
          f"(p90 {pct(out['field'], 90):6.1f})   target ≤ 150 ms")
    if out["mode"]:
        print(f"  mode switch to screen      median {statistics.median(out['mode']):6.1f} ms "
              f"(p90 {pct(out['mode'], 90):6.1f})   target ≤ 300 ms")
    return out


def measure_tree(name: str, cwd: Path, n: int, quiet: float, with_chromium: bool, websocket: bool = True) -> dict:
    """The explorer of the tree at ``cwd``, at the websocket level (unless not ``websocket``) and
    (optionally) in Chromium."""
    out = {}
    if websocket:
        out["ws"] = explorer(cwd, n, quiet)
        report(f"explorer ({name}), websocket level:", out["ws"])
        print(f"  target: server CPU per amplitude change ≤ 60 ms: "
              f"{statistics.median(out['ws']['amplitude']['cpu']):.1f} ms (median, answer)")
    if with_chromium:
        print(f"explorer ({name}), Chromium:")
        out["chromium"] = asyncio.run(chromium(cwd, n, quiet))
    return out


def main(n: int, quiet: float, rev: str | None, with_chromium: bool, floors: bool, websocket: bool = True):
    print(f"{n} changes of each kind after 4 warm-up changes; a change has answered when the "
          f"document has been quiet for {quiet:.2f} s; CPU and latency in ms per change")
    now = measure_tree("working tree", HERE.parent, n, quiet, with_chromium, websocket)
    if floors and websocket:
        for name, script in (("bare Bokeh floor", "bokeh_floor.py"), ("bare HoloViews floor", "holoviews_floor.py")):
            proc, url = start_floor(script)
            floor = measure_server(proc, url, n, quiet)
            report(f"{name}, websocket level:", floor, FLOOR_ROWS)
            ratios(f"explorer / {name}:", now["ws"], floor)
    if rev:
        with worktree(rev) as tree:
            old = measure_tree(f"before, {rev}", tree, n, quiet, with_chromium, websocket)
        if websocket:
            ratios(f"now / before ({rev}), websocket level:", now["ws"], old["ws"])
        if with_chromium:
            print(f"now / before ({rev}), Chromium medians: "
                  + "   ".join(f"{k} {statistics.median(now['chromium'][k]) / statistics.median(old['chromium'][k]):.2f}"
                             for k in ("slider", "field", "mode") if now["chromium"][k] and old["chromium"][k]))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--changes", type=int, default=40, help="changes of each kind (default 40)")
    ap.add_argument("--quiet", type=float, default=0.4, help="seconds without a document change (default 0.4)")
    ap.add_argument("--before", metavar="REV", help="also measure the explorer of this git revision")
    ap.add_argument("--chromium", action="store_true", help="also the medians in Chromium")
    ap.add_argument("--no-floors", dest="floors", action="store_false", help="skip the bare floors")
    ap.add_argument("--chromium-only", action="store_true", help="only the Chromium medians (no websocket level)")
    a = ap.parse_args()
    main(a.changes, a.quiet, a.before, a.chromium or a.chromium_only, a.floors, websocket=not a.chromium_only)
