"""The FMU that `bushing fmu` writes, through FMPy, an independent FMI importer (docs/fmu.md):
its model description, its binary, its forces against `bushing stiffness`, rejected steps,
serialized states across processes, resource URIs, errors, and its rebuild from its sources."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from core import PAPER_B
from core.bushing import stiffness
from core.element import CHANNEL_MODES, CHANNELS, OUTPUTS, coefficients
from fmu import write_fmu
from tests.fmu_helpers import equivalent_amplitude, first_harmonic

fmpy = pytest.importorskip("fmpy")
validation = pytest.importorskip("fmpy.validation")
FMU2Slave = pytest.importorskip("fmpy.fmi2").FMU2Slave

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler (README's test command)")

SLICES = 3
INPUTS = list(range(6))
FORCES = list(range(6, 12))


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The FMU of Paper B's bushing with 3 slices, written and extracted once."""
    root = tmp_path_factory.mktemp("fmu")
    co = coefficients(PAPER_B, SLICES)
    result = write_fmu(co, root / "front left.fmu", model_name="Paper B")
    unzipped = Path(fmpy.extract(str(result.path), unzipdir=str(root / "unzipped")))
    return result, unzipped, co


def slave(unzipped: Path, name="bushing", resource_uri=None):
    md = fmpy.read_model_description(str(unzipped))
    s = FMU2Slave(guid=md.guid, unzipDirectory=str(unzipped), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName=name)
    if resource_uri is None:
        s.instantiate()
    else:
        s.callbacks = fmpy.fmi2.defaultCallbacks
        s.component = s.fmi2Instantiate(name.encode(), fmpy.fmi2.fmi2CoSimulation, md.guid.encode(),
                                        resource_uri.encode(), fmpy.fmi2.byref(s.callbacks), 0, 0)
    return s


def start(s):
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    return s


def test_fmpy_validation_finds_nothing_and_the_description_is_complete(built):
    result, unzipped, co = built
    assert validation.validate_fmu(str(result.path)) == []
    md = fmpy.read_model_description(str(result.path))
    cs = md.coSimulation
    assert md.fmiVersion == "2.0" and cs.modelIdentifier == "front_left"
    assert cs.canHandleVariableCommunicationStepSize and cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    assert not cs.canInterpolateInputs
    names = {v.name: v for v in md.modelVariables}
    units = {u.name for u in md.unitDefinitions}
    assert all(v.unit in units for v in md.modelVariables)  # a unit for every variable
    assert [names[n].causality for n in CHANNELS] == ["input"] * 6
    assert [names[n].unit for n in CHANNELS] == ["m", "m", "m", "rad", "rad", "rad"]
    assert [names[n].unit for n in OUTPUTS] == ["N", "N", "N", "N.m", "N.m", "N.m"]
    assert [u.variable.name for u in md.outputs] == list(OUTPUTS)
    assert [u.variable.name for u in md.initialUnknowns] == list(OUTPUTS)
    # the coefficients, readable: the element's own list, names, units, values and order
    params = [v for v in md.modelVariables if v.causality == "parameter"]
    assert [(v.name, v.unit, v.description) for v in params] == [(p.name, p.unit, p.description)
                                                                 for p in co.parameters()]
    assert [float(v.start) for v in params] == [p.value for p in co.parameters()]  # written to read back exactly
    assert float(names["mu"].start) == co.mu and names["mu"].unit == "Pa"
    assert float(names["rate[1]"].start) == co.rate[0] and names["rate[1]"].unit == "1/s"
    assert float(names["dz.S[3]"].start) == co.channels["dz"].S[2] and names["dz.S[3]"].unit == "m"
    assert float(names["rz.c[2]"].start) == co.channels["rz"].c[1] and names["rz.c[2]"].unit == "1/rad"
    assert names["rx.compliance"].unit == "rad/(N.m)" and "dx.S[2]" not in names and "rate[0]" not in names
    xml = ET.parse(unzipped / "modelDescription.xml").getroot()
    listed = [f.get("name") for f in xml.iter("File")]
    assert listed and all((unzipped / "sources" / f).is_file() for f in listed)


def test_the_binary_needs_no_python_only_libc_and_libm(built):
    result, unzipped, _ = built
    assert result.binary == "binaries/linux64/front_left.so" and result.note is None
    lib = unzipped / result.binary
    symbols = subprocess.run(["nm", "-D", str(lib)], capture_output=True, text=True, check=True).stdout
    names = [line.split()[-1] for line in symbols.splitlines() if line.strip()]
    assert "fmi2DoStep" in names and "fmi2SerializeFMUstate" in names
    assert not [n for n in names if n.lstrip("_").startswith("Py")]
    dynamic = subprocess.run(["readelf", "-d", str(lib)], capture_output=True, text=True, check=True).stdout
    needed = {line.split("[")[1].rstrip("]") for line in dynamic.splitlines() if "(NEEDED)" in line}
    assert needed <= {"libc.so.6", "libm.so.6"}


def run_harmonic(unzipped, frequency, strain, steps_per_period=1000, periods=16):
    """Drive every channel at one frequency and equivalent strain amplitude; the settled first
    harmonic of each channel's force over the last period, per unit drive: K (N/m, N·m/rad)."""
    amps = np.array([equivalent_amplitude(PAPER_B, ch, strain) for ch in CHANNELS])
    h = 1.0 / (frequency * steps_per_period)
    s = start(slave(unzipped))
    forces, phases = [], []
    for i in range(steps_per_period * periods):
        theta = 2 * np.pi * (i + 1) / steps_per_period  # the input held over the step is x(t_{n+1})
        s.setReal(INPUTS, list(amps * np.sin(theta)))
        s.doStep(i * h, h)
        if i >= steps_per_period * (periods - 1):
            forces.append(s.getReal(FORCES))
            phases.append(theta)
    s.terminate()
    s.freeInstance()
    forces = np.array(forces)
    return amps, [first_harmonic(forces[:, c], phases) / amps[c] for c in range(6)]


@pytest.mark.parametrize("frequency", [1.0, 40.0, 800.0])
def test_the_settled_first_harmonic_is_bushing_stiffness_in_every_channel(built, frequency):
    """Every direction (radial, axial, conical, torsion), across the band, at a small and a
    large amplitude of the Fletcher–Gent range: |K| within 1 %, the loss factor within 0.005."""
    _, unzipped, _ = built
    for strain in (2e-4, 8e-3):
        amps, ks = run_harmonic(unzipped, frequency, strain)
        for c, ch in enumerate(CHANNELS):
            mode = CHANNEL_MODES[ch]
            ref = stiffness(PAPER_B.in_mode(mode), frequency, amps[c],
                            slices=SLICES if mode in ("axial", "torsion") else 1).stiffness[0, 0]
            k = ks[c]
            assert abs(abs(k) / abs(ref) - 1) < 0.01, (ch, frequency, strain, k, ref)
            assert abs(k.imag / k.real - ref.imag / ref.real) < 0.005, (ch, frequency, strain, k, ref)


def drive(i):
    return list(1e-4 * np.sin(0.05 * i + np.arange(6)) * np.array([1, 1, 1, 3, 3, 3]))


def test_a_rejected_step_repeated_from_the_saved_state_gives_the_same_forces(built):
    _, unzipped, _ = built
    s = start(slave(unzipped))
    h = 1e-4
    for i in range(50):
        s.setReal(INPUTS, drive(i))
        s.doStep(i * h, h)
    saved = s.getFMUstate()
    s.setReal(INPUTS, drive(50))
    s.doStep(50 * h, h)
    first = s.getReal(FORCES)
    s.setReal(INPUTS, drive(999))  # a different trial, rejected
    s.doStep(51 * h, 3 * h)
    s.setFMUstate(saved)
    s.setReal(INPUTS, drive(50))
    s.doStep(50 * h, h)
    assert s.getReal(FORCES) == first  # the same computation from the same state
    s.freeFMUstate(saved)
    s.terminate()
    s.freeInstance()


SERIALIZE = textwrap.dedent("""
    import json, sys
    import numpy as np
    import fmpy
    from fmpy.fmi2 import FMU2Slave
    unzipped, mode, path = sys.argv[1:4]
    md = fmpy.read_model_description(unzipped)
    s = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier)
    s.instantiate(); s.setupExperiment(startTime=0.0); s.enterInitializationMode(); s.exitInitializationMode()
    def drive(i):
        return list(1e-4 * np.sin(0.05 * i + np.arange(6)) * np.array([1, 1, 1, 3, 3, 3]))
    h = 1e-4
    if mode == "save":
        for i in range(40):
            s.setReal(list(range(6)), drive(i)); s.doStep(i * h, h)
        state = s.getFMUstate()
        open(path, "wb").write(bytes(s.serializeFMUstate(state)))
    else:
        state = s.deSerializeFMUstate(open(path, "rb").read())
        s.setFMUstate(state)
    out = []
    for i in range(40, 60):
        s.setReal(list(range(6)), drive(i)); s.doStep(i * h, h); out.append(s.getReal(list(range(6, 12))))
    print(json.dumps(out))
""")


def test_a_serialized_state_loads_in_another_process(built, tmp_path):
    _, unzipped, _ = built
    script = tmp_path / "serialize.py"
    script.write_text(SERIALIZE)
    blob = tmp_path / "state.bin"

    def run(mode):
        done = subprocess.run([sys.executable, str(script), str(unzipped), mode, str(blob)],
                              capture_output=True, text=True, check=True)
        return json.loads(done.stdout)

    saved = run("save")
    data = blob.read_bytes()
    assert data[:8] == b"BUSHFMU\0" and int.from_bytes(data[8:12], sys.byteorder) == 2  # magic, version (2: the Newton's last-step changes)
    assert run("load") == saved  # the same forces after the state crossed processes
    # a state of another size is refused, not read
    blob.write_bytes(data[:-8])
    failed = subprocess.run([sys.executable, str(script), str(unzipped), "load", str(blob)],
                            check=False, capture_output=True, text=True)
    assert failed.returncode != 0


def test_the_state_does_not_grow_with_the_history(built):
    _, unzipped, _ = built
    s = start(slave(unzipped))
    sizes = []
    for i in range(3000):
        s.setReal(INPUTS, drive(i))
        s.doStep(i * 1e-4, 1e-4)
        if i in (10, 2999):
            state = s.getFMUstate()
            sizes.append(len(s.serializeFMUstate(state)))
            s.freeFMUstate(state)
    assert sizes[0] == sizes[1]
    s.freeInstance()


@pytest.mark.parametrize("form", ["file:///{p}", "file:/{p}", "file://localhost/{p}", "file://host/{p}",
                                  "file:///{p}/", "FILE:///{p}"])
def test_resource_uris_with_and_without_an_authority_and_with_percent_20(built, tmp_path, form):
    _, unzipped, co = built
    spaced = tmp_path / "a dir with spaces"
    shutil.copytree(unzipped, spaced)
    resources = (spaced / "resources").as_posix().lstrip("/").replace(" ", "%20")
    s = slave(spaced, resource_uri=form.format(p=resources))
    assert s.component is not None
    assert s.getReal([12]) == [co.mu]  # mu, read from the resource file
    s.freeInstance()


@pytest.mark.parametrize("uri", ["http://example.com/resources", "file:relative/resources",
                                 "file:///nowhere%20at%20all/resources", "file:///bad%2/resources"])
def test_a_resource_uri_that_leads_nowhere_fails_instantiation(built, uri):
    _, unzipped, _ = built
    s = slave(unzipped, resource_uri=uri)
    assert not s.component
    s.freeLibrary()


def test_errors_are_fmi2_errors_with_a_message_never_a_crash(built, capfd):
    _, unzipped, _ = built
    s = start(slave(unzipped))
    s.setReal(INPUTS, drive(1))
    s.doStep(0.0, 1e-4)
    before = s.getReal(FORCES)
    for bad_input, bad_step in ((float("nan"), 1e-4), (1e-4, -1.0), (float("inf"), 1e-4)):
        s.setReal([0], [bad_input])
        with pytest.raises(Exception, match="status 3"):
            s.doStep(1e-4, bad_step)
        assert s.getReal(FORCES) == before  # the state is left as it was
    logged = capfd.readouterr().out  # FMPy's logger prints the FMU's messages
    assert "input dx = nan: must be a finite number" in logged and "step size -1 s" in logged
    with pytest.raises(Exception, match="status 3"):
        s.setReal([12], [1.0])  # a fixed parameter after initialization
    s.freeInstance()
    # a bad parameter value is refused at the end of initialization
    s = slave(unzipped)
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.setReal([12], [-1.0])
    with pytest.raises(Exception, match="status 3"):
        s.exitInitializationMode()
    assert "mu = -1: must be a finite number ≥ 0" in capfd.readouterr().out
    s.freeInstance()


def test_a_parameter_set_by_the_host_overrides_the_resource_file(built):
    _, unzipped, co = built
    forces = []
    for mu in (co.mu, 2 * co.mu):
        s = slave(unzipped)
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.setReal([12], [mu])
        s.exitInitializationMode()
        s.setReal(INPUTS, [1e-5] * 6)
        s.doStep(0.0, 1e-4)
        forces.append(np.array(s.getReal(FORCES)))
        s.freeInstance()
    assert np.all(forces[1] > forces[0])  # stiffer rubber, more force in every channel


def test_fmpy_rebuilds_the_binary_from_the_fmus_sources(built, tmp_path, monkeypatch):
    from fmpy.build import build_platform_binary

    _, unzipped, _ = built
    # FMPy runs cmake, which pip installs beside this Python
    monkeypatch.setenv("PATH", f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    (tmp_path / "build").mkdir()
    rebuilt = tmp_path / "rebuilt"
    shutil.copytree(unzipped, rebuilt)
    shutil.rmtree(rebuilt / "binaries")
    build_platform_binary(str(rebuilt), build_dir=str(tmp_path / "build"))
    assert (rebuilt / "binaries" / "linux64" / "front_left.so").is_file()
    outputs = []
    for where in (unzipped, rebuilt):
        s = start(slave(where))
        for i in range(30):
            s.setReal(INPUTS, drive(i))
            s.doStep(i * 1e-4, 1e-4)
        outputs.append(np.array(s.getReal(FORCES)))
        s.freeInstance()
    np.testing.assert_allclose(outputs[1], outputs[0], rtol=1e-12)


SIMULATE = textwrap.dedent("""
    import json, sys
    import numpy as np
    from fmpy import simulate_fmu
    path = sys.argv[1]
    h = 2e-4
    t = np.arange(0, 0.2 + h / 2, h)
    names = ["dx", "dy", "dz", "rx", "ry", "rz"]
    signal = np.zeros(t.size, dtype=[("time", float)] + [(n, float) for n in names])
    signal["time"] = t
    for k, n in enumerate(names):
        signal[n] = (1e-4 if k < 3 else 3e-3) * np.sin(2 * np.pi * (5 + 3 * k) * t)
    out = simulate_fmu(path, start_time=0.0, stop_time=0.2, step_size=h, output_interval=h, input=signal,
                       output=["fx", "fy", "fz", "mx", "my", "mz"])
    print(json.dumps({n: out[n].tolist() for n in out.dtype.names}))
""")


def fmpy_only_python() -> Path:
    """A Python with only FMPy installed (and what FMPy needs), in a cache directory; created
    with pip from PyPI the first time."""
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "bushing-explorer" / "fmpy-only"
    python = cache / "bin" / "python"
    if not python.exists() or subprocess.run([str(python), "-c", "import fmpy"], check=False,
                                             capture_output=True).returncode:
        subprocess.run([sys.executable, "-m", "venv", "--clear", str(cache)], check=True, capture_output=True)
        subprocess.run([str(python), "-m", "pip", "install", "--quiet", "fmpy"], check=True, capture_output=True)
    return python


def test_fmpy_in_a_python_with_nothing_of_this_project_simulates_the_same(built, tmp_path):
    result, _, _ = built
    python = fmpy_only_python()
    script = tmp_path / "simulate.py"
    script.write_text(SIMULATE)
    alone = subprocess.run([str(python), str(script), str(result.path)], cwd=tmp_path, capture_output=True,
                           text=True, check=True)
    nothing = subprocess.run([str(python), "-c", "import core"], cwd=tmp_path, check=False, capture_output=True)
    assert nothing.returncode != 0  # the project is not importable there
    here = subprocess.run([sys.executable, str(script), str(result.path)], cwd=tmp_path, capture_output=True,
                          text=True, check=True)
    a, b = json.loads(alone.stdout), json.loads(here.stdout)
    assert len(a["time"]) == len(b["time"]) > 900
    for name in ("fx", "fy", "fz", "mx", "my", "mz"):
        assert np.max(np.abs(a[name])) > 0
        np.testing.assert_allclose(a[name], b[name], rtol=1e-12, atol=1e-12 * np.max(np.abs(b[name])))


def test_the_fmi_headers_built_against_are_the_ones_fmpy_ships():
    from fmu.build import FMI_HEADERS, c_sources

    shipped = Path(fmpy.__file__).parent / "c-code"
    for name in FMI_HEADERS:
        assert (c_sources() / "fmi2" / name).read_bytes() == (shipped / name).read_bytes()
