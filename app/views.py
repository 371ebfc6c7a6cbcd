"""The base of every tab that plots the state: refreshed when what it shows changes, only while
its tab is on screen (a hidden tab catches up when shown), never raising."""

from __future__ import annotations

import numpy as np
import panel as pn
import param

from .curves import amplitude_bounds
from .live import update_or_keep
from .plotting.style import dimensions
from .state import SHOWN, ExplorerState
from .units import OPERATING_FREQUENCIES


def _same(a, b) -> bool:
    """Whether two values a view draws are the same (the same object, or equal; values that
    cannot say, such as arrays, are not)."""
    if a is b:
        return True
    try:
        return bool(a == b)
    except (TypeError, ValueError):
        return False


class PlotView(pn.viewable.Viewer):
    """Plots of one tab. A subclass names what it shows (:attr:`shows`, keys of
    :data:`app.state.SHOWN`, and :attr:`own`, its own parameters) and draws in :meth:`_update`;
    it is refreshed once per change of those values, while its tab is visible (a hidden tab
    catches up when shown), and not at all when a change leaves them as they were drawn."""

    state = param.ClassSelector(class_=ExplorerState, doc="The session whose design this view plots.")
    shows: tuple[str, ...] = ()
    own: tuple[str, ...] = ()

    def __init__(self, state: ExplorerState, **params):
        self._shown = True
        self._stale = False
        self._mode = None
        self._drawn: tuple | None = None  # the values drawn last
        self.dims: dict = {}
        super().__init__(state=state, **params)
        for owner, names in self._sources().items():
            owner.param.watch(self._on_change, list(names))

    @classmethod
    def watched(cls) -> tuple[str, ...]:
        """The parameters the view draws from: the state's (:data:`app.state.SHOWN`; the fit's as
        ``fit.NAME``) and its own (:attr:`own`, as ``self.NAME``)."""
        return (*(name for key in cls.shows for name in SHOWN[key]), *(f"self.{n}" for n in cls.own))

    def _owner(self, name: str):
        """The object holding a parameter of :meth:`watched`, and the parameter's own name."""
        owner, _, own = name.rpartition(".")
        return {"": self.state, "self": self}.get(owner) or getattr(self, owner), own

    def _sources(self) -> dict:
        out: dict = {}
        for name in self.watched():
            owner, own = self._owner(name)
            out.setdefault(owner, []).append(own)
        return out

    def values(self) -> tuple:
        """The values the view draws from, now."""
        return tuple(getattr(*self._owner(name)) for name in self.watched())

    def _on_change(self, *_events):
        self.changed()

    def draw(self):
        """Draw the view's current values (the first time, outside a held document: held, new panes
        are laid out wrong)."""
        self._drawn = self.values()
        self._update()

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
        """Draw the current values, unless they are those drawn last (a change that reached the
        view twice, or one that left its values as they were)."""
        values = self.values()
        if self._drawn is not None and len(values) == len(self._drawn) and all(map(_same, values, self._drawn)):
            return
        self._drawn = values
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
