"""The one place where the app uses a library's private internals (each measured to matter).

Checked against Panel 1.9 and Bokeh 3.9 (``pyproject.toml`` pins ``panel<1.10`` and
``bokeh<3.10``); ``tests/test_app.py`` fails if an internal is gone or no longer takes effect.

**Model recomputation.** Every HoloViews plot update freezes the Bokeh document's models, and
Bokeh recomputes the set of models (a walk over every model's properties) whenever the last
freeze ends, whether or not the model graph changed. Measured on the explorer's page (536
models): 24 ms per recomputation, a fifth of the server's time per change, spent on changes that
add no model (data, ranges, a marker). :func:`frozen_models` freezes the models for a whole
change and recomputes them at its end only if something asked for it (``invalidate``, which Bokeh
calls when a property change adds or removes models). Upstream, Bokeh's
``DocumentModelManager`` could do the same: remember an ``invalidate`` while frozen, and
recompute at the last unfreeze only then (``add_root`` and ``remove_root`` would invalidate
explicitly).

**MathJax.** Panel 1.9 sends Bokeh's MathJax bundle (1.8 MB, the largest script of the page) whenever the
page holds an HTML pane, in case one holds math (holoviz/panel#8424; holoviz/panel#8179 would
load it late instead). The explorer's texts hold none: the bundle is sent only to a page whose
texts have math delimiters. Measured here: about 0.1 s of each page load.
"""

from __future__ import annotations

import contextlib
import re

from panel.io import resources as panel_resources
from panel.models.markup import HTML as PanelHTML

MATH_DELIMITERS = re.compile(r"\$\$|\\\(|\\\[")
PATCHED = hasattr(panel_resources, "_panel_use_mathjax")


def holds_math(roots) -> bool:
    """Whether any Panel HTML model under ``roots`` has text with math delimiters."""
    return any(isinstance(model, PanelHTML) and MATH_DELIMITERS.search(model.text or "")
               for root in roots for model in root.references())


if PATCHED:
    panel_resources._panel_use_mathjax = holds_math


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
