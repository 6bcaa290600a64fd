"""Two layer rules of docs/architecture.md, read from the sources with ``ast``.

- no import cycle between modules of lcpbench, counting the imports inside
  functions and under ``TYPE_CHECKING`` (import-linter, in tests/test_house.py,
  sees the cycles between layers only, and not every import inside a function);
- no private name (``_name``, not a dunder) imported from another module of
  lcpbench: a name another module needs is public where it is defined, or lives
  in the module that owns it. Importing a private *module* (``cli/_common.py``)
  within its package is allowed; a private alias (``import x as _x``) too;
- the energy minimisation, the tests' oracle (``reference/energy.py``), shares
  only the chain's kinematics, energy and walls with the model: no contact step,
  outer loop, judge or back-end, not through an import inside a function nor
  through a kernel loaded by name.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "lcpbench"


def _name(path: Path) -> str:
    parts = ("lcpbench", *path.relative_to(SRC).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_name(p): p for p in sorted(SRC.rglob("*.py"))}
PACKAGES = {_name(p) for p in SRC.rglob("__init__.py")}


def _absolute(module: str, level: int, target: str | None) -> str:
    """The absolute name of ``from <level dots><target> import ...`` in ``module``."""
    if level == 0:
        return target or ""
    base = module.split(".") if module in PACKAGES else module.split(".")[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([target] if target else []))


def _imports(module: str) -> list[tuple[str, str | None, int]]:
    """(imported module, name taken from it or None, line) for every import of a module
    of lcpbench in ``module``, at any depth (functions, classes, ``if`` blocks)."""
    found = []
    for node in ast.walk(ast.parse(MODULES[module].read_text())):
        if isinstance(node, ast.Import):
            for alias in node.names:
                target = alias.name
                while target and target not in MODULES:
                    target = target.rpartition(".")[0]
                if target:
                    found.append((target, None, node.lineno))
        elif isinstance(node, ast.ImportFrom):
            source = _absolute(module, node.level, node.module)
            if source not in MODULES:
                continue
            for alias in node.names:
                sub = f"{source}.{alias.name}"
                found.append((sub, None, node.lineno) if sub in MODULES
                             else (source, alias.name, node.lineno))
    return found


def import_graph() -> dict[str, set[str]]:
    """module -> the modules of lcpbench it imports (itself left out)."""
    return {m: {t for t, _, _ in _imports(m)} - {m} for m in MODULES}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            part = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                part.append(w)
                if w == v:
                    break
            if len(part) > 1:
                found.append(sorted(part))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def private_imports() -> list[str]:
    """``module:line imports _name from other`` for every private name imported across
    modules of lcpbench."""
    return [f"{m}:{line} imports {name} from {source}"
            for m in MODULES for source, name, line in _imports(m)
            if name is not None and source != m and name.startswith("_")
            and not name.startswith("__")]


def test_the_checker_sees_imports_inside_functions_and_relative_ones():
    graph = import_graph()
    # compiled._drive imports large_driver inside the function
    assert "lcpbench.model.large_driver" in graph["lcpbench.model.compiled"]
    assert "lcpbench.model.outer" in graph["lcpbench.model.compiled"]  # from .outer import
    assert "lcpbench.solvers.base" in graph["lcpbench.model.outer"]  # from ..solvers.base
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_cycle_between_modules():
    assert cycles(import_graph()) == []


def test_no_private_name_is_imported_from_another_module():
    assert private_imports() == []


def thresholds_defined_again() -> list[str]:
    """``module:line`` for every module-level assignment, outside ``thresholds.py``, of a
    name that ``lcpbench.thresholds`` defines: a threshold that kernels and Python both
    read is written once (a second copy could drift from the first unseen). The machine
    epsilon ``EPS`` is a fact of the doubles, not a threshold: modules may name it."""
    own = SRC / "thresholds.py"
    names = {t.id for node in ast.parse(own.read_text()).body if isinstance(node, ast.Assign)
             for t in ast.walk(node) if isinstance(t, ast.Name)} - {"EPS"}
    found = []
    for module, path in MODULES.items():
        if path == own:
            continue
        for node in ast.parse(path.read_text()).body:
            targets = node.targets if isinstance(node, ast.Assign) else (
                [node.target] if isinstance(node, ast.AnnAssign) else [])
            for t in targets:
                hit = {n.id for n in ast.walk(t) if isinstance(n, ast.Name)} & names
                found += [f"{module}:{node.lineno} defines {h}" for h in sorted(hit)]
    return found


def test_the_thresholds_are_defined_once():
    assert thresholds_defined_again() == []


#: what the energy oracle may share with the model: the chain's kinematics and exact
#: energy (and the elastic walls' springs in it), the walls' heights at x
ORACLE_SHARES = {"lcpbench.model.chain", "lcpbench.model.elastic", "lcpbench.model.profile"}
ORACLE_KERNELS = {"lcpbench.model.chain_kernel", "lcpbench.model.wall_kernel",
                  "lcpbench.problems.table_kernel"}


def reached(graph: dict[str, set[str]], roots: list[str]) -> set[str]:
    """Every module of lcpbench that ``roots`` import, directly or not."""
    seen: set[str] = set()
    todo = list(roots)
    while todo:
        m = todo.pop()
        if m not in seen:
            seen.add(m)
            todo += sorted(graph.get(m, ()))
    return seen


def test_the_energy_oracle_reaches_only_the_chain_and_its_walls():
    graph = import_graph()
    assert reached({"a": {"b"}, "b": {"c"}, "d": {"a"}}, ["a"]) == {"a", "b", "c"}
    seen = reached(graph, ["lcpbench.reference.energy", "lcpbench.reference.energy_profile"])
    model = {m for m in seen if m.startswith(("lcpbench.model.", "lcpbench.solvers"))}
    assert model <= ORACLE_SHARES, sorted(model - ORACLE_SHARES)
    loaded = {name for m in seen
              for name in re.findall(r'kernel_module\(\s*"([^"]+)"', MODULES[m].read_text())}
    assert loaded <= ORACLE_KERNELS, sorted(loaded - ORACLE_KERNELS)
