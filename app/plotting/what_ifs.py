"""The What-ifs tab's plots: the sensitivities at the operating point.
"""

from __future__ import annotations

import holoviews as hv

from .style import (
    canvas,
    png_name,
)


def sensitivity_bars(bars: hv.Bars, title: str, color: str, png: str) -> hv.Bars:
    """Sensitivities as a bar chart, in the order of ``bars`` (:mod:`core.whatif.sensitivity`)."""
    return bars.opts(title=title, color=color, responsive=True, height=260, framewise=True, tools=["hover"],
                     hooks=[canvas, png_name(png)], fontsize={"title": "13px"}, xrotation=0, show_legend=False)
