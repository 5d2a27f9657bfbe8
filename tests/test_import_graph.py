"""No two simgrip modules import each other, however indirectly; no source file is over 600 lines (issue 21).

The graph is read from the source with :mod:`ast`, nothing is imported.  Its
nodes are the modules of ``simgrip/``, ``envs/`` and ``models/`` (shipped as
``simgrip.envs``, ``simgrip.models``); an edge ``a -> b`` is any ``import`` or ``from ... import``
statement in ``a`` that names ``b`` -- at module level, inside a function or
method, and under ``if TYPE_CHECKING:`` alike.  Why the lazy ones count: an
import moved into a function only defers the circle to the first call; the
two modules still need each other and neither can be read, tested or moved
without the other, which is what the design rule (data flows one way:
parameters -> scene -> settle -> state -> comparison) forbids.  How a
statement resolves: ``import a.b.c`` and ``from a.b import c`` name ``a.b.c``
when that is a module, else the nearest package or module above it
(``from a.b import name``: ``a.b``); relative imports are resolved against
the importing module.  The implicit import of the parent packages that Python
runs before a submodule is not an edge (``from simgrip.settle.state import X``
depends on ``state``, not on everything ``simgrip/settle/__init__.py``
re-exports).  ``importlib.import_module`` with a literal name is counted too.

A circle is a strongly connected component of more than one module
(Tarjan's algorithm, iterative: no recursion limit on a deep graph).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Source trees and the package name each is installed as (pyproject's package-dir).
TREES = {"simgrip": "simgrip", "envs": "simgrip.envs", "models": "simgrip.models"}
#: The issue's size limit: no file over this many lines.
MAX_LINES = 600


def modules() -> dict[str, tuple[Path, bool]]:
    """Module name -> (path, is a package's ``__init__``) for every ``.py`` file of :data:`TREES`."""
    out = {}
    for tree, name in TREES.items():
        for path in sorted((ROOT / tree).rglob("*.py")):
            parts = list(path.relative_to(ROOT / tree).with_suffix("").parts)
            package = parts[-1] == "__init__"
            out[".".join([name] + (parts[:-1] if package else parts))] = (path, package)
    return out


def _known(name: str, mods) -> str | None:
    """``name`` if it is a module of the tree, else the nearest module or package above it (None: outside)."""
    while name and name not in mods:
        name = name.rpartition(".")[0]
    return name or None


def imported(module: str, package: bool, node: ast.AST, mods) -> list[str]:
    """The tree's modules one import statement (or ``importlib.import_module("literal")`` call) names."""
    if isinstance(node, ast.Import):
        return [t for t in (_known(a.name, mods) for a in node.names) if t]
    if isinstance(node, ast.ImportFrom):
        if node.level:
            base = module.split(".")[: None if package else -1]
            base = base[: len(base) - (node.level - 1)]
            base_name = ".".join(base + ([node.module] if node.module else []))
        else:
            base_name = node.module
        names = [f"{base_name}.{a.name}" for a in node.names]
        return [t for t in (n if n in mods else _known(base_name, mods) for n in names) if t]
    if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "import_module"
            and node.args and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)):
        target = _known(node.args[0].value, mods)
        return [target] if target else []
    return []


def import_graph() -> dict[str, set[str]]:
    """Module -> the tree's modules it imports anywhere in its source (itself left out)."""
    mods = modules()
    graph = {m: set() for m in mods}
    for module, (path, package) in mods.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            graph[module].update(t for t in imported(module, package, node, mods) if t != module)
    return graph


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components of ``graph``, iteratively; each sorted."""
    index, low, stack, on_stack, comps = {}, {}, [], set(), []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        work = [(root, iter(sorted(graph[root])))]
        while work:
            v, successors = work[-1]
            for w in successors:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    comps.append(sorted(comp))
    return comps


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    """The tree's import graph, read once for this file's tests (parsing every module: 1-3 s)."""
    return import_graph()


def test_the_checker_finds_a_circle_and_not_a_chain():
    """The check can fail: a three-module circle is one component, a chain is three of one."""
    circle = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert sorted(map(tuple, strongly_connected(circle))) == [("a", "b", "c"), ("d",)]
    chain = {"a": {"b"}, "b": {"c"}, "c": set()}
    assert all(len(c) == 1 for c in strongly_connected(chain))


def test_lazy_and_relative_imports_are_edges():
    """An import inside a function and a relative import name their module (what the graph counts)."""
    mods = {"p": (Path("p/__init__.py"), True), "p.a": (Path("p/a.py"), False), "p.b": (Path("p/b.py"), False)}
    tree = ast.parse("def f():\n    from p import b\nfrom . import b\nfrom .b import x\nimport p.b.c\n")
    found = [t for node in ast.walk(tree) for t in imported("p.a", False, node, mods)]
    assert found == ["p.b"] * 4


def test_graph_sees_the_whole_tree(graph):
    assert "simgrip.gripper.settle" in graph and "simgrip.envs.pick" in graph
    assert "simgrip.gripper.scene" in graph["simgrip.gripper.settle"]


def test_no_import_circles(graph):
    """No strongly connected component of more than one module: no modules import each other."""
    circles = [c for c in strongly_connected(graph) if len(c) > 1]
    lines = [" <-> ".join(c) + "\n    edges: " + ", ".join(f"{a} -> {b}" for a in c for b in sorted(graph[a]) if b in c)
             for c in circles]
    assert not circles, "import circles:\n" + "\n".join(lines)


@pytest.mark.parametrize("tree", ["simgrip", "envs", "tests", "examples"])
def test_no_file_over_600_lines(tree):
    long = {str(p.relative_to(ROOT)): n for p in sorted((ROOT / tree).rglob("*.py"))
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert not long, f"files over {MAX_LINES} lines: {long}"


#: simgrip.gripper's modules in the order of its docstring's table: parameters -> scene -> settle -> state ->
#: comparison; the first six build the scene.
GRIPPER_ORDER = ("placement", "model", "cradle", "scene", "scene_symmetry", "reuse", "state", "rest_depth", "start",
                 "dynamics", "stability", "full", "symmetry", "settle", "simulate", "compare")
GRIPPER_SCENE = GRIPPER_ORDER[:6]


def test_the_gripper_package_flows_one_way(graph):
    """Each module of simgrip.gripper imports only those before it in its table (so none imports its package
    back), and the scene modules import no settle module (simgrip.settle or the gripper's own)."""
    package = "simgrip.gripper."
    listed = {m[len(package):] for m in graph if m.startswith(package)}
    assert listed == set(GRIPPER_ORDER), "simgrip/gripper/__init__.py's table and GRIPPER_ORDER list every module"
    for i, name in enumerate(GRIPPER_ORDER):
        inside = {t[len(package):] for t in graph[package + name] if t.startswith(package)}
        later = sorted(inside - set(GRIPPER_ORDER[:i]))
        assert not later, f"simgrip.gripper.{name} imports {later}, listed after it"
        assert "simgrip.gripper" not in graph[package + name], f"simgrip.gripper.{name} imports its package"
    for name in GRIPPER_SCENE:
        settle = sorted(t for t in graph[package + name] if t == "simgrip.settle" or t.startswith("simgrip.settle."))
        assert not settle, f"scene module simgrip.gripper.{name} imports {settle}"


#: Packages (or modules) below -> what they must never import: the references know no MuJoCo, the scene no
#: solver, the settle no gripper or comparison; no physics imports the harness, the figures, the sweeps, the
#: environments or the command line (docs/layout.md).
_COMPARE = ("simgrip.compare", "simgrip.compare_full", "simgrip.settled", "simgrip.modes")
_TOOLS = ("simgrip.harness", "simgrip.figures", "simgrip.sweep", "simgrip.envs", "simgrip.cli")
LAYERS = {
    "simgrip.reference": ("simgrip.sim", "simgrip.settle", "simgrip.gripper") + _COMPARE + _TOOLS,
    "simgrip.sim": ("simgrip.settle", "simgrip.gripper") + _COMPARE + _TOOLS,
    "simgrip.settle": ("simgrip.gripper",) + _COMPARE + _TOOLS,
    "simgrip.gripper": ("simgrip.modes",) + _TOOLS,
    "simgrip.compare": _TOOLS,
    "simgrip.settled": _TOOLS,
    "simgrip.modes": _TOOLS,
}


def _within(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def test_the_layers_import_only_downwards(graph):
    wrong = [f"{a} -> {b}" for low, high in LAYERS.items() for a in sorted(graph) if _within(a, low)
             for b in sorted(graph[a]) if any(_within(b, h) for h in high)]
    assert not wrong, "imports against the flow (parameters -> scene -> settle -> state -> comparison):\n" + \
        "\n".join(wrong)
