"""The package's layout holds (issue 23): no import cycle between modules, no access to another module's private
names, modules and classes of a readable size, and a rollout built from a few values.

Read from the source with ``ast``, so these tests import nothing of the package but what they check by name.
"""

from __future__ import annotations

import ast
import inspect
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "regrasp"

#: The largest module [lines] and class [methods] the layout allows.
MAX_MODULE_LINES = 500
MAX_CLASS_METHODS = 25

#: The private names a test may read, each with why: only tests of a compiled kernel against its reference path
#: (they reach into the internals the two paths share), as (test file, name).
KERNEL_TEST_EXCEPTIONS: dict[tuple[str, str], str] = {}

#: Private attributes of the standard library that are its documented API (namedtuple's).
PUBLIC_UNDERSCORED = {"_fields", "_replace", "_asdict", "_make", "_field_defaults"}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _imported(module: str, path: Path, node: ast.ImportFrom, modules: dict[str, Path]) -> set[str]:
    """The package's modules a ``from ... import ...`` names (a submodule when a name is one, else the module)."""
    if node.level:
        base = module.split(".")
        if path.name != "__init__.py":
            base = base[:-1]
        base = base[:len(base) - node.level + 1]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    if not target.startswith("regrasp"):
        return set()
    out = set()
    for alias in node.names:
        sub = f"{target}.{alias.name}"
        out.add(sub if sub in modules else target)
    return {m for m in out if m in modules}


def import_graph() -> dict[str, set[str]]:
    """Module -> the package's modules it imports, anywhere in it (at the top, in functions, for type checkers)."""
    modules = _modules()
    graph: dict[str, set[str]] = defaultdict(set)
    for module, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                graph[module] |= _imported(module, path, node, modules) - {module}
            elif isinstance(node, ast.Import):
                graph[module] |= {a.name for a in node.names if a.name in modules and a.name != module}
        graph.setdefault(module, set())
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The graph's strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
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
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_cycle_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_module_imports_itself_back():
    found = cycles(import_graph())
    assert found == [], "import cycles: " + "; ".join(" <-> ".join(c) for c in found)


def _own_private_names(tree: ast.AST) -> set[str]:
    """The underscored names a module defines itself: functions, classes, variables, attributes it assigns,
    parameters."""
    own = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            own.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            own.add(node.id)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            own.add(node.attr)
        elif isinstance(node, ast.arg):
            own.add(node.arg)
    return {n for n in own if n.startswith("_")}


def private_accesses(path: Path) -> list[tuple[int, str]]:
    """(line, what) for each access to another module's private name: ``from m import _name``, or ``x._name`` where
    this module does not define ``_name`` (another module's class, or a library's)."""
    tree = ast.parse(path.read_text())
    own = _own_private_names(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            found += [(node.lineno, f"from {node.module} import {a.name}") for a in node.names
                      if a.name.startswith("_") and not a.name.startswith("__")]
        elif isinstance(node, ast.Attribute):
            name = node.attr
            if name.startswith("_") and not name.startswith("__") and name not in own \
                    and name not in PUBLIC_UNDERSCORED:
                found.append((node.lineno, ast.unparse(node)))
    return found


def test_the_private_access_finder_finds_one(tmp_path):
    path = tmp_path / "m.py"
    path.write_text("from a import _x\nclass C:\n    def f(self, o):\n        self._mine = o._theirs\n"
                    "        return self._mine\n")
    assert private_accesses(path) == [(1, "from a import _x"), (4, "o._theirs")]


CODE = sorted([*PACKAGE.rglob("*.py"), *(ROOT / "tests").rglob("*.py"), *(ROOT / "examples").glob("*.py"),
               *(ROOT / "benchmarks").glob("*.py")])


@pytest.mark.parametrize("path", CODE, ids=[str(p.relative_to(ROOT)) for p in CODE])
def test_no_module_reaches_into_another_modules_private_names(path):
    where = str(path.relative_to(ROOT))
    found = [(line, what) for line, what in private_accesses(path)
             if (where, what.rsplit(".", 1)[-1].split(" ")[-1]) not in KERNEL_TEST_EXCEPTIONS]
    assert found == []


def test_every_listed_exception_is_a_kernel_test_and_still_needed():
    for (where, name), why in KERNEL_TEST_EXCEPTIONS.items():
        assert where.startswith("tests/kernels/") and why
        assert any(what.endswith(name) for _, what in private_accesses(ROOT / where)), (where, name)


MODULES = sorted(PACKAGE.rglob("*.py"))


@pytest.mark.parametrize("path", MODULES, ids=[str(p.relative_to(PACKAGE)) for p in MODULES])
def test_modules_and_classes_are_of_a_readable_size(path):
    text = path.read_text()
    assert text.count("\n") <= MAX_MODULE_LINES
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ClassDef):
            methods = [b for b in node.body if isinstance(b, (ast.FunctionDef, ast.AsyncFunctionDef))]
            assert len(methods) <= MAX_CLASS_METHODS, f"{node.name}: {len(methods)} methods"


def test_a_rollout_is_built_from_a_few_values():
    from regrasp import build_rollout

    assert len(inspect.signature(build_rollout).parameters) <= 10
