"""The About tab: what the explorer computes, its units, shape factors, what-ifs and files."""

from __future__ import annotations

from core.parameters import BY_NAME, GEOMETRY, MATERIAL, MODES, SHAPES


def _keys(names, last: str = ", ") -> str:
    """```axial`, `torsion``: names in a sentence (the last two joined by ``last``)."""
    quoted = [f"`{n}`" for n in names]
    return last.join([", ".join(quoted[:-1]), quoted[-1]]) if len(quoted) > 1 else "".join(quoted)


# the design file's material keys in Pa (µ, m, σ_fmax), and those without a unit (α, ε½)
_DIMENSIONED = [n for n in MATERIAL if BY_NAME[n].unit.si != "–"]
_PLAIN = [n for n in MATERIAL if BY_NAME[n].unit.si == "–"]


ABOUT = f"""
### Bushing Explorer

Dynamic stiffness of carbon-black-filled rubber bushings, axially, radially, in torsion and
tilted (conical), over frequency and amplitude, with the Fletcher–Gent (Payne) effect: the engineering formulas of M.-J. García
Tárrago (KTH, 2006). Set the geometry and the five material parameters on the left, pick the
operating point (drive amplitude and loop frequency), and read the loop, the stiffness magnitude
|K| and the loss factor. **Tap** any frequency or amplitude plot to move the operating point
there; every plot follows. All numbers come from the closed-form steady state, which the tests
check against the thesis' time-domain simulation.

**Units.** Radii and length in mm; µ and m in MPa (m in MPa·s^α); σ_fmax in kPa; ε½ and α
plain numbers; the drive in mm (axial, radial) or rad (torsion, conical), as peak values. |K| in
kN/mm (= MN/m) or N·m/rad. Files and the command line use SI.

**Shape factors.** Axial and torsion use the thesis' closed forms unless *Finite-length shape
factor* is on; radial and conical always use the finite-element table (the rubber between rigid
bonded sleeves, ends free, b/a 1.2–4 and L/(b − a) 0.5–12). Each direction's equivalent strain
follows from the energy balance, ε_eq = x̂ √(S / (4V)).

**What-ifs.** Tolerances (± % per parameter, or a fit's covariance) become 5–95 % bands on the
stiffness plots (a Monte Carlo with a stated seed, the first-order spread beside it); the
sensitivities of |K| and the loss factor follow the operating point; targets on |K|, the loss
factor and the radial/axial ratio find the nearest design that meets them, or say why none can.

**Files.** *Measured stiffness* (CSV): a header row `frequency_hz,amplitude,magnitude,loss_factor`
(or `stiffness_real,stiffness_imag`, or `magnitude,phase_deg` with the phase in degrees, instead of
the last two; only these two carry Re K < 0), then one row per point; amplitude the peak
displacement in m (axial, radial) or angle in rad (torsion, conical), |K| in N/m or N·m/rad. A
negative loss factor (a blocked stiffness above a wave resonance) is a measurement like any other. *Measured
loop* (CSV): `time_s,displacement,force`, one or more periods of a steady harmonic test. *Design
file* (JSON): `mode` ({_keys(MODES)}), optional `shape` ({_keys(SHAPES)}), `geometry`
({_keys(GEOMETRY)} in m), `material` ({_keys(_DIMENSIONED, " and ")} in Pa,
{_keys(_PLAIN)}), optionally `name` and `effects`. A row or key that is missing, not a
number or out of range is refused with its line or key. The repository's `docs/` describe the
model (with the thesis' equation numbers), every file and the `bushing` command line.
"""
