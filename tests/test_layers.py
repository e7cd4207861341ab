"""The code's structure: floors that import only downward, short functions, a light import.

The import graph is read from the source (``ast``), function-level imports included: a module
that imports another inside a function still depends on it.
"""

import ast
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("steady", "transient")

#: The commands: the top floor, which no library module may import.
COMMANDS = ("steady.cli", "steady.__main__", "transient.cli", "transient.__main__")

#: Longest function allowed in the packages, lines.
MAX_FUNCTION_LINES = 120


def _module_name(path):
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules():
    """``name -> path`` of every module of the packages."""
    return {_module_name(p): p for package in PACKAGES for p in (ROOT / package).rglob("*.py")}


def _imports(name, path, modules):
    """The project modules ``name`` imports, anywhere in its source."""
    tree = ast.parse(path.read_text())
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            candidates = [target] + [f"{target}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            candidates = [alias.name for alias in node.names]
        else:
            continue
        found.update(c for c in candidates if c in modules and c != name)
    return found


def _graph():
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def _is_command(name):
    return any(name == c or name.startswith(c + ".") for c in COMMANDS)


def test_no_library_module_imports_a_command():
    bad = sorted((name, target) for name, targets in _graph().items() if not _is_command(name)
                 for target in targets if _is_command(target))
    assert not bad, f"library modules import the command line: {bad}"


def test_steady_does_not_know_transient():
    bad = sorted((name, target) for name, targets in _graph().items()
                 if name.split(".")[0] == "steady" for target in targets
                 if target.split(".")[0] == "transient")
    assert not bad, f"steady imports transient: {bad}"


def test_the_import_graph_has_no_cycle():
    graph = _graph()
    # A package's __init__ re-exports its modules; an edge into a package's __init__ from a
    # module inside it would be the cycle to find, so keep the __init__ nodes.
    state, stack, cycles = {}, [], []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for target in sorted(graph.get(node, ())):
            if state.get(target) == "open":
                cycles.append(stack[stack.index(target):] + [target])
            elif target not in state:
                visit(target)
        stack.pop()
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node)
    assert not cycles, f"import cycles: {cycles[:3]}"


def test_no_function_is_longer_than_the_limit():
    long = []
    for path in _modules().values():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name} ({lines})")
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines: {long}"


@pytest.mark.parametrize("heavy", ["h5py", "matplotlib", "skimage", "steady.scene"])
def test_import_steady_loads_no_file_or_figure_library(heavy):
    code = f"import sys, steady; print({heavy!r} in sys.modules)"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, check=True)
    assert proc.stdout.strip() == "False", f"import steady imported {heavy}"


def test_steady_names_import_on_first_use():
    code = ("import sys, steady; steady.solve; print('steady.solution' in sys.modules, "
            "'h5py' in sys.modules, sorted(steady.__all__) == steady.__all__)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, check=True)
    assert proc.stdout.split() == ["True", "False", "True"], \
        f"steady.solve did not import steady.solution alone: {proc.stdout}"
