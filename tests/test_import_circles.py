"""No import circle between the product's modules: a module imports down, never back up
(issue 19, item 8), within each package and between packages.

Every import counts, at module level or inside a function: a lazy import still ties the two
modules together (neither can be read, moved or loaded without the other). An import under
``if TYPE_CHECKING:`` does not: it is there for the type checker's annotations and never runs.
The product is the packages ``pyproject.toml`` installs; the graph is read from the source
with :mod:`ast`, nothing is imported.
"""

from __future__ import annotations

import ast
import tomllib
from collections import defaultdict
from pathlib import Path
from typing import NamedTuple

ROOT = Path(__file__).resolve().parents[1]


class Edge(NamedTuple):
    """``source`` imports ``target`` at ``line`` (``lazy``: inside a function)."""

    source: str
    target: str
    line: int
    lazy: bool


def product_packages(root: Path = ROOT) -> list[str]:
    """The top-level packages ``pyproject.toml`` installs (its ``packages.find`` include)."""
    with (root / "pyproject.toml").open("rb") as f:
        include = tomllib.load(f)["tool"]["setuptools"]["packages"]["find"]["include"]
    return [name for name in include if "." not in name and "*" not in name]


def modules_of(root: Path, packages: list[str]) -> dict[str, Path]:
    """Dotted module name -> its file, for every module of ``packages`` under ``root``."""
    found: dict[str, Path] = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            found[".".join(parts)] = path
    return found


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.Module) -> list[tuple[ast.Import | ast.ImportFrom, bool]]:
    """The imports that can run, each with whether it is inside a function."""
    out: list[tuple[ast.Import | ast.ImportFrom, bool]] = []

    def visit(node: ast.AST, lazy: bool) -> None:
        if isinstance(node, ast.Import | ast.ImportFrom):
            out.append((node, lazy))
        elif isinstance(node, ast.If) and _is_type_checking(node):
            for statement in node.orelse:  # the body is the type checker's only
                visit(statement, lazy)
        else:
            inner = lazy or isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
            for child in ast.iter_child_nodes(node):
                visit(child, inner)

    visit(tree, False)
    return out


def import_edges(modules: dict[str, Path]) -> list[Edge]:
    """Every import between two of ``modules`` that can run."""

    def resolve(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    edges: list[Edge] = []
    for source, path in modules.items():
        is_package = path.name == "__init__.py"
        for node, lazy in _imports(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                targets = [resolve(alias.name) for alias in node.names]
            else:
                base = node.module or ""
                if node.level:
                    here = source.split(".") if is_package else source.split(".")[:-1]
                    here = here[: len(here) - (node.level - 1)]
                    base = ".".join([*here, *([base] if base else [])])
                # ``from package import module`` imports the module; a name, the package
                targets = [resolve(f"{base}.{alias.name}") for alias in node.names]
            for target in {t for t in targets if t is not None and t != source}:
                edges.append(Edge(source, target, node.lineno, lazy))
    return edges


def circles(edges: list[Edge]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    graph: dict[str, set[str]] = defaultdict(set)
    for e in edges:
        graph[e.source].add(e.target)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                connect(w)
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
            connect(v)
    return sorted(found)


def describe(circle: list[str], edges: list[Edge]) -> str:
    members = set(circle)
    inside = sorted(e for e in edges if e.source in members and e.target in members)
    return "\n".join(
        [" <-> ".join(circle)]
        + [
            f"    {e.source} -> {e.target} (line {e.line}{', inside a function' if e.lazy else ''})"
            for e in inside
        ]
    )


def test_no_module_imports_back_up_its_own_imports() -> None:
    modules = modules_of(ROOT, product_packages())
    assert {"codec._frame", "planner._plan", "backend.commands.checks"} <= set(modules)
    edges = import_edges(modules)
    found = circles(edges)
    assert not found, "import circles (break them by moving the shared part down):\n" + (
        "\n".join(describe(c, edges) for c in found)
    )


def _write(root: Path, files: dict[str, str]) -> dict[str, Path]:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return modules_of(root, ["pkg"])


def test_a_lazy_or_relative_circle_is_found_and_a_type_only_one_is_not(tmp_path: Path) -> None:
    """Guards the test above against passing because the probe sees no circle at all."""
    modules = _write(
        tmp_path,
        {
            "pkg/__init__.py": "",
            "pkg/low.py": "def f():\n    from pkg.high import g\n",  # lazy, back up
            "pkg/high.py": "from . import low\n",
            "pkg/typed.py": (
                "TYPE_CHECKING = False\nif TYPE_CHECKING:\n    from pkg import low\n"
                "else:\n    import pkg.sub\n"
            ),
            "pkg/sub/__init__.py": "from ..typed import TYPE_CHECKING\n",
        },
    )
    edges = import_edges(modules)
    assert Edge("pkg.low", "pkg.high", 2, lazy=True) in edges
    assert Edge("pkg.high", "pkg.low", 1, lazy=False) in edges
    assert Edge("pkg.sub", "pkg.typed", 1, lazy=False) in edges
    assert [e for e in edges if e.source == "pkg.typed"] == [Edge("pkg.typed", "pkg.sub", 5, False)]
    assert circles(edges) == [["pkg.high", "pkg.low"], ["pkg.sub", "pkg.typed"]]
    assert "pkg.low -> pkg.high (line 2, inside a function)" in describe(circles(edges)[0], edges)
