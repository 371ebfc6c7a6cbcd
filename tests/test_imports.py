"""The core's imports: no circle among its modules (imports inside functions count: one there
only hides a circle; so do those under ``if TYPE_CHECKING:``, which hide one from the
interpreter but not from a reader: the types live below the modules that use them), no
command-line parser or user interface library, and every module importable on its own in a
fresh interpreter, before any other (``core/__init__.py``, which imports most of them, skipped)."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CORE = ROOT / "core"
FORBIDDEN = {"argparse", "panel", "bokeh", "holoviews"}


def _module(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = sorted(_module(p) for p in CORE.rglob("*.py"))


def _imports(tree: ast.AST):
    """Every import statement of a module, at any depth."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        yield from _imports(node)


def _targets(module: str, node) -> set[str]:
    """The modules an import statement of ``module`` loads (absolute names)."""
    if isinstance(node, ast.Import):
        return {alias.name for alias in node.names}
    package = module if (CORE / Path(*module.split(".")[1:]) / "__init__.py").exists() else module.rpartition(".")[0]
    if node.level:
        package = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1])
    base = ".".join(p for p in (package if node.level else "", node.module or "") if p)
    # `from . import x` and `from .pkg import mod` load the submodule when there is one
    return {base} | {f"{base}.{alias.name}" for alias in node.names if f"{base}.{alias.name}" in MODULES}


def _graph() -> dict[str, set[str]]:
    graph = {}
    for module in MODULES:
        path = CORE / Path(*module.split(".")[1:])
        path = path / "__init__.py" if path.is_dir() else path.with_suffix(".py")
        tree = ast.parse(path.read_text(encoding="utf-8"))
        graph[module] = set().union(*(_targets(module, n) for n in _imports(tree)), set())
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """A circle among the core's modules, as the list of modules along it; None if there is none.
    A package's ``__init__`` runs before its modules: the edge a module → its package is left
    out (it is no import the module makes), as is a package → its own modules' ``__init__``."""
    state, stack = {}, []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if nxt not in graph or node.startswith(nxt + ".") or nxt == node:
                continue
            if state.get(nxt) == "open":
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        state[node] = "done"
        stack.pop()
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_the_core_modules_import_each_other_without_a_circle():
    graph = _graph()
    assert "core.rules" in graph and graph["core.design"] >= {"core.effects", "core.rules"}
    circle = _cycle(graph)
    assert circle is None, " → ".join(circle)


def test_the_core_imports_no_command_line_parser_and_no_user_interface():
    graph = _graph()
    used = {m: sorted({t.split(".")[0] for t in targets} & FORBIDDEN) for m, targets in graph.items()}
    assert not {m: u for m, u in used.items() if u}


@pytest.mark.parametrize("module", MODULES)
def test_each_core_module_imports_on_its_own(module):
    alone = ("import sys, types; core = types.ModuleType('core'); core.__path__ = [sys.argv[1]]; "
             "sys.modules['core'] = core; " if module != "core" else "") + f"import {module}"
    done = subprocess.run([sys.executable, "-c", alone, str(CORE)], cwd=ROOT, capture_output=True, text=True,
                          check=False)
    assert done.returncode == 0, done.stderr
