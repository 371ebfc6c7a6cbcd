"""The Fletcher–Gent tab: how the elastic, viscoelastic and friction branches make up the
stiffness as the amplitude grows, and the loop changing shape as a player sweeps the amplitude."""

from __future__ import annotations

import numpy as np
import panel as pn

from core.numbers import format_number, format_value

from ..curves import amplitude_bounds, amplitude_grid, branch_breakdown, hysteresis_loop, padded
from ..live import LivePlot, update_or_keep
from ..plotting.fletcher_gent import branch_overlays, loop_shape_overlay
from ..plotting.style import ranged
from ..shapes import shape_pane
from ..state import ExplorerState
from ..units import amplitude_unit
from ..views import PlotView
from .slices import same_mode_reference

TEACHING_TEXT = """
**Why filled rubber softens and dissipates more as the amplitude grows.** The stress is the sum of
three branches driven by the same strain. The **elastic** branch (blue) is a spring: it stores and
gives back. The **viscoelastic** branch (green) depends on the rate: it adds stiffness and a
constant share of loss at every amplitude. The **friction** branch (red) is the carbon-black
filler network: at small amplitude it is stiff and nearly elastic; as the amplitude passes ε½ it
slips, its stiffness falls away and it dissipates most, hence the loss factor's peak; at large
amplitude it saturates at σ_fmax and both its stiffness and its share of the loss fade. The player
starts at the operating amplitude; press play to watch the loop change shape: a thin ellipse at
small amplitude, a fat friction loop near the knee, a sheared parallelogram at large amplitude.
"""


WHICH = ("real", "loss")


class TeachingView(PlotView):
    """The Fletcher–Gent effect branch by branch, and the loop changing as amplitude sweeps."""

    shows = ("design", "frequency", "amplitude", "reference")

    FRAMES = 48

    def __init__(self, state: ExplorerState, **params):
        super().__init__(state, **params)
        self.player = pn.widgets.Player(
            label="Amplitude sweep", start=0, end=self.FRAMES - 1, value=self.FRAMES // 2,
            loop_policy="loop", interval=150, show_value=False, show_loop_controls=False,
            sizing_mode="stretch_width",
        )
        self.frame_label = pn.pane.HTML("", css_classes=["loop-frame"], margin=(0, 10))
        self.branches: LivePlot | None = None
        self.loop: LivePlot | None = None
        self._following = False  # the player moved to the operating amplitude by the view itself
        self.player.param.watch(lambda _e: None if self._following else self._frame(), "value")
        self.draw()

    def frame(self, which: str):
        """What a plot shows now: "real", "loss" (the branches) or "loop" (the loop's shape)."""
        return self.loop.current[0] if which == "loop" else self.branches.current[WHICH.index(which)]

    def _update(self):
        s = self.state
        d = branch_breakdown(s.design, s.frequency_hz, amplitude_grid(s.design, 80))
        reference = same_mode_reference(s, d["amplitude"])
        totals = {which: [sum(b[which].values()) for b in (d, reference) if b is not None] for which in WHICH}
        dims = ranged(self.dims_for(self.state.design.mode), {
            "amplitude": padded([d["amplitude"]], log=True), "real": padded([np.zeros(1), *totals["real"]]),
            "branch_loss": padded([np.zeros(1), *totals["loss"]])})
        overlays = branch_overlays(d, dims, self.state.amplitude, reference)
        items = [overlays[w] for w in WHICH]
        self.branches = LivePlot.shown(self.branches, items, taps={0: self.tap_amplitude, 1: self.tap_amplitude})
        self._following = True  # the player starts again at the operating amplitude
        try:
            self.player.value = self.frames()[1]
        finally:
            self._following = False
        self._draw_frame()

    def frames(self) -> tuple[np.ndarray, int]:
        """The player's amplitudes (display units): :attr:`FRAMES` spread evenly on a log scale
        over the amplitude axis, the one nearest the operating amplitude replaced by it; and
        that frame's index."""
        s = self.state
        xs = np.geomspace(*amplitude_bounds(s.design), self.FRAMES)
        at = int(np.argmin(np.abs(np.log(xs) - np.log(s.amplitude))))
        xs[at] = s.amplitude
        return xs, at

    def _frame(self):
        update_or_keep("TeachingView kept its last frame", self._draw_frame)

    def _draw_frame(self):
        s = self.state
        xs, at = self.frames()
        x = xs[self.player.value]
        shape = loop_shape_overlay(hysteresis_loop(s.design, s.frequency_hz, x), self.dims)
        self.loop = LivePlot.shown(self.loop, [shape])
        where = " (the operating amplitude)" if self.player.value == at else ""
        self.frame_label.object = (f'<span class="frame-point">Loop shape at <b>{format_number(x, "amplitude")} '
                                   f"{amplitude_unit(s.design.mode)}</b>{where}, "
                                   f"{format_value(s.frequency_hz, 'Hz', 'frequency')}</span>")

    def __panel__(self):
        return pn.Column(
            pn.pane.Markdown(TEACHING_TEXT, sizing_mode="stretch_width"),
            shape_pane(self.state),
            pn.Row(
                pn.Column(*self.branches.panes, sizing_mode="stretch_width"),
                pn.Column(self.player, self.frame_label, self.loop.pane, sizing_mode="stretch_width"),
                sizing_mode="stretch_width",
            ),
            sizing_mode="stretch_width",
        )
