"""The plotting API: HoloViews objects of a bushing design, its operating point and measured data.

Plain functions, the same the explorer draws with; they need no server and work in a notebook::

    import holoviews as hv
    from core import PAPER_B
    from app import plots

    layout = plots.explorer_plots(PAPER_B, frequency_hz=10.0, amplitude=0.1)   # hv.Layout
    hv.save(layout, "paper_b.html")

Every axis is an :class:`holoviews.Dimension` with its name, label and unit
(:func:`app.plotting.style.dimensions`); plots of the same quantity share the dimension, so a layout
links their axes. Axis ranges are set per plot, on clones of the dimensions: nothing built earlier
changes. Importing the API changes nothing global (each plot asks for canvas, not WebGL, itself). Amplitudes are in the display units of :mod:`app.units` (mm axially, rad in
torsion), stiffnesses in kN/mm or N·m/rad, frequencies in Hz.

Two layers, in one builder module per tab of :mod:`app.plotting`: *element builders*
(``loop_overlay``, ``sweep_overlay``, …) turn curves (dicts of arrays from :mod:`app.curves`) into
elements made with the style machinery of :mod:`app.plotting.style`; *design functions*
(``explorer_plots``, ``slices_plots``, …, gathered here) compute the curves of a design and return
finished layouts.
"""

from __future__ import annotations

from .plotting.every_direction import card_plots
from .plotting.explorer import explorer_plots
from .plotting.find_the_missing_effect import diagnosis_plots
from .plotting.fletcher_gent import branch_plots
from .plotting.measured_data_and_fit import residual_plots
from .plotting.slices import slices_plots
from .plotting.style import dimensions

# the public plotting API: the design functions the README and examples/plotting_api.ipynb call,
# and the dimensions they draw on
__all__ = ["branch_plots", "card_plots", "diagnosis_plots", "dimensions", "explorer_plots",
           "residual_plots", "slices_plots"]
