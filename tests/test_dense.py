"""Dense data: fits and the diagnosis work on bins of at most about MAX_FIT_POINTS entries (loops
folded onto one period), weighted so that the noise of an entry is one measured point's; the
gaps, the predictions and the held-out check are over every measured point; long runs show
progress on a terminal only."""

import io

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cli.commands import Progress
from core import PAPER_B, stiffness_points
from core.data import MeasuredStiffness
from core.identify.diagnose import diagnose
from core.identify.fit import fit_global, folded
from core.loops import loop_force
from core.registry import parameter_values
from core.residuals import gap
from core.synthetic import synthetic_loop, synthetic_stiffness

AMPLITUDES = [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3]
START = PAPER_B.replace(shear_modulus=1.5e6, fractional_coefficient=1e6, fractional_order=0.4,
                        friction_stress_max=4e4, friction_strain_half=1e-3)


def test_binning_averages_neighbours_and_keeps_the_amplitudes():
    f = np.tile(np.geomspace(1.0, 100.0, 4000), 3)
    a = np.repeat([1e-5, 1e-4, 1e-3], 4000)
    k = (1.0 + 0.01 * np.log(f)) * (2.0 + 1j * (a * 1e3))  # smooth in ln f
    data = MeasuredStiffness(f, a, k)
    binned = data.binned(600)
    assert len(binned) == 600 and binned.count.sum() == 12000 and binned.measured_points == 12000
    assert set(np.unique(binned.amplitude)) == {1e-5, 1e-4, 1e-3}  # exactly, not a mean of logs
    # each entry is the mean of 20 neighbours: K linear in ln f, so K at the geometric-mean frequency
    assert_allclose(binned.stiffness, (1.0 + 0.01 * np.log(binned.frequency_hz)) * (2.0 + 1j * binned.amplitude * 1e3),
                    rtol=1e-12)
    assert data.binned(12000) is data
    scattered = MeasuredStiffness(np.geomspace(1, 100, 9000), np.geomspace(1e-5, 1e-3, 9000)[::-1], np.ones(9000) + 0j)
    out = scattered.binned(500)
    assert len(out) <= 500 + 25 and out.count.sum() == 9000


@pytest.mark.parametrize("points", [20_000])
def test_a_dense_fit_is_the_fit_of_every_point(points):
    data = synthetic_stiffness(PAPER_B, np.geomspace(1, 100, points // 5), AMPLITUDES, noise=0.005, seed=3)
    result = fit_global(START, data)
    assert result.points == points
    every = gap(stiffness_points(result.design, data.frequency_hz, data.amplitude), data.stiffness)
    assert result.gap == pytest.approx(every, rel=1e-12)
    # complex noise of 0.005 in each part: a gap of 0.005·√2 over every point
    assert result.gap == pytest.approx(0.005 * np.sqrt(2), rel=0.02)
    truth = parameter_values(PAPER_B)
    for name, (lo, hi) in result.intervals.items():
        assert lo <= truth[name] <= hi, name
        assert hi / lo < 1.02, name  # 20 000 points fix every parameter to a percent


def test_a_dense_diagnosis_reports_over_every_point_with_an_honest_noise():
    data = synthetic_stiffness(PAPER_B.replace(effects={"inertia": {"mass": 0.5}}), np.geomspace(1, 100, 4000),
                               AMPLITUDES, noise=0.005, seed=4)
    result = diagnose(PAPER_B, data)
    assert result.added == ["inertia"] and not result.unexplained
    assert len(result.predictions()["final_magnitude"]) == 20_000
    assert result.final.gap == pytest.approx(
        gap(stiffness_points(result.final.design, data.frequency_hz, data.amplitude), data.stiffness), rel=1e-12)
    # the noise estimate from the bins is one measured point's, not a bin mean's (√(count) smaller)
    assert result.noise_gap == pytest.approx(0.005 * np.sqrt(2), rel=0.1)
    held = result.held_out
    assert held["gap_final"] == pytest.approx(result.final.gap, rel=0.05)
    assert held["gap_baseline"] > 1.3 * held["gap_final"]


def test_folding_a_loop_onto_one_period():
    phase = np.linspace(0, 6 * np.pi, 30_001)[:-1]  # three periods
    phi, value, count = folded(phase, np.sin(phase), 300)
    assert phi.size == 300 and count.sum() == 30_000
    assert_allclose(value, np.sin(phi), atol=2e-4)  # a bin's mean is the value at its mean phase
    short = folded(phase[:100], np.cos(phase[:100]), 300)
    assert np.array_equal(short[0], phase[:100]) and np.all(short[2] == 1)


def test_a_long_loop_is_fitted_on_its_folded_period():
    loop = synthetic_loop(PAPER_B, 0.1, 1e-3, periods=10, per_period=5000, seed=2)
    result = fit_global(START, loop=loop)
    f, amp, phase = loop.harmonic()
    force = loop.force - loop.force.mean()
    truth = sum(loop_force(PAPER_B, f, amp, phase))
    truth_rms = np.sqrt(np.mean((truth - force) ** 2)) / np.max(np.abs(force))  # relative to the peak
    assert result.loop_rms <= truth_rms * 1.001  # at least as good as the truth, over every sample
    assert result.design.material.friction_stress_max == pytest.approx(PAPER_B.material.friction_stress_max, rel=0.02)
    # one loop at one frequency cannot split the fractional branch: the fit says so
    assert "fractional_order" in result.undetermined or "fractional_coefficient" in result.undetermined


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_shows_on_a_terminal_only():
    tty, pipe = _Terminal(), io.StringIO()
    for stream in (tty, pipe):
        say = Progress(stream, after=0.0)
        say(0.5, "trying inertia")
        say(1.0, "done")
    assert "\r\033[Kbushing:  50% trying inertia" in tty.getvalue() and tty.getvalue().endswith("done\n")
    assert pipe.getvalue() == ""
    quick = _Terminal()
    Progress(quick, after=60.0)(0.5, "x")  # a short run stays silent
    assert quick.getvalue() == ""

