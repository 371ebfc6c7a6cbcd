"""What the plots draw, computed from a design: curves in display units (:mod:`app.units`).

Pure functions of a design and the grids, no drawing and no session: the explorer's state and the
public plotting API (:mod:`app.plots`) both use them. The core caches the stiffness maps, so
asking twice for the same curve costs a look-up.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from core import Design
from core.bushing import (
    MAX_STRAIN,
    branch_stiffness,
    material_model,
    stiffness,
    stiffness_points,
)
from core.card import CARD_MODES, card_design
from core.data import MeasuredLoop, MeasuredStiffness
from core.identify.fit import folded, model_stiffness
from core.loops import loop, loop_model
from core.material import ConvergenceError
from core.residuals import gap
from core.response import loss_factor, magnitude_residual_pct
from core.whatif.tolerance import ToleranceError, band

from . import units
from .bands import tolerance_key, tolerances_of

SLICES = (1, 2, 3, "continuum")
# the frequency sweeps are drawn at these equivalent strains, as multiples of ε½
SWEEP_STRAINS = (0.01, 0.1, 1.0, 10.0)


def fletcher_gent_amplitudes(design: Design, n: int = 5, ratios=None) -> np.ndarray:
    """Drive amplitudes (display units) at equivalent strains ``ratios`` × ε½, by default ``n``
    log-spaced over the Fletcher–Gent range ε̂/ε½ = 1e-3 … 1e2."""
    z = np.geomspace(*units.FG_RANGE, n) if ratios is None else np.asarray(ratios, dtype=float)
    return units.display_amplitude(design.drive(z * design.material.friction_strain_half), design.mode)


def amplitude_bounds(design: Design) -> tuple[float, float]:
    """The amplitude axis (display units): the Fletcher–Gent range, up to the largest strain the
    core computes (:data:`core.bushing.MAX_STRAIN`)."""
    x = fletcher_gent_amplitudes(design, 2)
    top = units.display_amplitude(design.drive(MAX_STRAIN), design.mode)
    return float(min(x[0], top / 10)), float(min(x[1], top))


def amplitude_grid(design: Design, n: int = 120) -> np.ndarray:
    return np.geomspace(*amplitude_bounds(design), n)


def sweep_amplitudes(design: Design) -> np.ndarray:
    """The amplitudes of the frequency sweeps: ε̂/ε½ = 0.01, 0.1, 1 and 10 (within the amplitude
    axis)."""
    return np.minimum(fletcher_gent_amplitudes(design, ratios=SWEEP_STRAINS), amplitude_bounds(design)[1])


def sweep_frequencies(freq_min: float, freq_max: float) -> np.ndarray:
    """The frequencies of the amplitude sweeps: both ends of the range and their geometric mean."""
    return np.array([freq_min, math.sqrt(freq_min * freq_max), freq_max])


def frequency_sweep(design: Design, frequencies, amplitudes) -> dict:
    """|K| (display unit) and loss factor against frequency, one row per amplitude (display)."""
    f = np.asarray(frequencies, dtype=float)
    amplitudes = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    r = stiffness(design, f, units.to_si_amplitude(amplitudes, design.mode))
    return {"frequency_hz": f, "amplitude": amplitudes,
            "magnitude": units.display_stiffness(r.magnitude, design.mode), "loss_factor": r.loss_factor}


def amplitude_sweep(design: Design, amplitudes, frequencies) -> dict:
    """|K| (display unit) and loss factor against amplitude (display), one row per frequency."""
    x = np.asarray(amplitudes, dtype=float)
    frequencies = np.atleast_1d(np.asarray(frequencies, dtype=float))
    r = stiffness(design, frequencies, units.to_si_amplitude(x, design.mode))
    return {"amplitude": x, "frequency_hz": frequencies,
            "magnitude": units.display_stiffness(r.magnitude.T, design.mode), "loss_factor": r.loss_factor.T}


def hysteresis_loop(design: Design, frequency_hz: float, amplitude: float, points: int = 200) -> dict:
    """One steady period at ``amplitude`` (display units), closed for drawing, branch by branch.
    Stiffness-level effects have no branches: the loop is the material model's, with the bulk
    spring in series where the design has one (:func:`core.loops.loop_model`)."""
    design = loop_model(design)
    lp = loop(design, frequency_hz, float(units.to_si_amplitude(amplitude, design.mode)), points)
    close = np.r_[np.arange(points), 0]
    return {
        "displacement": units.display_amplitude(lp.displacement[close], design.mode),
        "force": lp.force[close],
        "force_elastic": lp.force_elastic[close],
        "force_viscoelastic": lp.force_viscoelastic[close],
        "force_friction": lp.force_friction[close],
    }


def slice_comparison(design: Design, frequency_hz: float, amplitudes) -> dict:
    """|K| and loss factor against amplitude at one frequency for 1, 2, 3 slices and the
    continuum (Paper A), with the differences from the single modulus in %. A model whose
    iteration does not converge is left out (never an unconverged number); one the core refuses
    for this design too, with its reason in ``"refused"``."""
    x = np.asarray(amplitudes, dtype=float)
    out = {"amplitude": x, "magnitude": {}, "loss_factor": {}, "magnitude_diff_pct": {},
           "loss_factor_diff_pct": {}, "refused": None}
    model = material_model(design)
    for s in SLICES:
        try:
            r = stiffness(model, frequency_hz, units.to_si_amplitude(x, design.mode), slices=s)
        except ConvergenceError:
            continue
        except ValueError as exc:  # slices are derived for some designs only (core.bushing says which)
            if s == 1:
                raise
            out["refused"] = str(exc)
            continue
        out["magnitude"][s] = units.display_stiffness(r.magnitude[:, 0], design.mode)
        out["loss_factor"][s] = r.loss_factor[:, 0]
    base_m, base_e = out["magnitude"][1], out["loss_factor"][1]
    for s in SLICES[1:]:
        if s in out["magnitude"]:
            out["magnitude_diff_pct"][s] = 100 * (out["magnitude"][s] / base_m - 1)
            out["loss_factor_diff_pct"][s] = 100 * (out["loss_factor"][s] / base_e - 1)
    return out


def branch_breakdown(design: Design, frequency_hz: float, amplitudes) -> dict:
    """How the elastic, viscoelastic and friction branches make up K against amplitude at one
    frequency: their parts of Re K (display unit) and of the loss factor (Im K_branch / Re K)."""
    x = np.asarray(amplitudes, dtype=float)
    model = material_model(design)
    parts = {k: v[:, 0] for k, v in branch_stiffness(model, frequency_hz, units.to_si_amplitude(x, design.mode)).items()}
    total = sum(parts.values())
    re = total.real
    return {
        "amplitude": x,
        "magnitude": units.display_stiffness(np.abs(total), design.mode),
        "loss_factor": loss_factor(total),
        "real": {k: units.display_stiffness(v.real, design.mode) for k, v in parts.items()},
        "loss": {k: v.imag / re for k, v in parts.items()},
    }


def operating_point(design: Design, frequency_hz: float, amplitude: float) -> dict:
    """|K| (display unit) and loss factor at one frequency and amplitude (display)."""
    r = stiffness(design, frequency_hz, units.to_si_amplitude(amplitude, design.mode))
    return {"magnitude": float(units.display_stiffness(r.magnitude[0, 0], design.mode)),
            "loss_factor": float(r.loss_factor[0, 0])}


def comparison(design: Design, reference: Design | None, frequency_hz: float, amplitude: float,
               freq_range=(1.0, 100.0), n: int = 120) -> dict | None:
    """``design`` against a pinned ``reference`` (None: no comparison), in %: at the operating
    point (``amplitude`` in display units) and the largest difference over the operating curves
    against frequency (``n`` points over ``freq_range``) and against amplitude."""
    if reference is None:
        return None
    f, x = np.linspace(*freq_range, n), amplitude_grid(design, n)
    now, ref = operating_point(design, frequency_hz, amplitude), operating_point(reference, frequency_hz, amplitude)
    fs_now, fs_ref = frequency_sweep(design, f, amplitude), frequency_sweep(reference, f, amplitude)
    as_now, as_ref = amplitude_sweep(design, x, frequency_hz), amplitude_sweep(reference, x, frequency_hz)

    def worst(a, b):
        d = 100 * (a / b - 1)
        return float(d.flat[np.argmax(np.abs(d))])

    return {
        "operating": {k: (now[k], ref[k], 100 * (now[k] / ref[k] - 1)) for k in ("magnitude", "loss_factor")},
        "largest_over_frequency": {k: worst(fs_now[k], fs_ref[k]) for k in ("magnitude", "loss_factor")},
        "largest_over_amplitude": {k: worst(as_now[k], as_ref[k]) for k in ("magnitude", "loss_factor")},
    }


PADDING = 0.1  # of the data's span (in log10 on a log axis), on both sides together


def padded(values, log: bool = False, pad: float = PADDING) -> tuple[float, float] | None:
    """The axis range that shows ``values`` (arrays, any shapes) with ``pad`` of their span
    added (in log10 on a log axis; two decades, or ±1, around a single value); None without a
    finite (positive, on a log axis) value."""
    parts = [np.ravel(np.asarray(v, dtype=float)) for v in values if v is not None]
    data = np.concatenate(parts) if parts else np.empty(0)
    data = data[np.isfinite(data) & ((data > 0) if log else True)]
    if data.size == 0:
        return None
    low, high = float(data.min()), float(data.max())
    if log:
        low, high = np.log10(low), np.log10(high)
    centre = (low + high) / 2
    half = (high - low) * (1 + pad) / 2 if high > low else 1.0
    start, end = centre - half, centre + half
    return (float(10**start), float(10**end)) if log else (float(start), float(end))


# measured data beyond this many points (loop samples) are drawn as bin means (a folded period):
# a browser draws a few thousand markers at once, not hundreds of thousands in every plot
DISPLAY_POINTS = 5000


def measured_points(measured: MeasuredStiffness | None, mode: str) -> dict | None:
    """Measured stiffness (SI) in display units, as the sweep plots draw it (dense data as the
    means of at most :data:`DISPLAY_POINTS` bins, :meth:`MeasuredStiffness.binned`); only the
    rows in ``mode``."""
    measured = None if measured is None else measured.of_mode(mode)
    if measured is None:
        return None
    measured = measured.binned(DISPLAY_POINTS)
    return {"frequency_hz": measured.frequency_hz,
            "amplitude": units.display_amplitude(measured.amplitude, mode),
            "magnitude": units.display_stiffness(measured.magnitude, mode),
            "loss_factor": measured.loss_factor}


def measured_residuals(design: Design, measured: MeasuredStiffness) -> dict | None:
    """``design`` at each measured point against the data: |K| in %, the loss factor (at the
    points :func:`measured_points` draws), the gap (over every measured point); the rows in the
    design's mode only (None if there are none)."""
    measured = measured.of_mode(design.mode)
    if measured is None:
        return None
    k = stiffness_points(design, measured.frequency_hz, measured.amplitude)
    shown = measured.binned(DISPLAY_POINTS)
    k_shown = k if shown is measured else stiffness_points(design, shown.frequency_hz, shown.amplitude)
    return {"magnitude_residual_pct": magnitude_residual_pct(k_shown, shown.stiffness),
            "loss_factor_residual": loss_factor(k_shown) - shown.loss_factor,
            "gap": gap(k, measured.stiffness)}


def measured_loop_points(measured_loop: MeasuredLoop | None, mode: str) -> dict | None:
    """A measured loop (SI) centred, the drive in display units."""
    if measured_loop is None:
        return None
    lp = measured_loop
    x, force = lp.displacement - np.mean(lp.displacement), lp.force - np.mean(lp.force)
    if x.size > DISPLAY_POINTS:  # one period, folded: the mean drive and force in each phase bin
        phase = lp.harmonic()[2]
        _, x, _ = folded(phase, x, DISPLAY_POINTS)
        _, force, _ = folded(phase, force, DISPLAY_POINTS)
    return {"displacement": units.display_amplitude(x, mode), "force": force}


@dataclass(frozen=True)
class ExplorerData:
    """Everything the explorer's five plots show for one design and operating point, in
    display units. Built by :func:`explorer_data`."""

    design: Design
    freq_range: tuple[float, float]
    frequency_hz: float
    amplitude: float
    sweeps: dict  # "frequency": frequency_sweep at the sweep amplitudes; "amplitude": amplitude_sweep
    operating: dict  # the same at the operating amplitude / frequency (one row each)
    references: dict | None  # the same for the pinned reference design, if any (same mode)
    measured: dict | None  # measured_points
    loop: dict  # hysteresis_loop at the operating point
    reference_loop: dict | None
    measured_loop: dict | None  # measured_loop_points
    ranges: dict  # axis name → (start, end), shared by every plot of that quantity
    bands: dict | None = None  # operating_bands, when tolerances are set

    @property
    def mode(self) -> str:
        return self.design.mode


def operating_bands(design: Design, frequency_hz: float, amplitude: float, freq_range, tolerances,
                    n_freq: int = 120, n_amp: int = 120) -> dict:
    """Tolerance bands (:mod:`core.whatif.tolerance`) of the operating curves: against frequency
    (``n_freq`` points over ``freq_range``, Hz) at the operating ``amplitude`` (display units) and
    against amplitude (:func:`amplitude_grid` of ``n_amp`` points) at the operating frequency. For
    each of ``"frequency"`` and ``"amplitude"``, (low, high) of ``magnitude`` (display unit) and
    ``loss_factor`` at the tolerances' first and last percentiles; ``"point"`` the operating
    point's band, spreads and first-order spreads. Raises ToleranceError with the reason there
    is no band.

    Three Monte Carlos with the same draws (the seed): each curve's (a frequency sweep at one
    strain computes the friction branch once, an amplitude sweep the fractional branch once) and
    the point's. Cached (``functools.lru_cache`` on the values, the tolerances by
    :func:`app.bands.tolerance_key`), the bands and the reasons alike, and each of the three
    bands too: moving the operating amplitude recomputes the frequency curve's band and the
    point's, not the amplitude curve's. The result is shared: read it, do not change it."""
    outcome = _operating_bands(design, float(frequency_hz), float(amplitude),
                               (float(freq_range[0]), float(freq_range[1])), int(n_freq), int(n_amp),
                               tolerance_key(tolerances))
    if isinstance(outcome, str):
        raise ToleranceError(outcome)
    return outcome


@functools.lru_cache(maxsize=8)
def _operating_bands(design: Design, frequency_hz: float, amplitude: float, freq_range: tuple[float, float],
                     n_freq: int, n_amp: int, tolerances: tuple) -> dict | str:
    """:func:`operating_bands`, or the reason there is none (a str)."""
    mode = design.mode
    a_si = float(units.to_si_amplitude(amplitude, mode))
    f = tuple(float(v) for v in np.linspace(*freq_range, n_freq))
    x_si = tuple(float(v) for v in units.to_si_amplitude(amplitude_grid(design, n_amp), mode))
    try:
        swept = {"frequency": _band(design, f, (a_si,), tolerances),
                 "amplitude": _band(design, (frequency_hz,), x_si, tolerances)}
        point = _band(design, frequency_hz, a_si, tolerances)
    except ToleranceError as exc:
        return str(exc)
    low, high = min(point.percentiles), max(point.percentiles)
    out = {against: {"magnitude": tuple(units.display_stiffness(b.magnitude[q], mode) for q in (low, high)),
                     "loss_factor": tuple(b.loss_factor[q] for q in (low, high))}
           for against, b in swept.items()}
    out["point"] = {"percentiles": (low, high), "samples": point.samples, "seed": point.seed,
                    "distribution": point.distribution,
                    "magnitude": tuple(float(units.display_stiffness(point.magnitude[q], mode)) for q in (low, high)),
                    "loss_factor": tuple(float(point.loss_factor[q]) for q in (low, high)),
                    "std_magnitude_pct": float(100 * point.std_magnitude / point.nominal_magnitude),
                    "first_order_magnitude_pct": float(100 * point.first_order_magnitude / point.nominal_magnitude),
                    "std_loss_factor": float(point.std_loss_factor),
                    "first_order_loss_factor": float(point.first_order_loss_factor)}
    return out


@functools.lru_cache(maxsize=6)
def _band(design: Design, frequency_hz, amplitude, tolerances: tuple):
    """The core's band over the points (a float or a tuple of them each, Hz and SI drive) under
    the tolerances of a :func:`app.bands.tolerance_key`."""
    return band(design, np.asarray(frequency_hz, dtype=float), np.asarray(amplitude, dtype=float),
                tolerances_of(tolerances))


def explorer_data(design: Design, frequency_hz: float, amplitude: float, *, freq_range=(1.0, 100.0),
                  reference: Design | None = None, measured: MeasuredStiffness | None = None,
                  measured_loop: MeasuredLoop | None = None, n_freq: int = 120, n_amp: int = 120,
                  bands: dict | None = None) -> ExplorerData:
    """The explorer's curves at the operating point (``frequency_hz``, ``amplitude`` in display
    units). A reference in another mode than ``design`` is left out. ``bands``: the operating
    curves' tolerance bands on the same grids (:func:`operating_bands`), if any."""
    mode = design.mode
    f = np.linspace(*freq_range, n_freq)
    x = amplitude_grid(design, n_amp)
    ref = reference if reference is not None and reference.mode == mode else None
    sweeps = {"frequency": frequency_sweep(design, f, sweep_amplitudes(design)),
              "amplitude": amplitude_sweep(design, x, sweep_frequencies(*freq_range))}
    operating = {"frequency": frequency_sweep(design, f, amplitude),
                 "amplitude": amplitude_sweep(design, x, frequency_hz)}
    references = ({"frequency": frequency_sweep(ref, f, amplitude),
                   "amplitude": amplitude_sweep(ref, x, frequency_hz)} if ref is not None else None)
    points = measured_points(measured, mode)
    lp = hysteresis_loop(design, frequency_hz, amplitude)
    ref_loop = hysteresis_loop(ref, frequency_hz, amplitude) if ref is not None else None
    loop_points = measured_loop_points(measured_loop, mode)
    ranges = {"frequency": padded([f]), "amplitude": padded([x], log=True)}
    for quantity in ("magnitude", "loss_factor"):
        parts = [s[quantity] for s in sweeps.values()] + [s[quantity] for s in operating.values()]
        parts += [v for against in ("frequency", "amplitude") for v in bands[against][quantity]] if bands else []
        parts += [s[quantity] for s in references.values()] if references else []
        parts += [points[quantity]] if points is not None else []
        ranges[quantity] = padded(parts)
    ranges["displacement"] = padded([lp["displacement"]] + ([ref_loop["displacement"]] if ref_loop else [])
                                    + ([loop_points["displacement"]] if loop_points else []))
    ranges["force"] = padded([lp["force"], lp["force_elastic"], lp["force_viscoelastic"], lp["force_friction"]]
                             + ([ref_loop["force"]] if ref_loop else []) + ([loop_points["force"]] if loop_points else []))
    return ExplorerData(design=design, freq_range=(float(freq_range[0]), float(freq_range[1])),
                        frequency_hz=frequency_hz, amplitude=amplitude, sweeps=sweeps,
                        operating=operating, references=references, measured=points, loop=lp,
                        reference_loop=ref_loop, measured_loop=loop_points, ranges=ranges, bands=bands)


def amplitude_groups(data: MeasuredStiffness, mode: str, models: dict, most: int = 5) -> list[dict]:
    """Measured stiffness (SI, one mode) and models at its points against frequency, one group per
    measured amplitude (the ``most`` most populated), in display units: each group's
    ``amplitude``, ``frequency_hz`` (sorted), ``data`` and every model's name (``models``: name →
    complex K at each row of ``data``) as (|K|, loss factor)."""
    groups = []
    for amp in np.sort(data.amplitudes()[:most]):
        sel = np.flatnonzero(data.amplitude == amp)
        sel = sel[np.argsort(data.frequency_hz[sel])]
        group = {"amplitude": float(units.display_amplitude(amp, mode)), "frequency_hz": data.frequency_hz[sel]}
        for name, k in {"data": data.stiffness, **models}.items():
            group[name] = (units.display_stiffness(np.abs(k[sel]), mode), loss_factor(k[sel]))
        groups.append(group)
    return groups


def measured_groups(measured: MeasuredStiffness | None, start: Design, fitted: Design | None = None) -> list[dict]:
    """The measured rows in ``start``'s mode (dense data as bin means) against frequency, one
    group per amplitude, with the model of ``start`` (``"start"``) and, after a fit, of the
    fitted design (``"fitted"``) at those points (:func:`amplitude_groups`); [] without rows."""
    data = None if measured is None else measured.of_mode(start.mode)
    if data is None:
        return []
    data = data.binned(DISPLAY_POINTS)
    models = {"start": stiffness_points(start, data.frequency_hz, data.amplitude)}
    if fitted is not None:
        models["fitted"] = stiffness_points(fitted.in_mode(start.mode), data.frequency_hz, data.amplitude)
    return amplitude_groups(data, start.mode, models)


def card_sweeps(design: Design, frequency_hz: float, strains=None) -> dict:
    """The bushing card's curves (:mod:`core.card`): for each direction, the drive amplitude in
    display units, |K| in display units and the loss factor at ``frequency_hz``, over a grid of
    equivalent strains (the same grid for every direction, so the loss factors share an axis)."""
    out = {"strain": _card_strains(strains)}
    for mode, d, drive in _card_directions(design, out["strain"]):
        k = stiffness_points(d, frequency_hz, drive)
        out[mode] = {"amplitude": units.display_amplitude(drive, mode),
                     "magnitude": units.display_stiffness(np.abs(k), mode), "loss_factor": loss_factor(k)}
    return out


def card_bands(design: Design, frequency_hz: float, tolerances, strains=None) -> dict:
    """Each direction's tolerance band along :func:`card_sweeps`' curves: ``magnitude_band`` and
    ``loss_factor_band``, (low, high) at the first and last percentiles (display units). Raises
    ToleranceError with the reason there is no band. Cached like :func:`operating_bands` (the
    result is shared: read it, do not change it)."""
    key = None if strains is None else tuple(float(v) for v in np.ravel(strains))
    outcome = _card_bands(design, float(frequency_hz), tolerance_key(tolerances), key)
    if isinstance(outcome, str):
        raise ToleranceError(outcome)
    return outcome


@functools.lru_cache(maxsize=4)
def _card_bands(design: Design, frequency_hz: float, tolerances: tuple, strains: tuple | None) -> dict | str:
    """:func:`card_bands`, or the reason there is none (a str)."""
    tol, out = tolerances_of(tolerances), {}
    try:
        for mode, d, drive in _card_directions(design, _card_strains(strains)):
            b = band(d, frequency_hz, drive, tol)
            low, high = min(b.percentiles), max(b.percentiles)
            out[mode] = {"magnitude_band": tuple(units.display_stiffness(b.magnitude[q], mode) for q in (low, high)),
                         "loss_factor_band": (b.loss_factor[low], b.loss_factor[high])}
    except ToleranceError as exc:
        return str(exc)
    return out


def _clear_operating_bands():
    _operating_bands.cache_clear()
    _band.cache_clear()


# the caches' hits and misses (functools.lru_cache's cache_info), and their clearing
operating_bands.cache_info, operating_bands.cache_clear = _operating_bands.cache_info, _clear_operating_bands
card_bands.cache_info, card_bands.cache_clear = _card_bands.cache_info, _card_bands.cache_clear


def _card_strains(strains) -> np.ndarray:
    return np.geomspace(1e-5, 1e-1, 60) if strains is None else np.asarray(strains, dtype=float)


def _card_directions(design: Design, strains: np.ndarray):
    """(mode, the card's design in that direction, the drives at ``strains``) of every direction."""
    for mode in CARD_MODES:
        d = card_design(material_model(design), mode)
        yield mode, d, d.drive(strains)


def prediction_misfit(fit, measured: MeasuredStiffness | None) -> dict | None:
    """A fit on a subset (its ``prediction``) against every measured row: per mode, the |K|
    misfit (model − measured, %) against frequency of the fitted rows and of the predicted ones."""
    if fit is None or not fit.prediction or measured is None:
        return None
    modes = measured.modes(fit.design.mode).astype(str)
    chosen = np.zeros(len(measured), dtype=bool)  # the rows of the groups the fit used (whatever the spec's units)
    for g in fit.prediction["groups"]:
        chosen |= (modes == g["mode"]) & (measured.amplitude == g["amplitude"]) & g["fitted"]
    pct = magnitude_residual_pct(model_stiffness(fit.design, measured), measured.stiffness)
    out = {}
    for mode in np.unique(modes):
        rows = modes == mode
        out[mode] = {which: {"frequency_hz": measured.frequency_hz[rows & sel], "misfit_pct": pct[rows & sel]}
                     for which, sel in (("fitted", chosen), ("predicted", ~chosen))}
    return out
