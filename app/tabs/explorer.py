"""The Explorer tab: the hysteresis loop at the operating point and |K| and the loss factor
against frequency and amplitude (HoloViews, linked by shared dimensions), the comparison with a
pinned reference."""

from __future__ import annotations

import holoviews as hv
import panel as pn
import param

from core.numbers import format_number, format_signed, format_value

from .. import curves, units
from ..bands import band_tolerances, banded
from ..fit_state import FitState
from ..live import LivePlot
from ..plotting.explorer import explorer_overlays
from ..shapes import shape_pane
from ..state import ExplorerState
from ..uploads import verdict_html
from ..views import PlotView

GRID = (("magnitude", "frequency"), ("magnitude", "amplitude"), ("loss_factor", "frequency"),
        ("loss_factor", "amplitude"))


class ExplorerPlots(PlotView):
    """Loop, |K| and loss factor against frequency and amplitude, linked by the operating
    point: a tap on a frequency plot sets the frequency, on an amplitude plot the amplitude."""

    shows = ("design", "frequency", "amplitude", "sweep range", "reference", "measured", "bands")

    fit = param.ClassSelector(class_=FitState, doc="The session's fit (its covariance may make the bands).")

    def __init__(self, state: ExplorerState, fit: FitState, **params):
        super().__init__(state, fit=fit, **params)
        self.summary = pn.pane.HTML("", sizing_mode="stretch_width", css_classes=["operating-point"],
                                    margin=(0, 10))
        # the verdict on the last measured file, as the measured-data tab says it (one message)
        self.verdict = pn.pane.HTML("", sizing_mode="stretch_width", margin=(0, 10))
        self._show_verdict()
        self.loop: LivePlot | None = None
        self.grid: LivePlot | None = None
        self.draw()

    @param.depends("state.data_message", "state.data_note", watch=True)
    def _show_verdict(self):
        self.verdict.object = verdict_html(self.state.data_message, self.state.data_note, "explorer")

    def frame(self, key) -> hv.Overlay:
        """What a plot shows now: ``"loop"`` or a (quantity, against) pair of :data:`GRID`."""
        return self.loop.current[0] if key == "loop" else self.grid.current[GRID.index(key)]

    def _update(self):
        s = self.state
        design, f, x, freq_range = s.design, s.frequency_hz, s.amplitude, s.freq_range
        bands, reason = banded(band_tolerances(**s.band_inputs(), fit_result=self.fit.fit_result),
                               lambda tol: curves.operating_bands(design, f, x, freq_range, tol))
        data = curves.explorer_data(design, f, x, freq_range=freq_range, reference=s.reference,
                                    measured=s.measured, measured_loop=s.measured_loop, bands=bands)
        overlays = explorer_overlays(data, self.dims_for(data.mode))
        grid = [overlays[k] for k in GRID]
        if self.grid is None:
            taps = {i: self.tap_frequency if against == "frequency" else self.tap_amplitude
                    for i, (_quantity, against) in enumerate(GRID)}
            self.loop = LivePlot([overlays["loop"]], linked=True)
            self.grid = LivePlot(grid, taps=taps, linked=True)
        else:
            self.loop.show([overlays["loop"]])
            self.grid.show(grid)
        point = curves.operating_point(design, f, x)
        amplitude_unit, stiffness_unit = units.amplitude_unit(design.mode), units.stiffness_unit(design.mode)
        self.summary.object = (
            f'<span class="op-summary"><b>Operating point</b>: <span class="op-point">'
            f"{format_value(x, amplitude_unit, 'amplitude')}, {format_value(f, 'Hz', 'frequency')}</span> &nbsp;→&nbsp; |K| = "
            f"<b>{format_value(point['magnitude'], stiffness_unit, 'stiffness')}</b>, loss factor <b>{point['loss_factor']:.4f}</b></span>"
            + (f'<br><span class="band-summary">{band_words(data.bands["point"], stiffness_unit)}</span>'
               if data.bands else "")
            + (f'<br><span class="band-message" style="color:#8a5300">No tolerance band: {reason}</span>'
               if reason else "")
        )

    def __panel__(self):
        return pn.Column(self.verdict, self.summary, shape_pane(self.state), self.loop.pane, self.grid.grid(2),
                         sizing_mode="stretch_width")


def band_words(p: dict, unit: str) -> str:
    """The operating point's band in one line: its percentiles, the Monte Carlo's spread and the
    first-order check."""
    low, high = p["percentiles"]
    return (f"<b>Tolerance band</b> ({low:g}–{high:g} %, {p['samples']} {p['distribution']} samples, seed {p['seed']}): "
            f"|K| {format_number(p['magnitude'][0], 'stiffness')}–{format_value(p['magnitude'][1], unit, 'stiffness')}, loss factor "
            f"{p['loss_factor'][0]:.4f}–{p['loss_factor'][1]:.4f}. Spread (1σ) of |K| {p['std_magnitude_pct']:.2f} % "
            f"(first order {p['first_order_magnitude_pct']:.2f} %), of the loss factor {p['std_loss_factor']:.4f} "
            f"(first order {p['first_order_loss_factor']:.4f}).")


def pct(value: float) -> str:
    """A signed percentage to 2 decimals, a true minus sign, without a "−0.00" from round-off."""
    return f"{format_signed(value, 2)} %"


class CompareView(PlotView):
    """Pin the current design as a reference; show the differences in %."""

    shows = ("design", "frequency", "amplitude", "sweep range", "reference")

    def __init__(self, state: ExplorerState, **params):
        super().__init__(state, **params)
        self.pin = pn.widgets.Button(label="Pin as reference", color="primary", description="Keep this design to compare the next ones with it (dashed curves).")
        self.clear = pn.widgets.Button(label="Clear reference", color="light")
        self.pin.on_click(lambda _e: state.pin_reference())
        self.clear.on_click(lambda _e: state.clear_reference())
        self.text = pn.pane.Markdown("", sizing_mode="stretch_width", css_classes=["comparison"])
        self.draw()

    def _update(self):
        self.text.object = self.table()

    def table(self) -> str:
        """The comparison with the pinned reference (Markdown), or what to do to see one."""
        s = self.state
        design, reference, f, x = s.design, s.reference, s.frequency_hz, s.amplitude
        if reference is None:
            return "_No reference pinned: press **Pin as reference**, then change the design._"
        if reference.mode != design.mode:
            return "_The reference is in another mode; switch back to compare._"
        c = curves.comparison(design, reference, f, x, s.freq_range)
        unit = units.stiffness_unit(design.mode)
        (m_now, m_ref, m_d), (e_now, e_ref, e_d) = c["operating"]["magnitude"], c["operating"]["loss_factor"]
        return (
            f"| at {format_value(f, 'Hz', 'frequency')}, {format_value(x, units.amplitude_unit(design.mode), 'amplitude')} | this design | reference | difference |\n|---|---|---|---|\n"
            f"| \\|K\\| ({unit}) | {format_number(m_now, 'stiffness')} | {format_number(m_ref, 'stiffness')} | {pct(m_d)} |\n"
            f"| loss factor | {e_now:.4f} | {e_ref:.4f} | {pct(e_d)} |\n\n"
            f"Largest difference over the frequency sweep: \\|K\\| {pct(c['largest_over_frequency']['magnitude'])}, "
            f"loss factor {pct(c['largest_over_frequency']['loss_factor'])}; over the amplitude sweep: "
            f"\\|K\\| {pct(c['largest_over_amplitude']['magnitude'])}, loss factor {pct(c['largest_over_amplitude']['loss_factor'])}."
        )

    def __panel__(self):
        return pn.Column(pn.Row(self.pin, self.clear), self.text, sizing_mode="stretch_width")
