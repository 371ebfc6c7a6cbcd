"""Bushing Explorer's computational core: pure NumPy/SciPy, no user interface.

Dynamic stiffness of carbon-black-filled rubber bushings in torsion and axially, over
frequency and amplitude, after García Tárrago (KTH, 2006). See docs/model.md for the physics.
"""

from .bushing import StiffnessResult, shape_factor, stiffness, stiffness_points, strain_factor
from .design import PAPER_B, TABLE_1, Design
from .io.design_file import dumps_design, loads_design, read_design, write_design
from .loops import HistoryResult, LoopResult, force_history, loop
from .material import ConvergenceError, equivalent_modulus, equivalent_modulus_time_domain
from .parts import Geometry, Material
from .rules import DesignError

__all__ = [
    "PAPER_B",
    "TABLE_1",
    "ConvergenceError",
    "Design",
    "DesignError",
    "Geometry",
    "HistoryResult",
    "LoopResult",
    "Material",
    "StiffnessResult",
    "dumps_design",
    "equivalent_modulus",
    "equivalent_modulus_time_domain",
    "force_history",
    "loads_design",
    "loop",
    "read_design",
    "shape_factor",
    "stiffness",
    "stiffness_points",
    "strain_factor",
    "write_design",
]
