"""What the FMU says about itself: its variables with units, ``modelDescription.xml``, the
resource file the C kernel starts from and the default experiment's step (docs/fmu.md).

The FMU's parameters are the element's coefficients as :meth:`core.element.Coefficients.parameters`
lists them: names (indices from 1), units, descriptions and order come from there, once; here
they only become ScalarVariables, unit definitions and the resource file's lines.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence

from core.element import CHANNEL_MODES, CHANNELS, OUTPUTS, Coefficients, Element, Parameter
from core.element.element import HELD_LIMIT

RESOURCE_FILE = "coefficients.txt"  # BR_FILE in fmu/c/bushing_resource.h
RESOURCE_VERSION = 1  # BR_VERSION
MAX_EXPONENTIALS = 64  # BK_MAX_EXPONENTIALS in fmu/c/bushing_kernel.h
MAX_LAYERS = 1000  # BK_MAX_LAYERS
# the default step is sought between these many steps a period of the band's top f₂
STEPS_PER_PERIOD = (2, 10_000_000)

# SI base-unit exponents of every unit a variable has (the parameters' units are
# Coefficients.parameters()'); units with a non-integer exponent (the fractional coefficient's
# Pa.s^α, the weights' s^-α) carry no BaseUnit
UNITS = {
    "1": {},
    "m": {"m": 1},
    "rad": {"rad": 1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "Pa.s": {"kg": 1, "m": -1, "s": -1},
    "1/s": {"s": -1},
    "1/m": {"m": -1},
    "1/rad": {"rad": -1},
    "m3/rad": {"m": 3, "rad": -1},
    "m/N": {"kg": -1, "s": 2},
    "rad/(N.m)": {"kg": -1, "m": -2, "s": 2, "rad": 1},
}


class CoefficientsError(ValueError):
    """The coefficients are not :class:`core.element.Coefficients`, or exceed the C kernel's sizes."""


def parameters(coefficients: Coefficients) -> tuple[list[Parameter], tuple[int, tuple[int, ...]]]:
    """The FMU's parameters: :meth:`core.element.Coefficients.parameters`, checked against the C
    kernel's limits, and the sizes the kernel reads them by.

    Parameters
    ----------
    coefficients : core.element.Coefficients
        From :func:`core.element.coefficients` (SI).

    Returns
    -------
    (list of Parameter, (int, tuple of int))
        The parameters in the kernel's order (names with indices from 1) and the sizes: the
        number of exponentials J and the six channels' layer counts.

    Raises
    ------
    CoefficientsError
        If ``coefficients`` is not a :class:`~core.element.Coefficients` or has more
        exponentials or layers than the kernel takes.
    """
    if not isinstance(coefficients, Coefficients):
        raise CoefficientsError("coefficients: give core.element.coefficients(design, slices, band), got "
                                f"{type(coefficients).__name__}")
    layers = tuple(len(coefficients.channels[ch].S) for ch in CHANNELS)
    if len(coefficients.rate) > MAX_EXPONENTIALS or max(layers) > MAX_LAYERS:
        raise CoefficientsError(f"at most {MAX_EXPONENTIALS} exponentials and {MAX_LAYERS} layers a channel, got "
                                f"{len(coefficients.rate)} and {max(layers)}")
    return coefficients.parameters(), (len(coefficients.rate), layers)


def _round_down(x: float, digits: int = 2) -> float:
    """``x`` > 0 cut to ``digits`` significant digits, never above ``x`` (a step that reads well)."""
    exponent = math.floor(math.log10(x)) - digits + 1
    mantissa = math.floor(x / 10.0**exponent * (1 + 1e-12))
    value = float(f"{mantissa}e{exponent}")
    return value if value <= x else float(f"{mantissa - 1}e{exponent}")


def default_step(coefficients: Coefficients, limit: tuple[float, float] = HELD_LIMIT) -> float:
    """The default experiment's step, s: the longest step h whose held input keeps the element's
    fractional term within ``limit`` (relative magnitude, phase in rad; default the element's own
    warning threshold, :data:`core.element.element.HELD_LIMIT`) of (iω)^α over the band, by
    :meth:`core.element.Element.held_error`.

    A bisection on log h between 1/(10⁷ f₂) and 1/(2 f₂) (:data:`STEPS_PER_PERIOD`, f₂ the band's
    top) to 1 %, the result cut to two significant digits (so 1.5 h is past the threshold); the
    bounds themselves when the threshold holds at the longest or fails at the shortest."""
    element = Element(coefficients)
    f2 = coefficients.band[1]

    def meets(h):
        mag, phase = element.held_error(h)
        return mag <= limit[0] and phase <= limit[1]

    lo, hi = 1.0 / (STEPS_PER_PERIOD[1] * f2), 1.0 / (STEPS_PER_PERIOD[0] * f2)
    if meets(hi):
        return _round_down(hi)
    if not meets(lo):
        return _round_down(lo)
    for _ in range(64):  # 11 halvings of the log interval reach 1 %
        if hi / lo <= 1.01:
            break
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if meets(mid) else (lo, mid)
    return _round_down(lo)


def _g(x: float) -> str:
    """A float written so that it reads back exactly (shortest repr)."""
    return repr(float(x))


def resource_text(params: list[Parameter], sizes: tuple[int, tuple[int, ...]], guid: str) -> str:
    """The resource file ``coefficients.txt`` the kernel reads at instantiation
    (``br_read`` in fmu/c/bushing_resource.c): a version line, the GUID, the sizes, then one
    ``name value`` line per parameter in the kernel's order."""
    lines = [f"bushing-fmu-coefficients {RESOURCE_VERSION}", f"guid {guid}",
             f"exponentials {sizes[0]}", "layers " + " ".join(str(n) for n in sizes[1])]
    lines += [f"{p.name} {_g(p.value)}" for p in params]
    return "\n".join(lines) + "\n"


def _unit_element(parent: ET.Element, name: str) -> None:
    unit = ET.SubElement(parent, "Unit", name=name)
    exponents = UNITS.get(name)
    if exponents:
        ET.SubElement(unit, "BaseUnit", {k: str(v) for k, v in exponents.items()})


def model_description(params: list[Parameter], *, model_identifier: str, model_name: str, guid: str,
                      step: float, source_files: Sequence[str], description: str,
                      generation_tool: str) -> str:
    """``modelDescription.xml`` of the FMU: FMI 2.0 co-simulation, the six inputs held over a
    step (value references 0–5), the six outputs (6–11), the parameters (12 on, fixed),
    units for every variable, the ModelStructure and a default experiment of ``step`` s
    (:func:`default_step`)."""
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": model_name, "guid": guid, "description": description,
        "generationTool": generation_tool, "variableNamingConvention": "structured",
        "numberOfEventIndicators": "0"})
    cs = ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": model_identifier, "needsExecutionTool": "false",
        "canHandleVariableCommunicationStepSize": "true", "canInterpolateInputs": "false",
        "maxOutputDerivativeOrder": "0", "canRunAsynchronuously": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false", "canNotUseMemoryManagementFunctions": "false",
        "canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true",
        "providesDirectionalDerivative": "false"})
    files = ET.SubElement(cs, "SourceFiles")
    for name in source_files:
        ET.SubElement(files, "File", name=name)
    used = {"m", "rad", "N", "N.m"} | {p.unit for p in params}
    units = ET.SubElement(root, "UnitDefinitions")
    for name in sorted(used):
        _unit_element(units, name)
    cats = ET.SubElement(root, "LogCategories")
    ET.SubElement(cats, "Category", name="logStatusError", description="errors: why a call failed")
    ET.SubElement(cats, "Category", name="logAll", description="every message")
    ET.SubElement(root, "DefaultExperiment", startTime="0", stopTime="1",
                  stepSize=_g(step))
    variables = ET.SubElement(root, "ModelVariables")
    for vr, name in enumerate(CHANNELS):
        direction = CHANNEL_MODES[name]
        unit = "rad" if name.startswith("r") else "m"
        what = "rotation" if name.startswith("r") else "displacement"
        var = ET.SubElement(variables, "ScalarVariable", name=name, valueReference=str(vr),
                            causality="input", variability="continuous",
                            description=f"{direction} {what} of the inner sleeve about the bushing's "
                                        f"centre (axis z), held over each step")
        ET.SubElement(var, "Real", start="0", unit=unit)
    for k, (name, direction) in enumerate(zip(OUTPUTS, CHANNEL_MODES.values(), strict=True)):
        unit = "N.m" if name.startswith("m") else "N"
        what = "moment" if name.startswith("m") else "force"
        var = ET.SubElement(variables, "ScalarVariable", name=name, valueReference=str(6 + k),
                            causality="output", variability="continuous",
                            description=f"{direction} {what} of the rubber on the inner sleeve at the "
                                        f"step's end, for the input held over the step")
        ET.SubElement(var, "Real", unit=unit)
    for k, p in enumerate(params):
        var = ET.SubElement(variables, "ScalarVariable", name=p.name, valueReference=str(12 + k),
                            causality="parameter", variability="fixed", initial="exact",
                            description=p.description)
        ET.SubElement(var, "Real", start=_g(p.value), unit=p.unit)
    structure = ET.SubElement(root, "ModelStructure")
    outputs = ET.SubElement(structure, "Outputs")
    initial = ET.SubElement(structure, "InitialUnknowns")
    for k in range(len(OUTPUTS)):
        # an output changes at a step only: it does not depend on the inputs directly
        ET.SubElement(outputs, "Unknown", index=str(7 + k), dependencies="")
        ET.SubElement(initial, "Unknown", index=str(7 + k), dependencies="")
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
