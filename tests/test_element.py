"""The element's sum of exponentials, coefficients and refusals (docs/element.md)."""

import json
import math
import warnings

import numpy as np
import pytest

from core import PAPER_B, stiffness
from core.element import CHANNELS, Element, ElementWarning, coefficients, fit_power
from core.element.prony import MAGNITUDE_TARGET, MAX_DECADES, PHASE_TARGET
from core.slices import slice_nodes


def _independent_errors(fit, points=20011):
    """Magnitude and phase error of the fit on a grid of its own, term by term in real arithmetic:
    g iω/(iω + λ) = g (ω² + iωλ)/(ω² + λ²), against ω^α e^{iαπ/2}."""
    f1, f2 = fit.band
    w = 2 * np.pi * np.geomspace(f1, f2, points)
    re = sum(g * w * w / (w * w + lam * lam) for g, lam in zip(fit.weights, fit.rates, strict=True))
    im = sum(g * w * lam / (w * w + lam * lam) for g, lam in zip(fit.weights, fit.rates, strict=True))
    mag = np.hypot(re, im) / w**fit.alpha
    phase = np.arctan2(im, re) - fit.alpha * np.pi / 2
    return np.max(np.abs(mag - 1)), np.max(np.abs(phase))


@pytest.mark.parametrize("alpha", [0.05, 0.2, 0.45, 0.8])
def test_fit_meets_its_bound_and_reports_the_true_maximum(alpha):
    fit = fit_power(alpha)
    assert fit.meets_target and fit.terms <= 20
    mag, phase = _independent_errors(fit)
    assert mag <= MAGNITUDE_TARGET and phase <= PHASE_TARGET
    # the reported bound is the maximum, not a loose bound: within 1 % of the independent one
    assert mag == pytest.approx(fit.magnitude_error, rel=1e-2)
    assert phase == pytest.approx(fit.phase_error, rel=1e-2)


def test_fit_bounds_rates_around_the_band():
    fit = fit_power(0.2, (1.0, 100.0))
    assert np.all(fit.weights > 0) and np.all(np.diff(fit.rates) > 0)
    assert fit.rates[0] < 2 * np.pi * 1.0 < 2 * np.pi * 100.0 < fit.rates[-1]


@pytest.mark.parametrize("band, words", [
    ((2000.0, 0.1), "below the upper"), ((0.0, 10.0), "positive finite"), ((1.0, math.inf), "positive finite"),
    ((1.0, math.nan), "positive finite"), ((1e-6, 1e3), f"at most {MAX_DECADES:g} decades"), ((1.0,), "two frequencies"),
])
def test_bad_band_is_refused_by_its_rule(band, words):
    with pytest.raises(ValueError, match=words):
        coefficients(PAPER_B, band=band)


def test_alpha_one_is_a_viscosity():
    with pytest.raises(ValueError, match="exact first derivative"):
        fit_power(1.0)
    design = PAPER_B.replace(fractional_order=1.0, fractional_coefficient=1e3)
    co = coefficients(design, band=(0.1, 20.0))  # 800 steps a period at 10 Hz: T/400 at 20 Hz
    assert co.rate == () and co.viscosity == 1e3 and co.fractional_as_viscosity
    el = Element(co, ("dz",))
    f, n = 10.0, 800
    k = _first_harmonic(el, design.drive(1e-3), f, n, periods=3)
    k0 = stiffness(design, f, design.drive(1e-3)).stiffness[0, 0]
    assert abs(k / k0 - 1) < 0.01


def _first_harmonic(el, amplitude, f, n, periods):
    h = 1.0 / (f * n)
    theta = 2 * np.pi * np.arange(1, n * periods + 1) / n
    force = np.array([el.commit([amplitude * np.sin(t)], h)[0] for t in theta])[-n:]
    th = theta[-n:]
    return (2 * np.mean(force * np.sin(th)) + 2j * np.mean(force * np.cos(th))) / amplitude


def test_coefficients_are_json_and_name_the_sliced_channels():
    co = coefficients(PAPER_B, slices=3)
    back = json.loads(json.dumps(co.as_dict()))
    assert back["sliced_channels"] == ["dz", "rz"] == list(co.sliced_channels)
    assert set(back["channels"]) == set(CHANNELS)
    nodes = slice_nodes(PAPER_B.geometry, "axial", 3)
    assert np.allclose(1 / np.array(back["channels"]["dz"]["S"]), nodes.q, rtol=1e-14)
    assert len(back["channels"]["dx"]["S"]) == 1
    names = [row[0] for row in co.parameters()]
    assert "rate[1]" in names and "rate[0]" not in names and "dz.S[3]" in names and "rx.compliance" in names
    # one layer: the design's own factors in that direction
    radial = PAPER_B.in_mode("radial")
    assert back["channels"]["dx"]["S"] == [radial.shape_factor] and back["channels"]["dx"]["c"] == [radial.strain_factor]


def test_bulk_spring_in_series_matches_the_compressible_stiffness_at_small_amplitude():
    design = PAPER_B.replace(bulk_modulus=0.3e9)
    co = coefficients(design, band=(0.1, 20.0))
    assert co.channels["dx"].compliance > 0 and co.channels["rx"].compliance > 0
    assert co.channels["dz"].compliance == 0 and co.channels["rz"].compliance == 0  # pure shear
    for name, mode in (("dx", "radial"), ("rx", "conical")):
        d = design.in_mode(mode)
        el = Element(co, (name,))
        amp = d.drive(1e-6)
        k = _first_harmonic(el, amp, 10.0, 800, periods=3)
        k0 = stiffness(d, 10.0, amp).stiffness[0, 0]
        k_incompressible = stiffness(d.replace(bulk_modulus=None), 10.0, amp).stiffness[0, 0]
        assert abs(k0 / k_incompressible - 1) > 0.02  # the bulk spring matters here
        assert abs(abs(k) / abs(k0) - 1) < 0.01 and abs(k.imag / k.real - k0.imag / k0.real) < 0.005


def test_long_radial_bulk_modulus_is_matched_at_the_reference_point():
    """The long radial closed form with K: the series matched at 10 Hz and ε̂ 1e-3
    (core.compressible.REFERENCE_FREQUENCY, REFERENCE_STRAIN); the element driven there draws
    the closed form's stiffness (core.stiffness) within 1 % and 0.005 (the element's own step
    error; docs/element.md states the bound away from that point), where the bulk modulus moves
    it more than 5 %."""
    from core.compressible import REFERENCE_FREQUENCY, REFERENCE_STRAIN

    design = PAPER_B.replace(shape="long", inner_radius=0.02, outer_radius=0.025, length=0.05, bulk_modulus=0.3e9)
    co = coefficients(design, band=(0.1, 20.0))
    assert co.channels["dx"].compliance > 0 and co.channels["dz"].compliance == 0
    d = design.in_mode("radial")
    amp = d.drive(REFERENCE_STRAIN)
    k = _first_harmonic(Element(co, ("dx",)), amp, REFERENCE_FREQUENCY, 800, periods=3)
    k0 = stiffness(d, REFERENCE_FREQUENCY, amp).stiffness[0, 0]
    assert abs(stiffness(d.replace(bulk_modulus=None), REFERENCE_FREQUENCY, amp).stiffness[0, 0] / k0 - 1) > 0.05
    assert abs(abs(k) / abs(k0) - 1) < 0.01 and abs(k.imag / k.real - k0.imag / k0.real) < 0.005


@pytest.mark.parametrize("effects, words", [
    ({"inertia": {"mass": 0.1}}, "apparent mass"),
    ({"wave_effects": {"density": 1100.0}}, "rubber's mass"),
    ({"rate_amplitude_coupling": {"rate_exponent": 0.1}}, "harmonic drives only"),
    ({"nonuniform_strain": {}, "strain_stiffening": {"stiffening": 1.0}}, "use slices"),
])
def test_effects_without_a_time_domain_form_are_refused(effects, words):
    with pytest.raises(ValueError, match=words):
        coefficients(PAPER_B.replace(effects=effects))


@pytest.mark.parametrize("slices", [0, 101, 2.0, True, "continuum"])
def test_bad_slices_are_refused(slices):
    with pytest.raises(ValueError, match="slices"):
        coefficients(PAPER_B, slices=slices)


@pytest.mark.parametrize("h", [0.0, -1e-4, math.nan, math.inf, "1e-4", None])
def test_bad_step_is_refused(h):
    el = Element.from_design(PAPER_B)
    with pytest.raises(ValueError, match="h: the step"):
        el.commit(np.zeros(6), h)


@pytest.mark.parametrize("x", [np.zeros(5), [0.0] * 5 + [math.nan], [[0.0] * 7]])
def test_bad_inputs_are_refused(x):
    with pytest.raises(ValueError, match="6 finite inputs"):
        Element.from_design(PAPER_B).trial(x, 1e-6)


def test_a_coarse_step_warns_once_with_the_band():
    el = Element.from_design(PAPER_B)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        for _ in range(3):
            el.commit(np.zeros(6), 1e-3)
    assert len(record) == 1 and issubclass(record[0].category, ElementWarning)
    message = str(record[0].message)
    assert "0.1–2000 Hz" in message and "shorter step" in message
    # the numbers it names are the held input's error (Element.held_error)
    mag, phase = el.held_error(1e-3)
    assert f"{100 * mag:.2g} %" in message and f"{phase:.2g} rad" in message and mag > 0.01


def test_the_docs_example_runs(tmp_path):
    import contextlib
    import io
    import pathlib
    import re
    import runpy

    text = pathlib.Path(__file__).parents[1].joinpath("docs/element.md").read_text(encoding="utf-8")
    script = tmp_path / "example.py"
    script.write_text(re.search(r"```python\n(.*?)```", text, re.DOTALL).group(1), encoding="utf-8")
    out = io.StringIO()
    with contextlib.redirect_stdout(out), warnings.catch_warnings():
        warnings.simplefilter("error", ElementWarning)
        runpy.run_path(str(script))
    assert out.getvalue().startswith("('dz', 'rz')")
