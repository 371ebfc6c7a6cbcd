"""What the FMU says about itself: its variables with units, ``modelDescription.xml`` and the
resource file the C kernel starts from (docs/fmu.md, docs/element.md's coefficients).

The one seam with the element is :func:`parameters`: it takes the element's coefficients as a
mapping (``core.element.coefficients(design, slices, band).as_dict()``) and lists the FMU's
parameters in the kernel's order (``fmu/c/bushing_kernel.h``).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

CHANNELS = ("dx", "dy", "dz", "rx", "ry", "rz")
OUTPUTS = ("fx", "fy", "fz", "mx", "my", "mz")
DIRECTIONS = ("radial", "radial", "axial", "conical", "conical", "torsion")
ROTATION = ("rx", "ry", "rz")
RESOURCE_FILE = "coefficients.txt"  # BR_FILE in fmu/c/bushing_resource.h
RESOURCE_VERSION = 1  # BR_VERSION
MAX_EXPONENTIALS = 64  # BK_MAX_EXPONENTIALS in fmu/c/bushing_kernel.h
MAX_LAYERS = 1000  # BK_MAX_LAYERS
STEPS_PER_PERIOD = 400  # docs/element.md: h ≤ T/400 at the highest frequency that matters

# SI base-unit exponents of every unit a variable has; units with a non-integer exponent (the
# fractional coefficient's Pa·s^α) are named with their exponent and carry no BaseUnit
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

# the material scalars, in the kernel's order (enum BK_MU … BK_VISCOSITY)
SCALARS = (
    ("mu", "Pa", "µ, the elastic branch's shear modulus"),
    ("m", "Pa.s^alpha", "m, the fractional branch's coefficient"),
    ("alpha", "1", "α, the fractional order (for reading: the weights carry it)"),
    ("sigma_f_max", "Pa", "σ_fmax, the friction stress limit (0: no friction)"),
    ("eps_half", "1", "ε½, the friction half strain"),
    ("beta", "1", "β, strain stiffening in 2µε(1 + βε²) (0: none)"),
    ("viscosity", "Pa.s", "c_v, the viscous coefficient (0: none)"),
)
OPTIONAL_SCALARS = ("beta", "viscosity")  # absent: 0


class CoefficientsError(ValueError):
    """The coefficients mapping is not of the element's shape (docs/element.md)."""


@dataclass(frozen=True)
class Parameter:
    """One FMU parameter: its readable name, value (SI), unit and description."""

    name: str
    value: float
    unit: str
    description: str


def _number(name: str, value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise CoefficientsError(f"{name}: must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise CoefficientsError(f"{name}: must be finite, got {x!r}")
    return x


def _numbers(name: str, values) -> list[float]:
    try:
        items = None if isinstance(values, (str, bytes, Mapping)) else list(values)
    except TypeError:
        items = None
    if items is None:
        raise CoefficientsError(f"{name}: must be a list of numbers, got {values!r}")
    return [_number(f"{name}[{k + 1}]", v) for k, v in enumerate(items)]


def _channel(coefficients: Mapping, channel: str) -> tuple[list[float], list[float], float]:
    """(S, c, compliance) of a channel: ``coefficients["channels"][channel]["S"]`` (as
    :meth:`core.element.Coefficients.as_dict` has them), ``coefficients[channel]["S"]`` … or the
    flat ``coefficients[f"{channel}.S"]`` …"""
    channels = coefficients.get("channels")
    nested = channels.get(channel) if isinstance(channels, Mapping) else coefficients.get(channel)
    if isinstance(nested, Mapping):
        get = nested.get
    else:
        def get(key, default=None):
            return coefficients.get(f"{channel}.{key}", default)
    s, c = get("S"), get("c")
    if s is None or c is None:
        raise CoefficientsError(f"{channel}: its layers' S and c are missing")
    s, c = _numbers(f"{channel}.S", s), _numbers(f"{channel}.c", c)
    if not 1 <= len(s) <= MAX_LAYERS or len(s) != len(c):
        raise CoefficientsError(f"{channel}: S and c must be two lists of 1 to {MAX_LAYERS} layers "
                                f"of one length, got {len(s)} and {len(c)}")
    return s, c, _number(f"{channel}.compliance", get("compliance", 0.0))


def parameters(coefficients) -> tuple[list[Parameter], tuple[int, tuple[int, ...]]]:
    """The FMU's parameters from the element's coefficients: THE seam with ``core.element``.

    Parameters
    ----------
    coefficients : mapping or object with ``as_dict()``
        The element's coefficients (docs/element.md, SI): the material scalars ``mu`` (Pa),
        ``m`` (Pa·s^α), ``alpha``, ``sigma_f_max`` (Pa), ``eps_half``, ``beta`` and
        ``viscosity`` (Pa·s; these two 0 when absent); the lists ``rate`` (1/s) and ``weight``
        (s^−α) of one length; and per channel ``dx`` … ``rz`` either a mapping
        ``{"S": [...], "c": [...], "compliance": C_b}`` or the flat keys ``"dx.S"``,
        ``"dx.c"``, ``"dx.compliance"`` (S in m or m³/rad, c in 1/m or 1/rad, C_b in m/N or
        rad/(N·m), 0 when absent).

    Returns
    -------
    (list of Parameter, (int, tuple of int))
        The parameters in the kernel's order (mu … viscosity, rate[1…J], weight[1…J], then
        per channel S[1…N], c[1…N], compliance; indices from 1), and the sizes (J, the six
        channels' layer counts).

    Raises
    ------
    CoefficientsError
        If a key is missing or a value is no finite number.
    """
    if hasattr(coefficients, "as_dict"):
        coefficients = coefficients.as_dict()
    if not isinstance(coefficients, Mapping):
        raise CoefficientsError(f"coefficients: must be a mapping, got {type(coefficients).__name__}")
    alpha = coefficients.get("alpha")
    alpha_text = f"{_number('alpha', alpha):.6g}" if alpha is not None else "alpha"
    out = []
    for name, unit, text in SCALARS:
        if name not in coefficients and name not in OPTIONAL_SCALARS:
            raise CoefficientsError(f"{name}: missing")
        unit = unit.replace("alpha", alpha_text)
        out.append(Parameter(name, _number(name, coefficients.get(name, 0.0)), unit, text))
    rate, weight = (_numbers(k, coefficients.get(k, [])) for k in ("rate", "weight"))
    if len(rate) != len(weight) or len(rate) > MAX_EXPONENTIALS:
        raise CoefficientsError(f"rate, weight: two lists of at most {MAX_EXPONENTIALS} exponentials "
                                f"of one length, got {len(rate)} and {len(weight)}")
    out += [Parameter(f"rate[{j + 1}]", v, "1/s", f"λ_{j + 1}, the rate of exponential {j + 1}")
            for j, v in enumerate(rate)]
    out += [Parameter(f"weight[{j + 1}]", v, f"s^-{alpha_text}", f"g_{j + 1}, the weight of exponential {j + 1}")
            for j, v in enumerate(weight)]
    layers = []
    for ch, direction in zip(CHANNELS, DIRECTIONS, strict=True):
        s, c, compliance = _channel(coefficients, ch)
        turn = ch in ROTATION
        layers.append(len(s))
        out += [Parameter(f"{ch}.S[{k + 1}]", v, "m3/rad" if turn else "m",
                          f"{direction} channel {ch}: layer {k + 1}'s shape factor") for k, v in enumerate(s)]
        out += [Parameter(f"{ch}.c[{k + 1}]", v, "1/rad" if turn else "1/m",
                          f"{direction} channel {ch}: layer {k + 1}'s strain factor") for k, v in enumerate(c)]
        out.append(Parameter(f"{ch}.compliance", compliance, "rad/(N.m)" if turn else "m/N",
                             f"{direction} channel {ch}: the series bulk compliance C_b (0: none)"))
    return out, (len(rate), tuple(layers))


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
                      band: tuple[float, float], source_files: Sequence[str], description: str,
                      generation_tool: str) -> str:
    """``modelDescription.xml`` of the FMU: FMI 2.0 co-simulation, the six inputs held over a
    step (value references 0–5), the six outputs (6–11), the parameters (12 on, fixed),
    units for every variable, the ModelStructure and a default experiment whose step is
    1/(400 f₂) (docs/element.md)."""
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
                  stepSize=_g(1.0 / (STEPS_PER_PERIOD * band[1])))
    variables = ET.SubElement(root, "ModelVariables")
    for vr, (name, direction) in enumerate(zip(CHANNELS, DIRECTIONS, strict=True)):
        unit = "rad" if name in ROTATION else "m"
        what = "rotation" if name in ROTATION else "displacement"
        var = ET.SubElement(variables, "ScalarVariable", name=name, valueReference=str(vr),
                            causality="input", variability="continuous",
                            description=f"{direction} {what} of the inner sleeve about the bushing's "
                                        f"centre (axis z), held over each step")
        ET.SubElement(var, "Real", start="0", unit=unit)
    for k, (name, direction) in enumerate(zip(OUTPUTS, DIRECTIONS, strict=True)):
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
