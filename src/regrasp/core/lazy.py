"""A package's public names, each imported from its module on first use (PEP 562).

A package ``__init__`` lists its public names once, as the imports of its ``if TYPE_CHECKING:`` block (what type
checkers and IDEs read), and ends with ``__getattr__, __dir__, __all__ = lazy_exports(__name__)``: at run time
nothing is imported until a name is used, so ``import regrasp`` and ``regrasp --help`` load neither Pinocchio,
coal, scipy, rerun nor numba.
"""

from __future__ import annotations

import ast
import importlib
import sys
from collections.abc import Callable

__all__ = ["lazy_exports"]


def lazy_exports(package: str) -> tuple[Callable[[str], object], Callable[[], list[str]], list[str]]:
    """``package``'s ``__getattr__``, ``__dir__`` and ``__all__``: the names its ``if TYPE_CHECKING:`` block
    imports (relative imports only), each loaded from its module on first use and kept."""
    module = sys.modules[package]
    source = module.__spec__.loader.get_source(package)  # type: ignore[union-attr]
    sources: dict[str, tuple[str, str]] = {}
    for node in ast.parse(source).body:
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            for statement in node.body:
                if isinstance(statement, ast.ImportFrom) and statement.level > 0:
                    where = "." * statement.level + (statement.module or "")
                    for alias in statement.names:
                        sources[alias.asname or alias.name] = (where, alias.name)

    def __getattr__(name: str) -> object:
        try:
            where, attribute = sources[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        value = getattr(importlib.import_module(where, package), attribute)
        setattr(module, name, value)  # (the next lookup is a plain attribute)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(module)) | set(sources))

    return __getattr__, __dir__, sorted(sources)
