"""Colours and labels shared by the explorer's figures: drawing conventions only."""

from __future__ import annotations

BRANCH_COLORS = {"elastic": "#1f77b4", "viscoelastic": "#2ca02c", "friction": "#d62728"}
OPERATING_COLOR = "#e6550d"
REFERENCE_STYLE = {"color": "#444444", "line_dash": "dashed", "line_width": 2}
SLICE_COLORS = {1: "#1f77b4", 2: "#ff7f0e", 3: "#2ca02c", "continuum": "#9467bd"}
SWEEP_PALETTES = {  # light to dark as the swept value grows
    "amplitude": ["#9ecae1", "#6baed6", "#3182bd", "#08519c", "#08306b"],
    "frequency": ["#a1d99b", "#41ab5d", "#006d2c", "#00441b", "#002910"],
}


def sweep_label(value, unit):
    return f"{value:.3g} {unit}"
