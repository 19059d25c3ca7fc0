"""The house's shape, checked from the code itself (issue 34): no import circle among the modules
of `core/` and `adapters/` (imports inside functions count; those under `TYPE_CHECKING` do not),
and no function over 60 lines. Run alone: `python -m pytest tests/unit/test_structure.py -v`."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LONGEST = 60


def _modules() -> dict[str, Path]:
    out = {}
    for f in sorted([*ROOT.glob("core/**/*.py"), *ROOT.glob("adapters/**/*.py")]):
        parts = f.relative_to(ROOT).with_suffix("").parts
        keep = parts[:-1] if parts[-1] == "__init__" else parts
        out[".".join(("brdfremap", *keep))] = f
    return out


def _type_only(tree: ast.Module) -> set[int]:
    """Ids of the import nodes under `if TYPE_CHECKING:` (annotations only, never run)."""
    hidden = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            hidden |= {id(n) for stmt in node.body for n in ast.walk(stmt)}
    return hidden


def _targets(mods: dict[str, Path], name: str, node: ast.AST) -> list[str]:
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name in mods]
    package = name if mods[name].name == "__init__.py" else name.rsplit(".", 1)[0]
    base = package
    for _ in range(node.level - 1):
        base = base.rsplit(".", 1)[0]
    target = (base + ("." + node.module if node.module else "")) if node.level else (node.module or "")
    subs = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in mods]
    return [t for t in (subs if len(subs) == len(node.names) else [target, *subs]) if t in mods and t != name]


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    graph: dict[str, set[str]] = {}
    for name, path in mods.items():
        tree = ast.parse(path.read_text())
        hidden = _type_only(tree)
        graph[name] = {t for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom))
                       and id(node) not in hidden for t in _targets(mods, name, node)}
    return graph


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iteratively)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    found.append(sorted(comp))
    return found


def test_no_import_circle_in_core_or_adapters():
    graph = _graph()
    assert "brdfremap.core.library.entries" in graph["brdfremap.core.library.yaml_reader"]  # the graph sees imports
    assert not _circles(graph)


def test_the_circle_check_finds_a_circle():
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_function_over_sixty_lines():
    long = [f"{path.relative_to(ROOT)}:{node.lineno} {node.name} ({node.end_lineno - node.lineno + 1} lines)"
            for path in _modules().values() for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
            and node.end_lineno - node.lineno + 1 > LONGEST]
    assert not long, long


ROOMS = (
    ("data", ("data",)),
    ("plugin host", ("", "host", "protocol", "testing")),
    ("engine", ("engine",)),
    ("job", ("job",)),
    ("images", ("images",)),
    ("run", ("run",)),
    ("experiments", ("experiments",)),
    ("tables", ("tables",)),
    ("textured sources", ("textured",)),
    ("library", ("library",)),
    ("cli", ("cli",)),
)
"""The rooms of docs/architecture.md, lowest first, by the folder of `core/` (the package itself and
its two shims, `protocol` and `testing`, where plugin authors import from, are the plugin host's):
a module imports from its own room and those below."""
UPWARD: dict[tuple[str, str], str] = {}
"""The imports that go up, each with its reason."""


def _room(module: str) -> int:
    parts = module.split(".")
    if parts[1] == "adapters":
        return len(ROOMS)
    first = parts[2] if len(parts) > 2 else ""
    room = next((i for i, (_, names) in enumerate(ROOMS) if first in names), None)
    assert room is not None, f"{module}: in no room of ROOMS (a module of core/ lives in its room's folder)"
    return room


def test_core_imports_only_downward_and_no_adapter_imports_the_engine():
    graph = _graph()
    upward = sorted((a, b) for a, outs in graph.items() for b in outs
                    if _room(b) > _room(a) and (a, b) not in UPWARD)
    assert not upward, [f"{a} ({ROOMS[_room(a)][0]}) -> {b} ({ROOMS[_room(b)][0]})" for a, b in upward]
    engine = sorted((a, b) for a, outs in graph.items() for b in outs
                    if a.startswith("brdfremap.adapters") and b.startswith("brdfremap.core.engine"))
    assert not engine, engine
