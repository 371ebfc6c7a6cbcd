"""The Exudyn example (examples/exudyn_bushing.py, docs/element.md "In Exudyn"): a rigid body on
the bushing element under base excitation, integrated by Exudyn, against the same system
integrated directly (the central difference over core.loops.force_history)."""

import numpy as np
import pytest

pytest.importorskip("exudyn")

from examples import exudyn_bushing as ex

END = 0.2  # s: three periods of the 15 Hz base, from rest
REJECT_AT = 0.1  # s: Exudyn rejects the first step past it once


@pytest.fixture(scope="module")
def runs():
    return ex.simulate_exudyn(END, reject_at=REJECT_AT), ex.simulate_direct(END)


def test_the_body_moves_as_the_directly_integrated_system_within_what_the_steps_allow(runs):
    """Motion and load of each excited channel (axial dz, torsion rz) agree in RMS within the
    bound the two step sizes fix (the element's held-input error over its band, the Grünwald
    sum's first-order lag), with one step rejected and rolled back on the way."""
    exudyn_run, direct_run = runs
    limit = ex.bound()
    assert 0.005 < limit < 0.03  # the stated error of these steps: a bound that can bind
    for name in ex.COMPARED:  # the base drives each body through its mode: motion to compare
        assert np.max(np.abs(direct_run.motion[name])) > ex.BASE[name]
    diff = ex.compare(exudyn_run, direct_run)
    assert set(diff) == {(n, w) for n in ex.COMPARED for w in ("motion", "load")}
    for key, value in diff.items():
        assert value < limit, (key, value, limit)


def test_the_element_is_committed_once_per_accepted_step_never_in_the_force_function(runs):
    """Exudyn calls the force function several times a step (Newton iterations, the numerical
    Jacobian's perturbed states): more calls than commits, so trial did not advance the state.
    The commits the data node keeps equal the accepted steps; the one rejected step's commit was
    rolled back with the data node (one post-Newton call more than accepted steps)."""
    counts = runs[0].counts
    accepted = counts["accepted steps"]
    assert accepted >= round(END / ex.H_EXUDYN)  # every step of h, and the shorter ones after the rejection
    assert counts["force calls"] > 3 * counts["post-Newton calls"]
    assert counts["commits kept"] == accepted
    assert counts["post-Newton calls"] == accepted + 1
    assert counts["rejected steps"] == 1
    t = runs[0].t
    assert np.all(np.diff(t) > 0) and t[-1] == pytest.approx(END)
    assert np.min(np.diff(t)) == pytest.approx(ex.H_EXUDYN / 2)  # the repeated step was half as long
