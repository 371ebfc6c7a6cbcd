"""The bushing element inside Exudyn: a rigid body on the bushing under base excitation
(docs/element.md, "In Exudyn").

A 250 kg rigid body sits on the Paper B bushing (axis z); the bushing's other end, the base,
moves harmonically along z and about z. Exudyn (its implicit solver, the trapezoidal rule) integrates
the body; the bushing is a ``RigidBodySpringDamper`` connector whose force user function asks
:class:`core.element.Element` for a **trial** force, and whose post-Newton user function
**commits** the element once per step into the connector's ``NodeGenericData``. Exudyn keeps
that data node per step: a rejected step restores it, so the element's history rolls back with
the step.

The same system is integrated a second, independent way: the body's two uncoupled equations
(m z̈ = −F_z(z − z_b), J θ̈ = −M_z(θ − θ_b)) by the central difference, with the force at
each step from :func:`core.loops.force_history` over the whole relative history so far (the
model's own definition: the Grünwald–Letnikov sum of eq 3 and Berg's friction, no sum of
exponentials, no held input). The script prints how close the two are.

Run: ``python examples/exudyn_bushing.py`` (needs the ``exudyn`` extra).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

if __package__ in (None, ""):  # run as a script: the repository's core
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from core import PAPER_B
from core.element import CHANNEL_MODES, CHANNELS, Element
from core.loops import force_history

DESIGN = PAPER_B
BAND = (0.5, 50.0)  # Hz: the frequencies that matter (drive 15 Hz, the body's modes 20–25 Hz)
MASS = 250.0  # kg: axial mode ≈ 21 Hz on the bushing's ≈ 4.3 kN/mm
INERTIA = 0.15  # kg·m², about every axis: torsion mode ≈ 25 Hz on ≈ 3.7 kN·m/rad
FREQUENCY = 15.0  # Hz, the base's motion
BASE = {"dz": 1.0e-4, "rz": 2.0e-3}  # amplitudes: m and rad (the other channels' base is still)
H_EXUDYN = 5.0e-5  # s: 1/(400 f₂), the element's held input within 0.5 % and 0.0075 rad in the band
H_DIRECT = 1.0e-4  # s: the direct route's step
COMPARED = ("dz", "rz")


def base_motion(t: float) -> np.ndarray:
    """The base's six coordinates at ``t`` s (m, rad), channels in :data:`CHANNELS`' order."""
    out = np.zeros(len(CHANNELS))
    for name, amplitude in BASE.items():
        out[CHANNELS.index(name)] = amplitude * np.sin(2.0 * np.pi * FREQUENCY * t)
    return out


@dataclass
class Run:
    """One integration: times (s), the body's motion and the bushing's load per compared channel
    (m or rad; N or N·m), and what was counted along the way."""

    t: np.ndarray
    motion: dict
    load: dict
    counts: dict = field(default_factory=dict)


class ElementConnector:
    """The element in Exudyn's connector: trial in the force function, commit in the post-Newton
    function, the history in the connector's data node.

    The data node holds [commits, time of the last commit (s), the element's state flattened].
    Exudyn passes the post-Newton function the data at the step's start and keeps what it
    returns; it restores the data when it rejects a step. The Python element is a cache of the
    data: when the data's (commits, time) are not the element's, it is restored from them.
    """

    def __init__(self, element: Element, reject_at: float | None = None):
        self.element = element
        template = element.state()
        self._keys = [k for k in template if k != "version"]
        self._shapes = [np.shape(template[k]) for k in self._keys]
        self._at = (0.0, 0.0)  # (commits, time) of the element's state
        self.reject_at = reject_at  # a time after which one step is rejected (for the test)
        self.force_calls = 0
        self.post_newton_calls = 0
        self.last = None  # (t, relative input, force) of the last commit

    def initial_data(self) -> list:
        return [0.0, 0.0, *self._flat(self.element.state())]

    def _flat(self, state) -> np.ndarray:
        return np.concatenate([np.ravel(state[k]) for k in self._keys])

    def _sync(self, data) -> None:
        """The element at the state ``data`` holds (the step's start)."""
        key = (data[0], data[1])
        if key != self._at:
            state, i = {"version": self.element.state()["version"]}, 2
            for k, shape in zip(self._keys, self._shapes):
                n = int(np.prod(shape))
                state[k] = np.reshape(data[i:i + n], shape)
                i += n
            self.element.restore(state)
            self._at = key

    def force(self, mbs, t, item, displacement, rotation, velocity, omega, *unused):
        """Exudyn's springForceTorqueUserFunction: the trial force for the relative motion
        (state unchanged). Exudyn calls it several times a step, at perturbed states too."""
        import exudyn as exu

        self.force_calls += 1
        data = mbs.systemData.GetDataCoordinates(exu.ConfigurationType.StartOfStep)
        self._sync(data)
        h = t - data[1]
        if h <= 0.0:  # the initial accelerations at t = 0: the committed force
            return list(self.element.state()["force"])
        return list(self.element.trial(self._input(t, displacement, rotation), h))

    def post_newton(self, mbs, t, item, data, displacement, rotation, *unused):
        """Exudyn's postNewtonStepUserFunction: commit the step; returns [error, recommended step,
        the new data]. With ``reject_at`` set, the first step past it is rejected once (a
        discontinuous error and half the step), as a host rejects steps."""
        self.post_newton_calls += 1
        data = np.asarray(data)
        self._sync(data)
        x = self._input(t, displacement, rotation)
        f = self.element.commit(x, t - data[1])
        self._at = (data[0] + 1.0, t)
        self.last = (t, x, f)
        new = [data[0] + 1.0, t, *self._flat(self.element.state())]
        if self.reject_at is not None and t > self.reject_at:
            self.reject_at = None
            return [1.0e3, 0.5 * (t - data[1]), *new]
        return [0.0, -1.0, *new]

    @staticmethod
    def _input(t, displacement, rotation) -> np.ndarray:
        """The bushing's relative motion: the body's (marker 1) against the moving base."""
        return np.concatenate([displacement, rotation]) - base_motion(t)


def simulate_exudyn(end_time: float, h: float = H_EXUDYN, reject_at: float | None = None) -> Run:
    """The body on the bushing in Exudyn, from rest, to ``end_time`` s with steps of ``h`` s."""
    import exudyn as exu
    from exudyn.utilities import (
        InertiaCuboid,
        MarkerBodyRigid,
        NodeGenericData,
        RigidBodySpringDamper,
    )

    element = Element.from_design(DESIGN, 1, BAND)
    conn = ElementConnector(element, reject_at)
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.CreateGround()
    side = (6.0 * INERTIA / MASS) ** 0.5  # a cube of this mass and inertia
    body = mbs.CreateRigidBody(inertia=InertiaCuboid(MASS / side**3, [side] * 3), gravity=[0.0, 0.0, 0.0])
    data = conn.initial_data()
    node = mbs.AddNode(NodeGenericData(initialCoordinates=data, numberOfDataCoordinates=len(data)))
    markers = [mbs.AddMarker(MarkerBodyRigid(bodyNumber=b)) for b in (ground, body)]
    mbs.AddObject(RigidBodySpringDamper(
        markerNumbers=markers, nodeNumber=node, stiffness=np.zeros((6, 6)), damping=np.zeros((6, 6)),
        springForceTorqueUserFunction=conn.force, postNewtonStepUserFunction=conn.post_newton))
    record = []

    def post_step(mbs, t):  # an accepted step: record what its commit saw
        if conn.last is not None and conn.last[0] == t:
            record.append(conn.last)
        return True

    mbs.SetPostStepUserFunction(post_step)
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.timeIntegration.endTime = end_time
    s.timeIntegration.numberOfSteps = round(end_time / h)
    s.timeIntegration.verboseMode = 0
    s.timeIntegration.generalizedAlpha.spectralRadius = 1.0  # the trapezoidal rule: no numerical damping
    s.solution.file.write = False  # no solution file
    mbs.SolveDynamic(s)
    final = mbs.systemData.GetDataCoordinates()
    t = np.array([0.0] + [r[0] for r in record])
    x = np.vstack([np.zeros(len(CHANNELS))] + [r[1] + base_motion(r[0]) for r in record])
    f = np.vstack([np.zeros(len(CHANNELS))] + [r[2] for r in record])
    idx = {n: CHANNELS.index(n) for n in COMPARED}
    return Run(t, {n: x[:, i] for n, i in idx.items()}, {n: f[:, i] for n, i in idx.items()}, {
        "force calls": conn.force_calls, "post-Newton calls": conn.post_newton_calls,
        "accepted steps": len(record), "commits kept": int(final[0]),
        "rejected steps": conn.post_newton_calls - len(record)})


def simulate_direct(end_time: float, h: float = H_DIRECT) -> Run:
    """The same body, each compared channel its own oscillator, by the central difference with
    the force from :func:`core.loops.force_history` over the whole relative history so far."""
    n = round(end_time / h)
    t = h * np.arange(n + 1)
    motion, load = {}, {}
    for name in COMPARED:
        design = DESIGN.in_mode(CHANNEL_MODES[name])
        inertia = MASS if name.startswith("d") else INERTIA
        base = BASE[name] * np.sin(2.0 * np.pi * FREQUENCY * t)
        x = np.zeros(n + 1)  # the body, from rest
        f = np.zeros(n + 1)
        for k in range(n):
            f[k] = force_history(design, x[: k + 1] - base[: k + 1], h).force[-1]
            previous = x[k - 1] if k else x[0]  # at rest: x_{-1} = x_0
            x[k + 1] = 2.0 * x[k] - previous - h * h * f[k] / inertia
        f[n] = force_history(design, x - base, h).force[-1]
        motion[name], load[name] = x, f
    return Run(t, motion, load)


def bound() -> float:
    """The relative difference the step sizes allow between the two routes: the element's
    fractional term is within ``held_error(H_EXUDYN)`` (magnitude, phase in rad) of (iω)^α over
    the band, the fit included; the Grünwald–Letnikov sum lags by αh/2 (first order), at most
    π α f₂ H_DIRECT of phase in the band. A branch off by δ in magnitude and φ in phase moves
    the load by at most δ + φ of that branch, less than the whole load."""
    element = Element.from_design(DESIGN, 1, BAND, ("dz",))
    magnitude, phase = element.held_error(H_EXUDYN)
    return magnitude + phase + np.pi * element.coefficients.alpha * BAND[1] * H_DIRECT


def compare(exudyn_run: Run, direct_run: Run, settle: float = 0.0) -> dict:
    """Per compared channel: the RMS of the difference over the RMS of the direct route's signal,
    for the body's motion and the bushing's load, at the direct route's times after ``settle``
    s (Exudyn's run interpolated there: its steps divide the direct route's)."""
    t = direct_run.t
    keep = t >= settle
    out = {}
    for name in COMPARED:
        for what, a, b in (("motion", exudyn_run.motion, direct_run.motion), ("load", exudyn_run.load, direct_run.load)):
            e = np.interp(t[keep], exudyn_run.t, a[name])
            d = b[name][keep]
            out[name, what] = float(np.sqrt(np.mean((e - d) ** 2)) / np.sqrt(np.mean(d**2)))
    return out


def main(end_time: float = 0.6) -> None:
    exudyn_run = simulate_exudyn(end_time)
    direct_run = simulate_direct(end_time)
    diff = compare(exudyn_run, direct_run)
    print(f"{DESIGN.name}: {MASS:g} kg, {INERTIA:g} kg·m² on the bushing; base {FREQUENCY:g} Hz, "
          f"dz {BASE['dz'] * 1e3:g} mm, rz {BASE['rz'] * 1e3:g} mrad; {end_time:g} s")
    print(f"Exudyn (trapezoidal rule, h = {H_EXUDYN:g} s, element band {BAND[0]:g}–{BAND[1]:g} Hz) against "
          f"the central difference over force_history (h = {H_DIRECT:g} s):")
    for name in COMPARED:
        unit = ("mm", "N") if name.startswith("d") else ("mrad", "N·m")
        peak = np.max(np.abs(direct_run.motion[name])) * 1e3
        print(f"  {name}: body peak {peak:.4g} {unit[0]}, RMS difference {100 * diff[name, 'motion']:.3f} % of the "
              f"motion, {100 * diff[name, 'load']:.3f} % of the load ({unit[1]})")
    print(f"  the step sizes allow {100 * bound():.2f} %")
    print("  " + ", ".join(f"{k} {v}" for k, v in exudyn_run.counts.items()))


if __name__ == "__main__":
    main()
