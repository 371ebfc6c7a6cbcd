"""The base of every tab that plots the state: refreshed when what it shows changes, only while
its tab is on screen (a hidden tab catches up when shown), never raising."""

from __future__ import annotations

import numpy as np
import panel as pn
import param

from .curves import amplitude_bounds
from .live import update_or_keep
from .plotting.style import dimensions
from .state import ExplorerState
from .units import OPERATING_FREQUENCIES


class PlotView(pn.viewable.Viewer):
    """Plots of one tab. A subclass declares what it shows with ``@param.depends("state.…",
    watch=True)`` on a method that calls :meth:`changed`, and draws in :meth:`_update`."""

    state = param.ClassSelector(class_=ExplorerState, doc="The session whose design this view plots.")

    def __init__(self, state: ExplorerState, **params):
        self._shown = True
        self._stale = False
        self._mode = None
        self.dims: dict = {}
        super().__init__(state=state, **params)

    def dims_for(self, mode: str) -> dict:
        """The view's dimensions (:func:`app.plotting.style.dimensions`): kept while the mode is, new with
        new units; never changed (each update puts its ranges on clones, :func:`app.plotting.style.ranged`)."""
        if mode != self._mode:
            self.dims, self._mode = dimensions(mode), mode
        return self.dims

    def changed(self):
        if self._shown:
            self.refresh()
        else:
            self._stale = True  # a hidden tab catches up when shown

    def show(self, shown: bool):
        """Tell the view whether its tab is on screen."""
        self._shown = shown
        if shown and self._stale:
            self._stale = False
            self.refresh()

    def refresh(self):
        update_or_keep(f"{type(self).__name__} kept its last plots", self._update)

    def _update(self):
        raise NotImplementedError

    def tap_amplitude(self, x):
        """A tap on an amplitude axis: the operating amplitude moves there (within its range)."""
        if x is not None and np.isfinite(x) and x > 0:
            lo, hi = amplitude_bounds(self.state.design)
            self.state.amplitude = float(np.clip(float(f"{x:.4g}"), lo, hi))

    def tap_frequency(self, x):
        """A tap on a frequency axis: the loop frequency moves there (within its slider)."""
        if x is not None and np.isfinite(x) and x > 0:
            self.state.frequency_hz = float(np.clip(float(f"{x:.4g}"), *OPERATING_FREQUENCIES))
