"""Regenerate the example data sets in this folder. They are SYNTHETIC: made from the model with
the stated parameters and stated noise, so that a newcomer can try `bushing fit` at once.

    python examples/make_examples.py [OUT_DIR]

writes them into this folder, or into OUT_DIR (tests/test_examples.py compares the two).

Noise: each complex stiffness is multiplied by (1 + n), n complex Gaussian with 0.5 % standard
deviation in its real and imaginary parts; loop forces get Gaussian noise of 0.5 % of their peak.
The random generators are seeded (12345 …), so the files are reproducible; the explorer's
"Load the synthetic example" button makes the same Paper B data (core/synthetic.py).
"""

import sys
from pathlib import Path

import numpy as np

from core import PAPER_B, TABLE_1, write_design
from core.synthetic import PAPER_B_AMPLITUDES, paper_b_example, synthetic_stiffness

HERE = Path(__file__).resolve().parent


def main(out: Path = HERE) -> None:
    """Write every generated example into ``out`` (created if missing)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    # Paper B bushing (axial): the thesis' amplitudes, 1-100 Hz, 150 points; the 0.1 Hz, 1 mm loop
    data, loop = paper_b_example(PAPER_B)
    data.to_csv(out / "paper_b_stiffness.csv")
    loop.to_csv(out / "paper_b_loop.csv")
    synthetic_stiffness(PAPER_B, np.linspace(1, 100, 100), [0.1e-3], seed=12347).to_csv(
        out / "paper_b_sweep_0.1mm.csv")
    # Table 1 bushing (torsion): 10-100 Hz at five angles, as real and imaginary parts
    synthetic_stiffness(TABLE_1, np.linspace(10, 100, 19),
                        [1.74e-5, 1.74e-4, 1.74e-3, 1.74e-2, 1.74e-1], seed=12348).to_csv(
        out / "table1_torsion_stiffness.csv", polar=False)
    # starting guesses: the right geometry, a deliberately poor material
    write_design(PAPER_B.replace(name="Paper B geometry, starting guess", shear_modulus=1.5e6,
                                 fractional_coefficient=1.0e6, fractional_order=0.4,
                                 friction_stress_max=4.0e4, friction_strain_half=1.0e-3),
                 out / "paper_b_guess.json")
    write_design(TABLE_1.replace(name="Table 1 geometry, starting guess", shear_modulus=1.0e6,
                                 fractional_coefficient=5.0e5, fractional_order=0.2,
                                 friction_stress_max=1.0e4, friction_strain_half=3.0e-3),
                 out / "table1_guess.json")
    # the discrepancy workflow: Paper B measured through a 0.5 kg fixture (inertia the model lacks)
    synthetic_stiffness(PAPER_B.replace(effects={"inertia": {"mass": 0.5}}),
                        np.linspace(1, 100, 30), PAPER_B_AMPLITUDES, seed=12349).to_csv(
        out / "paper_b_with_fixture_mass.csv")
    write_design(PAPER_B, out / "paper_b_true.json")
    write_design(TABLE_1, out / "table1_true.json")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE)
