"""The package's layout rules, read from the source with ``ast`` (docs/architecture.md).

Every module of ``cgamesh/`` and ``cli/`` (installed as ``cgamesh_cli``) is parsed; every import
statement counts, at module level, inside functions and under ``if TYPE_CHECKING:`` alike (a
lazy import is still a dependency; only its cost is deferred). The rules:

(a) **No import cycle** among the modules. An edge runs from a module to each project module it
    imports: ``import a.b.c`` and ``from a.b.c import x`` to ``a.b.c``; ``from a.b import c``
    to ``a.b.c`` when that is a module, else to ``a.b``. The parent packages Python runs on the
    way (``a/__init__.py``, ``a/b/__init__.py``) are not edges: a package's ``__init__`` is its
    table of contents and imports nothing eagerly.
(b) **No use of another module's private name.** A name with one leading underscore (not a
    dunder) belongs to the module or package that defines it: only that module may use it, or,
    for a package, the package's own modules (``cgamesh/foo/__init__.py`` and everything under
    ``cgamesh/foo/`` may import ``cgamesh.foo._impl``). Checked on every dotted part of what is
    imported (``from a._b import c``, ``from a.b import _c``) and on attributes read through an
    imported module (``import a.b as m; m._c``), for project modules only.
(c) **No stage reaches back up** (FORBIDDEN): no module under ``cgamesh/geometry/`` or
    ``cgamesh/meshing/`` imports ``cgamesh.inputs`` or anything under it (the stages talk
    through values); the tracer, the mesher's independent referee, imports nothing of
    ``cgamesh.meshing``; and no module of ``cgamesh`` imports the command line.
(d) **No module over MAX_LINES lines**, counted as ``wc -l`` counts them (newlines).

Violations that exist and are someone else's change to remove are listed below, each with why
and what removes it. The test fails on a violation not in the lists and on a listed one that
no longer exists: the lists only shrink, and they stay true.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = {"cgamesh": ROOT / "cgamesh", "cgamesh_cli": ROOT / "cli"}  # import name -> folder
MAX_LINES = 600

# --- known violations: remove an entry when its violation goes (the test says when) ----------

# (a) cycles, each as the set of modules of one strongly connected component.
KNOWN_CYCLES: set[frozenset[str]] = {
    # batching (the options tables): manifest.py reads ``from cgamesh import __version__``,
    # and the package's ``__getattr__`` imports cgamesh.batching lazily for ``cgamesh.batch``
    frozenset({"cgamesh", "cgamesh.batching", "cgamesh.batching.engine", "cgamesh.batching.manifest"}),
}

# (b) (importer, private name used, as its full dotted name).
KNOWN_PRIVATE_USES: set[tuple[str, str]] = {
    # the batched passes' readers share the products' and flatness' internals and the ribbon
    # mesher's helpers
    ("cgamesh.meshing.batch_pass.circle_rows", "cgamesh.geometry.algebra.products._selection"),
    ("cgamesh.meshing.batch_pass.circle_rows", "cgamesh.geometry.algebra.products._single_blade_columns"),
    ("cgamesh.meshing.scene_batch.projection_scan", "cgamesh.geometry.flatness._REFINE_ROUNDS"),
    ("cgamesh.meshing.scene_batch.projection_scan", "cgamesh.geometry.flatness._REFINE_SAMPLES"),
}

# (c) (importer, forbidden module imported).
KNOWN_FORBIDDEN_IMPORTS: set[tuple[str, str]] = {
    # builds objects from the scene reader's specs; goes with the internal surface value that
    # replaces the specs past the reader (a later change of issue 21)
    ("cgamesh.geometry.construction", "cgamesh.inputs.scene"),
}

# (d) module -> why it is still over MAX_LINES.
KNOWN_LONG_MODULES: dict[str, str] = {}


# --- reading the source -----------------------------------------------------------------------

@dataclass(frozen=True)
class Use:
    """One dotted name a module imports or reads through an imported module."""

    importer: str
    name: str      # full dotted name: a module, or a module's attribute
    line: int


def _module_name(package: str, folder: Path, path: Path) -> str:
    parts = list(path.relative_to(folder).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join([package, *parts])


@cache
def modules() -> dict[str, Path]:
    """Every project module: dotted import name -> file."""
    found = {}
    for package, folder in PACKAGES.items():
        for path in sorted(folder.rglob("*.py")):
            if "__pycache__" not in path.parts:
                found[_module_name(package, folder, path)] = path
    return found


def _is_package(name: str) -> bool:
    return modules()[name].name == "__init__.py"


def _in_project(name: str) -> bool:
    return name.split(".")[0] in PACKAGES


def _absolute(importer: str, node: ast.ImportFrom) -> str:
    """The module a ``from ... import`` reads from, relative imports resolved."""
    if not node.level:
        return node.module or ""
    base = importer.split(".")
    if not _is_package(importer):
        base.pop()
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _target(name: str) -> str:
    """The module a dotted name lives in: itself when it is a module, else its longest module prefix."""
    parts = name.split(".")
    while parts and ".".join(parts) not in modules():
        parts.pop()
    return ".".join(parts)


@cache
def uses(importer: str) -> tuple[Use, ...]:
    """Everything ``importer`` imports (``a.b`` for ``import a.b``, ``a.b.c`` for ``from a.b
    import c``) and every attribute it reads through a project module it imported by name."""
    tree = ast.parse(modules()[importer].read_text(), str(modules()[importer]))
    found = []
    aliases = {}  # local name -> the project module it stands for
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                found.append(Use(importer, alias.name, node.lineno))
                if alias.asname:
                    aliases[alias.asname] = alias.name
                else:
                    aliases.setdefault(alias.name.split(".")[0], alias.name.split(".")[0])
        elif isinstance(node, ast.ImportFrom):
            source = _absolute(importer, node)
            for alias in node.names:
                name = f"{source}.{alias.name}"
                found.append(Use(importer, name, node.lineno))
                if name in modules():
                    aliases[alias.asname or alias.name] = name
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            chain = []
            value = node
            while isinstance(value, ast.Attribute):
                chain.append(value.attr)
                value = value.value
            if isinstance(value, ast.Name) and value.id in aliases:
                name = aliases[value.id]
                for attr in reversed(chain):  # down through modules to the first non-module attribute
                    name = f"{name}.{attr}"
                    if name not in modules():
                        break
                if name not in modules():
                    found.append(Use(importer, name, node.lineno))
    return tuple(use for use in found if _in_project(use.name))


def _inside(importer: str, owner: str) -> bool:
    return importer == owner or importer.startswith(owner + ".")


def _private(part: str) -> bool:
    return part.startswith("_") and not (part.startswith("__") and part.endswith("__"))


# --- the rules ---------------------------------------------------------------------------------

def import_graph() -> dict[str, set[str]]:
    graph = {name: set() for name in modules()}
    for importer in modules():
        for use in uses(importer):
            target = _target(use.name)
            if target and target != importer:
                graph[importer].add(target)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each as one cycle
    through it, from its first module in sorted order back to it."""
    index, low, stack, on_stack, components = {}, {}, [], set(), []

    def visit(v):  # recursion depth is bounded by the module count
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                components.append(set(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return [_cycle_through(graph, component) for component in components]


def _cycle_through(graph, component: set[str]) -> list[str]:
    """A shortest cycle from the component's first module back to itself (breadth first)."""
    start = min(component)
    came_from = {start: None}
    frontier = [start]
    while frontier:
        following = []
        for v in frontier:
            for w in sorted(graph[v] & component):
                if w == start:
                    path = [v]
                    while came_from[path[-1]] is not None:
                        path.append(came_from[path[-1]])
                    return [*reversed(path), start]
                if w not in came_from:
                    came_from[w] = v
                    following.append(w)
        frontier = following
    raise AssertionError(f"no cycle through {start}")


def private_uses() -> dict[tuple[str, str], int]:
    """(importer, private dotted name) -> line, for every use of a name private to another module."""
    found = {}
    for importer in modules():
        for use in uses(importer):
            parts = use.name.split(".")
            for k, part in enumerate(parts):
                owner = ".".join(parts[:k])
                if _private(part) and not _inside(importer, owner):
                    found.setdefault((importer, ".".join(parts[: k + 1])), use.line)
                    break
    return found


# (c) the packages whose modules must not import these packages' modules
FORBIDDEN = {"cgamesh.geometry": ("cgamesh.inputs",), "cgamesh.meshing": ("cgamesh.inputs",),
             "cgamesh.tracer": ("cgamesh.meshing",), "cgamesh": ("cgamesh_cli",)}


def forbidden_imports() -> dict[tuple[str, str], int]:
    found = {}
    for importer in modules():
        banned = [b for package, names in FORBIDDEN.items() if _inside(importer, package) for b in names]
        for use in uses(importer):
            if any(_inside(use.name, b) for b in banned):
                found.setdefault((importer, _target(use.name)), use.line)
    return found


def line_counts() -> dict[str, int]:
    return {name: path.read_bytes().count(b"\n") for name, path in modules().items()}


def _where(name: str, line: int | None = None) -> str:
    path = modules()[name].relative_to(ROOT)
    return f"{path}:{line}" if line else str(path)


# --- the tests ---------------------------------------------------------------------------------

def test_the_rules_read_every_module_and_every_import():
    assert "cgamesh" in modules() and "cgamesh_cli.main" in modules() and len(modules()) > 100
    graph = import_graph()
    assert "cgamesh.errors" in graph["cgamesh.api"]  # a module-level import
    assert "cgamesh.pipelines.centerline_tolerance" in graph["cgamesh.pipelines.centerlines"]  # inside a function
    assert "cgamesh.pipelines.scene" in graph["cgamesh_cli.build"]  # the command line's, by its installed name


def test_no_import_cycle():
    graph = import_graph()
    found = {frozenset(cycle): cycle for cycle in cycles(graph)}
    new = [" -> ".join(cycle) for key, cycle in found.items() if key not in KNOWN_CYCLES]
    gone = [sorted(key) for key in KNOWN_CYCLES if key not in found]
    assert not new, "import cycles (break them; see docs/architecture.md):\n  " + "\n  ".join(new)
    assert not gone, f"these listed cycles are gone: remove them from KNOWN_CYCLES: {gone}"


def test_no_use_of_another_modules_private_names():
    found = private_uses()
    new = [f"{_where(importer, line)}: {importer} uses {name}" for (importer, name), line in sorted(found.items())
           if (importer, name) not in KNOWN_PRIVATE_USES]
    gone = sorted(KNOWN_PRIVATE_USES - set(found))
    assert not new, "private names used outside their module (make them public where they belong):\n  " + \
        "\n  ".join(new)
    assert not gone, f"these listed private uses are gone: remove them from KNOWN_PRIVATE_USES: {gone}"


def test_no_stage_reaches_back_up():
    found = forbidden_imports()
    new = [f"{_where(importer, line)}: {importer} imports {name}" for (importer, name), line in sorted(found.items())
           if (importer, name) not in KNOWN_FORBIDDEN_IMPORTS]
    gone = sorted(KNOWN_FORBIDDEN_IMPORTS - set(found))
    assert not new, f"forbidden imports ({FORBIDDEN}):\n  " + "\n  ".join(new)
    assert not gone, f"these listed imports are gone: remove them from KNOWN_FORBIDDEN_IMPORTS: {gone}"


def test_no_module_over_the_line_limit():
    counts = line_counts()
    long = {name for name, count in counts.items() if count > MAX_LINES}
    new = [f"{_where(name)}: {counts[name]} lines" for name in sorted(long - set(KNOWN_LONG_MODULES))]
    gone = sorted(set(KNOWN_LONG_MODULES) - long)
    assert not new, f"modules over {MAX_LINES} lines (split them by concern):\n  " + "\n  ".join(new)
    assert not gone, f"these listed modules are within {MAX_LINES} lines: remove them from KNOWN_LONG_MODULES: {gone}"


# Public modules moved in issue 21, kept one release under their old names: old -> new.
MOVED_MODULES = {"cgamesh.pipeline": "cgamesh.pipelines.scene",
                 "cgamesh.centerline_pipeline": "cgamesh.pipelines.centerlines"}


def test_a_moved_public_module_is_its_new_module_under_the_old_name_and_warns():
    import subprocess
    import sys

    probe = """
import importlib, sys, warnings
old, new = sys.argv[1:]
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    module = importlib.import_module(old)
assert module is importlib.import_module(new), module
assert [w.category for w in caught] == [FutureWarning] and new in str(caught[0].message), caught
"""
    for old, new in MOVED_MODULES.items():
        subprocess.run([sys.executable, "-c", probe, old, new], check=True, timeout=120)
