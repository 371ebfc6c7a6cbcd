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
