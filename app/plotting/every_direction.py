"""The Every direction tab's plots: the bushing card, |K| and the loss factor of every direction."""

from __future__ import annotations

import holoviews as hv

from core import Design
from core.parameters import ROTATIONS, TRANSLATIONS

from .. import curves
from ..units import ROTATION, TRANSLATION
from .style import (
    MODE_COLORS,
    REFERENCE_STYLE,
    band_area,
    curve,
    marker,
    overlay,
    sized,
)


def direction_title(mode: str) -> str:
    """The title of a direction's |K| plot: "|K| axial" (the tab's text says what each direction
    moves; a longer title was cut in a half-width plot at 1280 px)."""
    return f"|K| {mode}"


def card_dimensions() -> dict[str, hv.Dimension]:
    """The card's axes: translations and rotations apart (their units differ), and each
    direction's |K| on its own axis (radial is several times axial: on one axis the smaller
    would be squashed flat)."""
    dims = {
        "displacement": hv.Dimension("card_displacement", label="Displacement amplitude",
                                     unit=TRANSLATION.amplitude.display),
        "angle": hv.Dimension("card_angle", label="Angle amplitude", unit=ROTATION.amplitude.display),
        "loss": hv.Dimension("card_loss", label="Loss factor"),
    }
    for m in TRANSLATIONS + ROTATIONS:
        unit = (TRANSLATION if m in TRANSLATIONS else ROTATION).stiffness.display
        dims[f"k_{m}"] = hv.Dimension(f"card_k_{m}", label=f"|K| {m}", unit=unit)
    return dims


def card_overlays(data: dict, dims: dict, at: dict, reference: dict | None = None) -> dict:
    """The card (:func:`app.curves.card_sweeps`) as six plots: each direction's |K| on its own
    axes (``axial``, ``radial`` against displacement, ``torsion``, ``conical`` against angle),
    and the loss factors of the translations and of the rotations (one material: one loss axis);
    ``at`` the card's displacement and angle (display units); ``reference`` the pinned
    reference's card sweeps, drawn dashed, if any."""
    out = {}
    for which, modes, xdim in (("translation", TRANSLATIONS, dims["displacement"]),
                               ("rotation", ROTATIONS, dims["angle"])):
        for m in modes:
            ydim = dims[f"k_{m}"]
            items = [band_area(data[m]["amplitude"], *data[m]["magnitude_band"], xdim, ydim, f"{m} band",
                               MODE_COLORS[m])] if "magnitude_band" in data[m] else []
            if reference is not None:
                items.append(curve(reference[m]["amplitude"], reference[m]["magnitude"], xdim, ydim, "reference",
                                   **REFERENCE_STYLE))
            items += [curve(data[m]["amplitude"], data[m]["magnitude"], xdim, ydim, m, color=MODE_COLORS[m],
                            line_width=2), marker(at[which], xdim)]
            out[m] = overlay(items, direction_title(m), f"bushing-card-{m}", logx=True, height=240)
        items = [band_area(data[m]["amplitude"], *data[m]["loss_factor_band"], xdim, dims["loss"], f"{m} band",
                           MODE_COLORS[m]) for m in modes if "loss_factor_band" in data[m]]
        if reference is not None:
            items += [curve(reference[m]["amplitude"], reference[m]["loss_factor"], xdim, dims["loss"],
                            f"reference {m}", **REFERENCE_STYLE) for m in modes]
        items += [curve(data[m]["amplitude"], data[m]["loss_factor"], xdim, dims["loss"], m, color=MODE_COLORS[m],
                        line_width=2) for m in modes]
        items.append(marker(at[which], xdim))
        title = "Loss factor, along and across the axis" if which == "translation" else "Loss factor, turning and tilting"
        out[f"{which}_loss"] = overlay(items, title, f"bushing-card-{which}-loss", logx=True, height=240)
    return out


def card_plots(design: Design, frequency_hz: float = 10.0, displacement: float = 1e-4, angle: float = 0.01, *,
               width: int | None = 800) -> hv.Layout:
    """The bushing card's four plots: every direction of ``design`` at one frequency.

    Parameters
    ----------
    design : Design
        The bushing, in SI units, in any mode: the card takes it into every mode, with the
        card's shape factors (:func:`core.card.card_design`: the finite-length table in every
        direction if its ``shape`` is ``finite``, else the long-bushing formulas of axial and
        torsion).
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
        Six plots in two columns: |K| of axial and radial (kN/mm) against displacement (mm),
        of torsion and conical (N·m/rad) against angle (rad), each on its own axes, and the
        loss factors (dimensionless) of the translations and of the rotations.
    """
    data = curves.card_sweeps(design, frequency_hz)
    at = {"translation": TRANSLATION.amplitude.to_display(displacement),
          "rotation": ROTATION.amplitude.to_display(angle)}
    return sized(hv.Layout(list(card_overlays(data, card_dimensions(), at).values())).cols(2), width)
