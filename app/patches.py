"""The one place where the app changes a library's private internals (measured to matter).

Checked against Panel 1.9 (``pyproject.toml`` pins ``panel<1.10``); ``tests/test_app.py``
fails if the internal is gone or the patch no longer takes effect.

Panel 1.9 sends Bokeh's MathJax bundle (1.8 MB, the largest script of the page) whenever the
page holds an HTML pane, in case one holds math (holoviz/panel#8424; holoviz/panel#8179 would
load it late instead). The explorer's texts hold none: the bundle is sent only to a page whose
texts have math delimiters. Measured here: about 0.1 s of each page load.
"""

from __future__ import annotations

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
