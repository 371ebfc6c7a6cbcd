"""The Slices tab: Paper A's sliced bushing against the single equivalent modulus."""

from __future__ import annotations

import numpy as np
import panel as pn

from core.numbers import format_signed, format_value

from ..curves import amplitude_grid, branch_breakdown, padded, slice_comparison
from ..live import LivePlot
from ..plotting.slices import SLICE_NAMES, slices_overlays
from ..plotting.style import ranged
from ..shapes import shape_pane
from ..state import ExplorerState
from ..units import amplitude_unit
from ..views import PlotView

WHICH = ("magnitude", "magnitude_diff_pct", "loss_factor")


class SlicesView(PlotView):
    """One equivalent modulus against 2 and 3 slices and the continuum, at the loop frequency."""

    shows = ("design", "frequency", "amplitude", "reference")

    NAMES = SLICE_NAMES

    def __init__(self, state: ExplorerState, **params):
        super().__init__(state, **params)
        self.table = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.plots: LivePlot | None = None
        self.draw()

    def frame(self, which: str):
        return self.plots.current[WHICH.index(which)]

    def _update(self):
        s = self.state
        data = slice_comparison(s.design, s.frequency_hz, amplitude_grid(s.design, 60))
        dims = ranged(self.dims_for(self.state.design.mode), {"amplitude": padded([data["amplitude"]], log=True)})
        reference = same_mode_reference(s, data["amplitude"])
        overlays = slices_overlays(data, dims, self.state.amplitude, reference)
        items = [overlays[w] for w in WHICH]
        self.plots = LivePlot.shown(self.plots, items, taps={i: self.tap_amplitude for i in range(len(WHICH))})
        self.table.object = self.summary(data)

    def summary(self, data):
        xs, unit = data["amplitude"], amplitude_unit(self.state.design.mode)
        rows = ["| model | largest \\|K\\| difference | largest loss-factor difference |", "|---|---|---|"]
        for s in (2, 3, "continuum"):
            if s in data["magnitude_diff_pct"]:
                dm, de = data["magnitude_diff_pct"][s], data["loss_factor_diff_pct"][s]
                im, ie = int(np.argmax(np.abs(dm))), int(np.argmax(np.abs(de)))
                rows.append(f"| {self.NAMES[s]} | {format_signed(dm[im], 2)} % at {format_value(xs[im], unit, 'amplitude')} "
                            f"| {format_signed(de[ie], 2)} % at {format_value(xs[ie], unit, 'amplitude')} |")
        missing = [self.NAMES[s] for s in (2, 3, "continuum") if s not in data["magnitude"]]
        design = self.state.design
        if data["refused"]:
            rows.append(f"\n_Slices and the continuum are derived for axial and torsion bushings with the "
                        f"long (closed-form) shape factors; this design is {design.mode} with the "
                        f"{design.shape_kind} shape: only the single modulus is shown._")
        elif missing:
            rows.append(f"\n_Not shown, the iteration did not converge: {', '.join(missing)}._")
        return "\n".join(rows)

    def __panel__(self):
        return pn.Column(
            pn.pane.Markdown(
                "Paper A splits the rubber into concentric slices of equal thickness, each with "
                "its own equivalent strain; the continuum takes infinitely many. The single "
                "equivalent modulus (eqs 17/18) is close when the differences below are small. "
                "All at the loop frequency; tap a plot to move the amplitude.", sizing_mode="stretch_width"),
            shape_pane(self.state),
            self.table,
            *self.plots.panes,
            sizing_mode="stretch_width",
        )


def same_mode_reference(state: ExplorerState, amplitudes) -> dict | None:
    """The pinned reference's material model at ``amplitudes`` (display units) and the loop
    frequency (:func:`app.curves.branch_breakdown`: |K|, the loss factor, Re K and the loss
    factor branch by branch), or None: no reference, or one in another mode (other units)."""
    ref = state.reference
    if ref is None or ref.mode != state.design.mode:
        return None
    return branch_breakdown(ref, state.frequency_hz, amplitudes)
