"""The bushing as a native FMI 2.0 co-simulation FMU (docs/fmu.md): a generic C kernel
(``fmu/c/``) and the writer that packs it with a design's coefficients (:func:`write_fmu`):
their names, units and order are :meth:`core.element.Coefficients.parameters`'."""

from .build import FmuError, FmuResult, find_compiler, write_fmu
from .description import CoefficientsError, default_step, parameters

__all__ = ["CoefficientsError", "FmuError", "FmuResult", "default_step", "find_compiler", "parameters",
           "write_fmu"]
