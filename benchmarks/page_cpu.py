"""The server's CPU for one explorer page, built and serialised in process: prints figures,
asserts nothing.

    PYTHONPATH=$PWD python benchmarks/page_cpu.py [--builds 8] [--without-cached-defaults]

Builds the explorer's session document as the server does for a new page (``app.main.create_app``
and the template's ``server_doc`` into a fresh Bokeh ``Document``), serialises it (``to_json``, what
the page pulls), ``--builds`` times after two warm-up builds, and prints the median, the spread and
the count of Bokeh models. ``--without-cached-defaults`` puts Bokeh's own property-default lookups
back (``app.patches.cache_immutable_defaults`` undone) to measure what the cache saves: run both,
back to back, on an idle machine.
"""

from __future__ import annotations

import argparse
import statistics
import time


def build():
    import panel as pn
    from bokeh.document import Document

    from app.main import create_app

    doc = Document()
    pn.state.curdoc = doc
    create_app().server_doc(doc)
    doc.to_json()
    return doc


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--builds", type=int, default=8)
    ap.add_argument("--without-cached-defaults", action="store_true")
    a = ap.parse_args(argv)
    if not 1 <= a.builds <= 100:
        raise SystemExit("page_cpu: --builds 1..100")
    from app import patches

    patches.install()
    if a.without_cached_defaults:
        from bokeh.core.property.bases import Property
        from bokeh.core.property.descriptors import PropertyDescriptor

        Property.themed_default = Property.themed_default.original
        PropertyDescriptor.has_unstable_default = PropertyDescriptor.has_unstable_default.original
    for _ in range(2):
        build()
    times = []
    for _ in range(a.builds):
        t0 = time.process_time()
        doc = build()
        times.append(1000 * (time.process_time() - t0))
    label = "Bokeh's own defaults" if a.without_cached_defaults else "cached defaults"
    print(f"explorer page, {label}: {statistics.median(times):.0f} ms CPU median of {a.builds} "
          f"(min {min(times):.0f}, max {max(times):.0f}); {len(doc.models)} Bokeh models")


if __name__ == "__main__":
    main()
