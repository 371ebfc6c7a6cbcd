"""The Every direction tab's plots: the bushing card, |K| and the loss factor of every direction.
"""

from __future__ import annotations

import holoviews as hv

from core import Design
from core.parameters import ROTATIONS, TRANSLATIONS

from .. import curves
from ..units import ROTATION, TRANSLATION
from .style import (
    MODE_COLORS,
    band_area,
    curve,
    marker,
    overlay,
    sized,
)


def card_dimensions() -> dict[str, hv.Dimension]:
    """The card's axes: translations and rotations apart (their units differ)."""
    return {
        "displacement": hv.Dimension("card_displacement", label="Displacement amplitude",
                                     unit=TRANSLATION.amplitude.display),
        "angle": hv.Dimension("card_angle", label="Angle amplitude", unit=ROTATION.amplitude.display),
        "k_translation": hv.Dimension("card_k_translation", label="|K|", unit=TRANSLATION.stiffness.display),
        "k_rotation": hv.Dimension("card_k_rotation", label="|K|", unit=ROTATION.stiffness.display),
        "loss": hv.Dimension("card_loss", label="Loss factor"),
    }


def card_overlays(data: dict, dims: dict, at: dict) -> dict:
    """The card (:func:`app.curves.card_sweeps`) as four plots: |K| and the loss factor of the
    translations against displacement, of the rotations against angle; ``at`` the card's
    displacement and angle (display units)."""
    out = {}
    for which, modes, xdim, ydim, title in (
            ("translation", TRANSLATIONS, dims["displacement"], dims["k_translation"],
             "|K| along and across the axis"),
            ("rotation", ROTATIONS, dims["angle"], dims["k_rotation"], "|K| turning and tilting")):
        for quantity, y_dim, name in (("magnitude", ydim, which), ("loss_factor", dims["loss"], f"{which}_loss")):
            items = [band_area(data[m]["amplitude"], *data[m][f"{quantity}_band"], xdim, y_dim, f"{m} band",
                               MODE_COLORS[m]) for m in modes if f"{quantity}_band" in data[m]]
            items += [curve(data[m]["amplitude"], data[m][quantity], xdim, y_dim, m, color=MODE_COLORS[m],
                            line_width=2) for m in modes]
            items.append(marker(at[which], xdim))
            label = title if quantity == "magnitude" else f"Loss factor, {title[4:]}"
            out[name] = overlay(items, label, f"bushing-card-{name.replace('_', '-')}", logx=True, height=260)
    return out


def card_plots(design: Design, frequency_hz: float = 10.0, displacement: float = 1e-4, angle: float = 0.01, *,
               width: int | None = 800) -> hv.Layout:
    """The bushing card's four plots: every direction of ``design`` at one frequency.

    Parameters
    ----------
    design : Design
        The bushing, in SI units, in any mode: the card takes it into every mode.
    frequency_hz : float, default 10.0
        The frequency in Hz.
    displacement : float, default 1e-4
        The card's displacement amplitude (the marker), in m (SI, drawn in mm).
    angle : float, default 0.01
        The card's angle amplitude (the marker), in rad.
    width : int or None, default 800
        The width of each plot in pixels; None: as wide as its container.

    Returns
    -------
    holoviews.Layout
        Four plots in two columns: |K| of the translations (kN/mm) against displacement (mm)
        and of the rotations (N·m/rad) against angle (rad), and their loss factors
        (dimensionless).
    """
    data = curves.card_sweeps(design, frequency_hz)
    at = {"translation": TRANSLATION.amplitude.to_display(displacement),
          "rotation": ROTATION.amplitude.to_display(angle)}
    return sized(hv.Layout(list(card_overlays(data, card_dimensions(), at).values())).cols(2), width)
