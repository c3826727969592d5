"""The package's import graph, parsed from its source: imports point down the data flow
(scene -> raster -> shading -> pipelines -> metrics -> study -> figures -> cli), nothing
imports in a circle, and no module imports another module's private names.

Imports inside functions count: a lazy import that closes a circle is still a circle, only
hidden until the function runs."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "jaxrender"

# Rank of each top-level part of the package; a module may import modules of its own part or
# of lower rank. Plain helpers that know nothing of rendering sit at the bottom.
LAYERS = {
    "types": 0, "compaction": 0, "sorting": 0, "spawning": 0, "parallel": 0, "version": 0,
    "errors": 0, "catalog": 0, "parsing": 0, "memory_maps": 0, "fusion": 0,
    "scene": 1,
    "raster": 2,
    "shading": 3,
    "pipelines": 4,
    "metrics": 5,
    "timing": 5.5,  # times compiled pipeline programs
    "study": 6,
    "seeds": 6.5,  # the sources' published numbers beside study rows
    "figures": 7, "bench": 7,
    "cli": 8,
    "api": 9, "__init__": 9, "__main__": 9,
}


def module_files() -> dict[str, Path]:
    mods = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(parts)] = path
    return mods


MODULES = module_files()


def is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def imports_of(name: str, path: Path | None = None) -> list[tuple[str, str | None, int]]:
    """(module imported, name taken from it or None, line) for every import in ``name`` (or
    in the script ``path``), relative imports resolved; only imports of this package."""
    path = path or MODULES[name]
    package = name if name in MODULES and is_package(name) else name.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(a.name, None, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            for alias in node.names:
                child = f"{source}.{alias.name}"
                if child in MODULES:  # `from package import module`
                    found.append((child, None, node.lineno))
                else:
                    found.append((source, alias.name, node.lineno))
    return [(m, n, line) for m, n, line in found if m.split(".")[0] == "jaxrender"]


def layer(name: str) -> tuple[str, int]:
    parts = name.split(".")
    part = parts[1] if len(parts) > 1 else "__init__"
    if part not in LAYERS:
        raise AssertionError(f"{name}: top-level part {part!r} has no layer in LAYERS; "
                             f"place it in the data flow")
    return part, LAYERS[part]


def edges() -> dict[str, set[str]]:
    """Module -> modules it imports. A package's ``__init__`` importing its own submodules (to
    re-export or register them) is not an edge: it runs after they exist."""
    graph = {name: set() for name in MODULES}
    for name in MODULES:
        for target, _, _ in imports_of(name):
            if target == name or target not in MODULES:
                continue
            if is_package(name) and target.startswith(name + "."):
                continue
            graph[name].add(target)
    return graph


def test_imports_point_down_the_data_flow():
    wrong = []
    for name in MODULES:
        part, rank = layer(name)
        for target, _, line in imports_of(name):
            if target not in MODULES:
                continue
            target_part, target_rank = layer(target)
            # The bottom layer's helpers may use each other; other parts only lower ones.
            if target_part != part and target_rank >= rank and (rank > 0 or target_rank > 0):
                wrong.append(f"{MODULES[name].relative_to(PACKAGE.parent)}:{line} ({part}) "
                             f"imports {target} ({target_part})")
    assert not wrong, "imports against the data flow:\n" + "\n".join(sorted(set(wrong)))


def test_no_module_imports_its_own_package_namespace():
    # The package's __init__ imports its submodules, so a submodule taking a name from the
    # package namespace closes a circle (and sees a half-initialised package).
    wrong = []
    for name in MODULES:
        if name.endswith(".__main__"):  # runs after its package is imported
            continue
        for target, _, line in imports_of(name):
            if target != name and name.startswith(target + ".") and is_package(target):
                wrong.append(f"{MODULES[name].relative_to(PACKAGE.parent)}:{line} imports "
                             f"its ancestor package {target}")
    assert not wrong, "\n".join(wrong)


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}  # 1: on the current path, 2: finished
    path: list[str] = []

    def visit(node):
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            if nxt not in state:
                cycle = visit(nxt)
                if cycle:
                    return cycle
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            cycle = visit(node)
            if cycle:
                return cycle
    return None


def test_no_import_cycles():
    cycle = find_cycle(edges())
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def private_uses(name: str, path: Path | None = None) -> list[str]:
    """Private names of another module: imported by name, or read as ``module._name``."""
    found = []
    path = path or MODULES[name]
    rel = path.relative_to(PACKAGE.parent)
    module_aliases = {}
    imports = imports_of(name, path)
    home = name if name in MODULES and is_package(name) else name.rpartition(".")[0]
    for target, taken, line in imports:
        if target == name:
            continue
        if taken and taken.startswith("_") and not taken.startswith("__"):
            found.append(f"{rel}:{line} imports {target}.{taken}")
        leaf = target.rpartition(".")[2]
        if (leaf.startswith("_") and not leaf.startswith("__")
                and target.rpartition(".")[0] != home):
            found.append(f"{rel}:{line} imports the private module {target}")
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("jaxrender") and a.name != name:
                    module_aliases[a.asname or a.name] = a.name
        elif isinstance(node, ast.ImportFrom):
            for a in node.names:
                for target, _, _ in imports:
                    if target.endswith("." + a.name) and target in MODULES and target != name:
                        module_aliases[a.asname or a.name] = target
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                and node.value.id in module_aliases and node.attr.startswith("_")
                and not node.attr.startswith("__")):
            found.append(f"{rel}:{node.lineno} reads {module_aliases[node.value.id]}."
                         f"{node.attr}")
    return found


def test_no_private_names_across_modules():
    found = [use for name in MODULES for use in private_uses(name)]
    assert not found, "private names used across modules:\n" + "\n".join(sorted(found))


def test_benchmarks_use_public_names():
    scripts = sorted((PACKAGE.parent / "benchmarks").glob("*.py"))
    found = [use for path in scripts for use in private_uses(f"benchmarks.{path.stem}", path)]
    assert not found, "benchmarks using private names:\n" + "\n".join(sorted(found))


def test_no_product_module_is_named_like_a_test():
    named = [str(p.relative_to(PACKAGE.parent)) for p in PACKAGE.rglob("test*.py")]
    assert not named, f"test code inside the package: {named}"


# The checks themselves, on a made-up graph: a check that cannot fail proves nothing.
@pytest.mark.parametrize("graph, expect", [
    ({"a": {"b"}, "b": {"c"}, "c": set()}, None),
    ({"a": {"b"}, "b": {"c"}, "c": {"a"}}, ["a", "b", "c", "a"]),
    ({"a": {"a"}}, ["a", "a"]),
])
def test_find_cycle_finds_circles(graph, expect):
    assert find_cycle(graph) == expect
