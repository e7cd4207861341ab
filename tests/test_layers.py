"""The code's structure: floors that import only downward, short functions, a light import.

:data:`FLOORS` declares the floors of both packages, from the bottom up; every module is on
exactly one, and a module imports only modules on its own floor or below.  ``transient``'s
floors sit above ``steady``'s library, the commands of both packages on top.

The import graph is read from the source (``ast``), function-level imports included: a module
that imports another inside a function still depends on it.  ``from . import reference`` is read
as an import of ``steady.reference`` alone, not of the package: a package's ``__init__`` runs
before any of its modules anyway, and ``steady``'s and ``transient``'s only re-export names on
first use.
"""

import ast
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("steady", "transient")

#: The floors, from the bottom up: name -> its modules.  A module imports only modules on its
#: own floor or a lower one; a new module needs a line here.
FLOORS = {
    # Message text, memory estimates, the version, the packages' lazy names; the registries
    # filled by decorators and the declarative scene keys.
    "base": ("steady.text", "steady.memory", "steady.version", "steady.lazy",
             "steady.registry", "steady.schema"),
    # Arrays on a grid and what acts on them, knowing no outline: the half-space operators
    # (finite and periodic) and the choice between them by a grid's ``periodic``,
    # array files, rasterised labels, eq. 7, depth columns, rms heights, the small-slope
    # warning, measured faces, the closed forms, a face's power spectrum and topography; the
    # counter-body, whose operator is the one place a grid's operator is chosen.
    "fields": ("steady.halfspace", "steady.periodic", "steady.counterbody", "steady.array_files",
               "steady.labels", "steady.pressures", "steady.depth", "steady.relief",
               "steady.validity", "steady.measured_face", "steady.reference",
               "steady.topography"),
    # The face: outlines and their grids, phase geometries (depth-dependent ones too), wear
    # laws, sliding kinematics, load programmes.
    "face": ("steady.outline", "steady.phases", "steady.inclusions", "steady.micrograph",
             "steady.depth_maps", "steady.wear", "steady.sliding", "steady.load_programme"),
    # Estimators on a face: the corrected rms slope, the reference slope of an outline.
    "estimators": ("steady.rms_slope", "steady.normalisation"),
    # The one checked problem definition.
    "problem": ("steady.problem",),
    # Where inputs enter and files are written safely: scene files, the shipped examples,
    # atomic writes, backups and locks.
    "scenes": ("steady.scene", "steady.examples", "steady.safe_files"),
    # The steady features: the solve, the sweep basis, profiles, the wear-ratio fit.
    "steady": ("steady.solution", "steady.basis", "steady.profiles", "steady.fit"),
    # Result files (the format sits above the result it stores) and figures.
    "results": ("steady.output", "steady.plotting"),
    # Resumable sweeps, the design table, the fit's files.
    "studies": ("steady.sweep", "steady.voronoi_sweep", "steady.design", "steady.fit_files"),
    # steady's public names, re-exported from every floor below on first use.
    "steady names": ("steady",),
    # The run-in's numerics and inputs: the contact solver and its preconditioners, the worn
    # depth of a wear work, initial faces, the axisymmetric closed form, the memory of a
    # run, the version.
    "contact": ("transient.contact", "transient.preconditioners", "transient.depth",
                "transient.initial_face", "transient.axisymmetric", "transient.memory",
                "transient.version"),
    # The wear problem (fixed data).
    "wear problem": ("transient.problem",),
    # The stage solver and its warm start; the integrators, step control and run options.
    "stepping": ("transient.warm_start", "transient.solver", "transient.stepping",
                 "transient.control", "transient.options"),
    # The run-in's scene sections and its factory from a scene (above the problem it builds).
    "run-in scenes": ("transient.scene",),
    # The friction proxy along a run: what is recorded of a face, the history's estimator.
    "history": ("transient.diagnostics", "transient.history"),
    # The run: the loop, what it records, its result and the result's run-in distance.
    "run": ("transient.runin", "transient.recording", "transient.result",
            "transient.run_in_distance"),
    # Runs compared: with the steady face, with a coarser grid.
    "comparison": ("transient.comparison", "transient.spatial_error"),
    # Run files and figures.
    "run files": ("transient.output", "transient.plotting"),
    # transient's public names.
    "transient names": ("transient",),
    # The commands of both packages, which no library module imports.
    "commands": ("steady.cli", "steady.cli.common", "steady.cli.entry", "steady.cli.solve",
                 "steady.cli.fit", "steady.cli.design", "steady.cli.examples",
                 "steady.__main__", "transient.cli", "transient.cli.progress",
                 "transient.cli.run_file", "transient.cli.runin", "transient.__main__"),
}

#: The commands: the top floor, which no library module may import.
COMMANDS = FLOORS["commands"]

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
            # A name that is a module is that module's import; any other, the package's.
            candidates = [f"{target}.{alias.name}" if f"{target}.{alias.name}" in modules
                          else target for alias in node.names]
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


def _floor_of():
    """``module -> (rank, floor name)``, rank 0 at the bottom."""
    return {module: (rank, floor) for rank, (floor, modules) in enumerate(FLOORS.items())
            for module in modules}


def test_every_module_is_on_one_floor():
    modules = _modules()
    listed = [module for floor in FLOORS.values() for module in floor]
    missing = sorted(set(modules) - set(listed))
    unknown = sorted(set(listed) - set(modules))
    twice = sorted({module for module in listed if listed.count(module) > 1})
    assert not missing, f"modules on no floor (add them to FLOORS): {missing}"
    assert not unknown, f"FLOORS names modules that do not exist: {unknown}"
    assert not twice, f"modules on more than one floor: {twice}"


def test_imports_go_to_the_same_floor_or_below():
    floor_of = _floor_of()
    up = [f"{name} ({floor_of[name][1]}) imports {target} ({floor_of[target][1]})"
          for name, targets in sorted(_graph().items()) if name in floor_of
          for target in sorted(targets)
          if target in floor_of and floor_of[target][0] > floor_of[name][0]]
    assert not up, "imports up a floor:\n" + "\n".join(up)


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
