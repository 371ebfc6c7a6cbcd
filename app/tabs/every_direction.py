"""The "Every direction" tab: the bushing card. The four stiffnesses at the operating frequency,
axial and radial at a displacement, torsion and conical at an angle, the ratios engineers quote,
and |K| and the loss factor against amplitude in every direction."""

from __future__ import annotations

import panel as pn
import param

from core.card import CARD_MODES, against_incompressible, card, ratios
from core.numbers import format_change, format_number, format_value
from core.parameters import BY_NAME, MODE, ROTATIONS, TRANSLATIONS
from core.shape import long_shape_factor

from .. import units
from ..bands import band_tolerances, banded
from ..curves import card_bands, card_sweeps, padded
from ..fit_state import FitState
from ..live import LivePlot
from ..number_field import NumberField
from ..plotting.every_direction import card_dimensions, card_overlays
from ..plotting.style import ranged
from ..shapes import shape_pane, shape_used
from ..state import ExplorerState
from ..units import ROTATION, TRANSLATION
from ..views import PlotView

# the grid, two columns: each direction's |K| (translations, then rotations), then the loss factors
WHICH = (*TRANSLATIONS, *ROTATIONS, "translation_loss", "rotation_loss")
TEXT = """
**Every direction of the bushing.** The same rubber and geometry loaded four ways: **axial** (the
sleeves moved apart along the axis), **radial** (across it), **torsion** (turned about it) and
**conical** (tilted about a diameter). The shape factors follow the sidebar's *Finite-length shape
factor* switch: off, axial and torsion use the thesis' long-bushing formulas, radial and conical
the finite-length table (they have no formula that holds at real lengths); on, the finite-length
table everywhere. Each row of the table names its own. Each direction has its own equivalent
strain, so the Fletcher–Gent softening sets in at a different drive in each (at the same
equivalent strain, the loss factors are the same: one material). Each |K| has its own axes.
"""


class CardView(PlotView):
    """The bushing card at the operating frequency."""

    shows = ("design", "frequency", "bands", "reference")
    own = ("displacement_mm", "angle_rad")

    displacement_mm = param.Number(0.1, bounds=(1e-6, 100.0),
                                   label=f"Displacement amplitude ({TRANSLATION.amplitude.display})")
    angle_rad = param.Number(0.01, bounds=(1e-7, 1.0), label=f"Angle amplitude ({ROTATION.amplitude.display})")

    fit = param.ClassSelector(class_=FitState, doc="The session's fit (its covariance may make the bands).")

    def __init__(self, state: ExplorerState, fit: FitState, **params):
        super().__init__(state, fit=fit, **params)
        self.inputs = pn.Row(
            NumberField(self, "displacement_mm", unit=TRANSLATION.amplitude.display, quantity="amplitude"),
            NumberField(self, "angle_rad", unit=ROTATION.amplitude.display, quantity="amplitude"),
            sizing_mode="stretch_width")
        self.table = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.dims = card_dimensions()
        self.plots: LivePlot | None = None
        self.draw()

    def frame(self, which: str):
        return self.plots.current[WHICH.index(which)]

    def _update(self):
        design, f = self.state.design, self.state.frequency_hz
        reference = self.state.reference
        x = float(TRANSLATION.amplitude.to_si(self.displacement_mm))  # m
        angle = float(ROTATION.amplitude.to_si(self.angle_rad))  # rad
        try:
            rows = card(design, f, x, angle)
            data = card_sweeps(design, f)
        except ValueError as exc:  # outside the finite-length table, or an effect with no card
            self.table.object = f"_The card is not available for this design: {exc}_"
            return
        try:
            shown_reference = None if reference is None else card_sweeps(reference, f)
        except ValueError:  # a reference with no card: the design's card alone
            shown_reference = None
        tolerances = band_tolerances(**self.state.band_inputs(), fit_result=self.fit.fit_result)
        for mode, b in (banded(tolerances, lambda tol: card_bands(design, f, tol))[0] or {}).items():
            data[mode].update(b)
        self.table.object = self.summary(design, f, rows)
        swept = [data] if shown_reference is None else [data, shown_reference]  # a reference's drives differ
        dims = ranged(self.dims, {axis: padded([d[m]["amplitude"] for d in swept for m in modes], log=True)
                                  for axis, modes in (("displacement", TRANSLATIONS), ("angle", ROTATIONS))})
        at = {"translation": TRANSLATION.amplitude.to_display(x), "rotation": ROTATION.amplitude.to_display(angle)}
        overlays = card_overlays(data, dims, at, shown_reference)
        self.plots = LivePlot.shown(self.plots, [overlays[w] for w in WHICH])

    @staticmethod
    def summary(design, frequency_hz, rows) -> str:
        g = design.geometry
        bulk = against_incompressible(design, frequency_hz, rows)
        lines = [f"**At {format_value(frequency_hz, 'Hz', 'frequency')}** ({design.name or 'this design'})", "",
                 ("| direction | amplitude | \\|K\\| | loss factor | shape factor used | S "
                 "| S / long-bushing formula | \\|K\\|, loss factor against an incompressible rubber |"),
                 "|---|---|---|---|---|---|---|---|"]
        for r in rows:
            mode = r["mode"]
            amp = units.display_amplitude(r["amplitude"], mode)
            k = units.display_stiffness(r["magnitude"], mode)
            s_unit = "m³" if MODE[mode].rotation else "m"
            try:
                versus = f"{r['shape_factor'] / long_shape_factor(g.inner_radius, g.outer_radius, g.length, mode):.3f}"
            except ValueError:
                versus = "no formula"
            lines.append(f"| {mode} | {kept(format_value(amp, units.amplitude_unit(mode), 'amplitude'))} "
                         f"| {kept(format_value(k, units.stiffness_unit(mode), 'stiffness'))} | {r['loss_factor']:.4f} "
                         f"| {shape_used(design, mode)} | {kept(format_value(r['shape_factor'], s_unit))} | {versus} "
                         f"| {format_change(bulk[mode][0])}, {format_change(bulk[mode][1])} |")
        k = design.material.bulk_modulus
        unit = BY_NAME["bulk_modulus"].unit
        lines += ["", (f"**Compressibility**: bulk modulus K = {format_value(unit.to_display(k), unit.display, 'parameter')} (K/µ "
                       f"{format_number(k / design.material.shear_modulus, 3)})" if k is not None else
                       "**Compressibility**: no bulk modulus given: a nearly incompressible rubber, K = 5000 µ")
                  + "; the last column compares each direction with the same bushing of an incompressible rubber "
                    "(torsion and the long axial formula are pure shear; thin walls squeezed radially care most)."]
        q = ratios(design, rows)
        lines += ["", (f"**Ratios**: radial / axial **{q['radial/axial']:.2f}**; radial / torsion-equivalent "
                       f"(K_torsion / r_m², r_m = (a + b)/2) **{q['radial/torsion-equivalent']:.2f}**.")]
        return "\n".join(lines)

    def __panel__(self):
        return pn.Column(pn.pane.Markdown(TEXT, sizing_mode="stretch_width"), shape_pane(self.state, CARD_MODES),
                         self.inputs, self.table,
                         self.plots.grid(2), sizing_mode="stretch_width")


def kept(text: str) -> str:
    """A number and its unit held on one line (a no-break space): a narrow table cell broke
    ``4.207 kN/mm`` between them."""
    return text.replace(" ", "\u00a0")
