"""The bushing as a native FMI 2.0 co-simulation FMU (docs/fmu.md): a generic C kernel
(``fmu/c/``) and the writer that packs it with a design's coefficients (:func:`write_fmu`)."""

from .build import FmuError, FmuResult, find_compiler, write_fmu
from .description import CHANNELS, OUTPUTS, CoefficientsError, parameters

__all__ = ["CHANNELS", "OUTPUTS", "CoefficientsError", "FmuError", "FmuResult", "find_compiler",
           "parameters", "write_fmu"]
