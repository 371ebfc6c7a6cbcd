"""What the package needs at run time: the finite-element library (felupe, GPL-3.0) only builds
and checks the shape-factor table (the `fe` extra), never serves a result."""

import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_fe_library_is_an_extra_not_a_dependency():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert not any(d.startswith("felupe") for d in project["dependencies"])
    assert any(d.startswith("felupe") for d in project["optional-dependencies"]["fe"])


def test_every_direction_and_the_app_run_without_the_fe_library():
    # finite-length radial and conical stiffness come from the shipped table; the app and the
    # command line load without the FE library
    code = (
        "import sys\n"
        "import cli.main, app.main\n"
        "from core import PAPER_B, stiffness\n"
        "for mode in ('axial', 'radial', 'torsion', 'conical'):\n"
        "    assert abs(stiffness(PAPER_B.in_mode(mode), [10.0], [1e-4]).magnitude[0, 0]) > 0\n"
        "print('felupe' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


COPYLEFT = ("GPL", "AGPL", "GNU General Public", "Affero")  # LGPL and MPL-2.0 are fine to depend on


def licence_of(dist) -> str:
    meta = dist.metadata
    classifiers = [c for c in meta.get_all("Classifier") or [] if c.startswith("License ::")]
    return " | ".join(filter(None, [meta.get("License-Expression"), (meta.get("License") or "")[:200], *classifiers]))


def runtime_closure() -> dict[str, str]:
    """Every distribution the installed package needs at run time (its requirements without
    extras, and theirs), with its declared licence."""
    from importlib import metadata

    from packaging.requirements import Requirement

    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    todo, seen = [Requirement(r).name for r in project["dependencies"]], {}
    while todo:
        name = todo.pop().lower().replace("_", "-")
        if name in seen:
            continue
        dist = metadata.distribution(name)
        seen[name] = licence_of(dist)
        todo += [Requirement(r).name for r in dist.requires or []
                 if Requirement(r).marker is None or Requirement(r).marker.evaluate({"extra": ""})]
    return seen


def test_the_project_has_a_permissive_licence_and_so_has_everything_it_runs_on():
    """BSD-3-Clause (the licence of Panel, HoloViews and Bokeh), declared in pyproject.toml and
    written in LICENSE; no run-time dependency, direct or indirect, is under the GPL (felupe,
    GPL-3.0, stays an extra)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert project["license"] == "BSD-3-Clause"
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("BSD 3-Clause License") and "Neither the name of the copyright holder" in text
    closure = runtime_closure()
    assert {"numpy", "scipy", "panel", "holoviews", "bokeh"} <= closure.keys()
    assert "felupe" not in closure
    for name, licence in closure.items():
        assert licence.strip(), f"{name} declares no licence"
        words = licence.replace("LGPL", "").replace("Lesser General Public", "")
        assert not any(c in words for c in COPYLEFT), f"{name}: {licence}"


def test_fmpy_the_fmus_checks_use_is_a_test_extra_under_bsd_2_clause():
    """FMPy (the FMU's independent importer and validator, tests/test_fmu.py) declares no licence
    in its metadata; its licence file says 2-Clause BSD. It is only in the test extra."""
    from importlib import metadata

    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert not any(d.lower().startswith("fmpy") for d in project["dependencies"])
    assert any(d.lower().startswith("fmpy") for d in project["optional-dependencies"]["test"])
    try:
        dist = metadata.distribution("fmpy")
    except metadata.PackageNotFoundError:
        return  # not installed here: nothing more to read
    texts = [f.read_text() for f in dist.files or [] if "licen" in str(f).lower()]
    assert any("2-Clause BSD" in t for t in texts)


def test_exudyn_the_examples_engine_is_an_extra_under_bsd_3_clauses_conditions():
    """Exudyn (examples/exudyn_bushing.py) is the `exudyn` extra, which the test extra pulls in,
    never a run-time dependency; its metadata names the "EXUDYN General License", whose text
    carries BSD-3-Clause's three conditions."""
    from importlib import metadata

    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    extras = project["optional-dependencies"]
    assert not any(d.lower().startswith("exudyn") for d in project["dependencies"])
    assert any(d.lower().startswith("exudyn") for d in extras["exudyn"])
    assert "bushing-explorer[exudyn]" in extras["test"]
    try:
        dist = metadata.distribution("exudyn")
    except metadata.PackageNotFoundError:
        return  # not installed here: nothing more to read
    texts = [" ".join(f.read_text().split()) for f in dist.files or [] if "licen" in str(f).lower()]
    assert any(t.startswith("EXUDYN General License")
               and "Redistributions of source code must retain the above copyright notice" in t
               and "Neither the name of the copyright holders nor the names of its contributors may be used" in t
               for t in texts)
