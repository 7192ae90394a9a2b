"""The import graph of ``uasnav``: no cycles, and nothing below the CLI imports from it.

Every ``import`` / ``from … import`` statement of every module counts, including imports inside
functions (a lazy import still ties two modules together); only imports under
``if TYPE_CHECKING:`` are exempt, because they never run.
"""

from __future__ import annotations

import ast
from pathlib import Path

PKG_DIR = Path(__file__).resolve().parents[1] / "python" / "uasnav"


def _module_name(path: Path) -> str:
    rel = path.relative_to(PKG_DIR.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(path: Path, modules: set[str]) -> set[str]:
    """The uasnav modules that ``path`` imports at run time (resolved to known modules)."""
    name = _module_name(path)
    is_pkg = path.name == "__init__.py"
    package = name if is_pkg else name.rpartition(".")[0]
    found: set[str] = set()

    def resolve(target: str) -> str | None:
        # The longest known module that ``target`` names (``uasnav.io.read_log`` → ``uasnav.io``).
        while target:
            if target in modules:
                return target
            target = target.rpartition(".")[0]
        return None

    def visit(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child.test):
                for sub in child.orelse:
                    visit(sub)
                continue
            if isinstance(child, ast.Import):
                for alias in child.names:
                    if alias.name.startswith("uasnav"):
                        m = resolve(alias.name)
                        if m:
                            found.add(m)
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = package.split(".")
                    if child.level > 1:
                        base = base[: len(base) - (child.level - 1)]
                    mod = ".".join(base + ([child.module] if child.module else []))
                else:
                    mod = child.module or ""
                if not mod.startswith("uasnav"):
                    continue
                for alias in child.names:
                    m = resolve(f"{mod}.{alias.name}") or resolve(mod)
                    if m:
                        found.add(m)
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8"), filename=str(path)))
    found.discard(name)
    return found


def _graph() -> dict[str, set[str]]:
    files = sorted(PKG_DIR.rglob("*.py"))
    # the compiled extension is a module of its own (described by its stub), not the package face
    modules = {_module_name(f) for f in files} | {_module_name(f) for f in PKG_DIR.glob("_core.pyi")}
    return {_module_name(f): _imports(f, modules) for f in files}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan).

    A package's ``__init__`` re-exporting its submodules is an edge like any other: a
    submodule that imports its own package's face then closes a real circle.
    """
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def strong(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            strong(v)
    return out


def test_graph_sees_imports() -> None:
    """The walker finds the imports it must (guards against a test that cannot fail)."""
    g = _graph()
    assert "uasnav.errors" in g["uasnav.imu"]
    assert "uasnav.units" in g["uasnav.noise"]
    # A function-level import counts: AllanResult.identify imports noise lazily.
    assert "uasnav.noise" in g["uasnav.allan"]


def test_cycle_detector_finds_a_cycle() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_cycles() -> None:
    cycles = _cycles(_graph())
    assert not cycles, "import cycles inside uasnav: " + "; ".join(" ↔ ".join(c) for c in cycles)


#: The floors from the top: a module may import its own floor and the floors below, never above.
#: Everything not named here is the domain floor (numerics, formats, models).
FLOORS = ("uasnav.cli", "uasnav.report", "uasnav.experiments")


def _floor(mod: str) -> int:
    for i, top in enumerate(FLOORS):
        if mod == top or mod.startswith(top + "."):
            return i
    return len(FLOORS)


def test_no_upward_imports() -> None:
    """CLI → report → experiments → domain: nothing imports a floor above its own (so the
    report never imports the CLI, and no numerics module imports an experiment or the report)."""
    up = {
        m: sorted(d for d in deps if _floor(d) < _floor(m)) for m, deps in _graph().items() if m != "uasnav"
    }
    up = {m: d for m, d in up.items() if d}
    assert not up, f"upward imports: {up}"


def test_floor_rule_catches_an_upward_import() -> None:
    assert _floor("uasnav.cli.zupt") < _floor("uasnav.report") < _floor("uasnav.experiments.zupt")
    assert _floor("uasnav.experiments.thesis") < _floor("uasnav.zupt")


def test_experiments_do_not_render() -> None:
    """Experiments compute; only the report renders (no report, matplotlib or HTML imports)."""
    offenders = {}
    for f in sorted((PKG_DIR / "experiments").rglob("*.py")):
        tree = ast.parse(f.read_text(encoding="utf-8"))
        names = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module:
                names.add(node.module)
        bad = sorted(
            n for n in names if n.split(".")[0] in {"matplotlib", "html"} or n.startswith("uasnav.report")
        )
        if bad:
            offenders[f.name] = bad
    assert not offenders, offenders
