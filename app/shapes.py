"""Which shape factor a view uses, in one phrase.

The one setting is the design's ``shape`` (the sidebar's *Finite-length shape factor* switch,
:attr:`app.state.ExplorerState.finite_length`): ``finite``, the finite-length FE table in every
direction; otherwise (None, or ``thesis`` from a file) the thesis' long-bushing formulas where they
exist, axial (eq 18) and torsion (eq 17), and the finite-length table for radial and conical,
which have none that holds at real lengths: the design file's rule, which the card and the
exports follow too (:func:`core.card.card_design`). Every view that draws a design says which it
uses with :func:`shape_phrase`.
"""

from __future__ import annotations

from core import Design
from core.numbers import format_value
from core.parameters import BY_NAME, MODE
from core.shape import pure_shear


def shape_used(design: Design, mode: str | None = None) -> str:
    """The shape factor ``design``'s setting gives direction ``mode`` (default: its own), in a
    few words: "long-bushing formula (eq 18)", "long-bushing closed form (plane strain)" (radial:
    no equation of the thesis) or "finite-length table"."""
    mode = mode or design.mode
    if design.in_mode(mode).shape_kind != "long":
        return "finite-length table"
    equation = MODE[mode].long_equation  # the thesis' closed forms (docs/model.md)
    return f"long-bushing formula (eq {equation})" if equation else "long-bushing closed form (plane strain)"


def shape_phrase(design: Design, modes: tuple[str, ...] | None = None) -> str:
    """The one sentence each view shows: "Shape factor: …" for ``design``'s own mode, or for
    each of ``modes`` (those with the same kind of shape factor named together)."""
    if modes is None:
        k = design.material.bulk_modulus
        bulk = "" if k is None or pure_shear(design.mode, design.shape_kind) else (
            f" Bulk modulus K = {format_value(BY_NAME['bulk_modulus'].unit.to_display(k), 'GPa', 'parameter')}: "
            + "|K|, the loss factor and the loop include it (a bulk spring in series"
            + (", matched to the plane-strain closed form at this frequency and amplitude" if design.shape_kind == "long"
               else "") + "); the branches are the material's (incompressible).")
        return f"Shape factor: {shape_used(design)}.{bulk}"
    used = {m: shape_used(design, m) for m in modes}
    long = [m for m in modes if used[m].startswith("long-bushing formula")]
    plane = [m for m in modes if used[m] == "long-bushing closed form (plane strain)"]
    finite = [m for m in modes if used[m] == "finite-length table"]
    if len(finite) == len(modes):
        return "Shape factor: finite-length table, every direction."
    parts = []
    if long:
        plural = "s" if len(long) > 1 else ""
        eqs = ", ".join(str(MODE[m].long_equation) for m in long)
        parts.append(f"{' and '.join(long)}, long-bushing formula{plural} (eq{plural} {eqs})")
    if plane:
        parts.append(f"{' and '.join(plane)}, long-bushing closed form (plane strain)")
    if finite:
        parts.append(f"{' and '.join(finite)}, finite-length table")
    return "Shape factor: " + "; ".join(parts) + "."


def shape_note_html(design: Design, modes: tuple[str, ...] | None = None) -> str:
    """:func:`shape_phrase` as the page shows it (class ``shape-phrase``)."""
    return f'<span class="shape-phrase">{shape_phrase(design, modes)}</span>'


def shape_pane(state, modes: tuple[str, ...] | None = None):
    """A line that follows ``state.design``: :func:`shape_note_html` (a Panel pane)."""
    import panel as pn

    return pn.pane.HTML(pn.bind(lambda design: shape_note_html(design, modes), state.param.design),
                        sizing_mode="stretch_width", margin=(0, 10), styles={"font-size": "0.9em"})
