"""Write the bushing as an FMI 2.0 co-simulation FMU (docs/fmu.md): ``modelDescription.xml``,
the C sources, the resource file with the design's coefficients and, where a C compiler is
found, the binary for this platform, compiled from the same sources.

The binary is plain C (libc and libm): no Python inside, nothing of this project needed by
the host.
"""

from __future__ import annotations

import hashlib
import os
import platform
import re
import shutil
import subprocess
import tempfile
import uuid
import zipfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from .description import default_step, model_description, parameters, resource_text

KERNEL_SOURCES = ("bushing_kernel.c", "bushing_series.c")  # the element alone: no FMI in it
SOURCES = (*KERNEL_SOURCES, "bushing_resource.c", "bushing_fmu.c", "bushing_state.c")
HEADERS = ("bushing_kernel.h", "bushing_series.h", "bushing_resource.h", "bushing_fmu.h")
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
TOOL = "bushing-explorer (bushing fmu)"
CFLAGS = ("-std=c99", "-O2", "-fPIC", "-shared", "-fvisibility=hidden")


class FmuError(ValueError):
    """The FMU cannot be written (the output is not writable, the coefficients are bad)."""


@dataclass(frozen=True)
class FmuResult:
    """What :func:`write_fmu` wrote: the FMU's path, its binary's path inside the archive
    (None for a source-only FMU) and a sentence on why there is none."""

    path: Path
    binary: str | None
    note: str | None = None


def c_sources() -> Path:
    """The directory of the C sources and the FMI 2.0 headers (package data)."""
    return Path(str(resources.files(__package__) / "c"))


def platform_folder() -> tuple[str, str] | None:
    """(FMI 2.0 binaries folder, shared-library suffix) of this machine, or None."""
    machine = platform.machine().lower()
    if machine not in ("x86_64", "amd64"):
        return None
    return {"Linux": ("linux64", ".so"), "Darwin": ("darwin64", ".dylib")}.get(platform.system())


def find_compiler() -> str | None:
    """The system C compiler: ``$CC`` if set, else ``cc`` on the PATH (None if there is none)."""
    return shutil.which(os.environ.get("CC") or "cc")


def model_identifier(path: Path) -> str:
    """A C identifier from the FMU's file name (the binary's name and the FMI model id)."""
    name = re.sub(r"\W", "_", path.stem, flags=re.ASCII) or "bushing"
    return name if not name[0].isdigit() else f"bushing_{name}"


def compile_binary(compiler: str, out: Path) -> str | None:
    """Compile the FMU's shared library to ``out``; None on success, else the compiler's
    first error line."""
    src = c_sources()
    command = [compiler, *CFLAGS, "-I", str(src / "fmi2"), "-I", str(src),
               *(str(src / f) for f in SOURCES), "-o", str(out), "-lm"]
    try:
        done = subprocess.run(command, check=False, capture_output=True, text=True, timeout=300)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return str(exc)
    if done.returncode != 0:
        lines = [ln for ln in done.stderr.splitlines() if "error" in ln] or done.stderr.splitlines() or ["?"]
        return lines[0]
    return None


def write_fmu(coefficients, path, *, model_name: str | None = None, description: str | None = None,
              compiler: str | None | bool = True) -> FmuResult:
    """Write the FMU of a bushing element's coefficients.

    Parameters
    ----------
    coefficients : core.element.Coefficients
        The element's coefficients (:func:`core.element.coefficients`), SI: the FMU's parameters
        (:meth:`~core.element.Coefficients.parameters`) and, from its band and the held input's
        error, the default experiment's step (:func:`fmu.description.default_step`).
    path : str or pathlib.Path
        The ``.fmu`` file to write (replaced if it exists), with the permissions of a new file
        (0666 less the umask).
    model_name : str, optional
        The model's name in ``modelDescription.xml`` (default: the file's stem).
    description : str, optional
        A sentence for ``modelDescription.xml``.
    compiler : str, True or None
        The C compiler's path; True: :func:`find_compiler`; None: none (source only).

    Returns
    -------
    FmuResult
        The path, the binary's name in the archive (None without a compiler) and a note.

    Raises
    ------
    FmuError
        If the coefficients are not of the element's shape or the file cannot be written.
    """
    path = Path(path)
    try:
        params, sizes = parameters(coefficients)
    except ValueError as exc:
        raise FmuError(f"coefficients: {exc}") from None
    ident = model_identifier(path)
    body = resource_text(params, sizes, "-")
    guid = "{" + str(uuid.UUID(hashlib.sha256(body.encode()).hexdigest()[:32])) + "}"
    files = {
        "modelDescription.xml": model_description(
            params, model_identifier=ident, model_name=model_name or path.stem, guid=guid,
            step=default_step(coefficients), source_files=SOURCES, generation_tool=TOOL,
            description=description or "A rubber bushing with frequency- and amplitude-dependent "
                                       "stiffness (Bushing Explorer's time-domain element)").encode(),
        "resources/coefficients.txt": resource_text(params, sizes, guid).encode(),
    }
    src = c_sources()
    for name in (*SOURCES, *HEADERS):
        files[f"sources/{name}"] = (src / name).read_bytes()
    if compiler is True:
        compiler = find_compiler()
    binary, note = None, None
    target = platform_folder()
    with tempfile.TemporaryDirectory() as tmp:
        if not compiler:
            note = "no C compiler found (install one, e.g. gcc, or set CC): wrote the source-only FMU"
        elif target is None:
            note = f"no FMI 2.0 binary folder for {platform.system()} {platform.machine()}: wrote the source-only FMU"
        else:
            folder, suffix = target
            lib = Path(tmp) / f"{ident}{suffix}"
            failed = compile_binary(compiler, lib)
            if failed:
                note = f"the C compiler failed ({failed}): wrote the source-only FMU"
            else:
                binary = f"binaries/{folder}/{ident}{suffix}"
                files[binary] = lib.read_bytes()
        _write_zip(path, files)
    return FmuResult(path, binary, note)


def _umask() -> int:
    """The process's umask (read by setting it and setting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _write_zip(path: Path, files: dict[str, bytes]) -> None:
    """The archive written beside its destination and moved over it: never half a file. It gets
    a new file's usual permissions, 0666 less the umask (a temporary file is 0600)."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=".fmu-", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise FmuError(f"{path}: cannot write there ({exc.strerror or exc})") from None
    try:
        with os.fdopen(fd, "wb") as raw, zipfile.ZipFile(raw, "w", zipfile.ZIP_DEFLATED) as zf:
            for name, data in files.items():
                zf.writestr(name, data)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise FmuError(f"{path}: cannot write it ({exc.strerror or exc})") from None
