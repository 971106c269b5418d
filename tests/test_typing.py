"""Library users' type checkers see every public signature: each public function's and method's parameters and
return are annotated (PEP 484), and the package says so (PEP 561's ``py.typed``)."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "regrasp"
#: Every module but the compiled kernels (numba types their arguments; they are the fast paths, not the API).
MODULES = sorted(p for p in PACKAGE.rglob("*.py") if not p.name.startswith("_") and "kernels" not in p.parts)


def unannotated(path: Path) -> list[str]:
    """``module:line name(parameters)`` for each public function or method (``__init__`` and ``__call__``
    included) with a parameter or a return that has no annotation."""
    found = []

    def visit(body, owner: str | None) -> None:
        for node in body:
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                visit(node.body, node.name)
            elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                if node.name.startswith("_") and node.name not in ("__init__", "__call__"):
                    continue
                a = node.args
                params = a.posonlyargs + a.args + a.kwonlyargs + [p for p in (a.vararg, a.kwarg) if p is not None]
                missing = [p.arg for p in params if p.annotation is None and p.arg not in ("self", "cls")]
                if node.returns is None and node.name != "__init__":
                    missing.append("return")
                if missing:
                    found.append(f"{path.name}:{node.lineno} {owner + '.' if owner else ''}{node.name}"
                                 f"({', '.join(missing)})")

    visit(ast.parse(path.read_text()).body, None)
    return found


@pytest.mark.parametrize("path", MODULES, ids=[str(p.relative_to(PACKAGE)) for p in MODULES])
def test_every_public_signature_is_annotated(path):
    assert unannotated(path) == []


def test_the_package_is_marked_typed():
    assert (PACKAGE / "py.typed").is_file()
