"""The package's architecture rules (docs/architecture.md), checked on the source.

Every ``import`` statement counts, including those inside functions and under
``TYPE_CHECKING`` (an import hidden in a function is still a dependency).
Dynamic imports (``importlib.import_module``) are allowed only for the CLI's
command dispatch and the deprecation shims, which list them explicitly.
"""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "pendulab"

#: Lowest first. A module may import its own layer and the layers below it, never one above.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("_checks", "_version", "_io", "_lazy"),
    ("_inputs",),
    ("_journal",),
    ("model",),
    ("analysis", "native"),
    ("integrate",),
    ("scene", "scenes"),
    ("ensemble",),
    ("identify",),
    ("control",),
    ("evaluate",),
    ("viz",),
    ("fmu",),
    ("cosim",),
    ("gym",),
    ("bench",),
    ("commands",),
    ("cli", "_aliases"),
    ("__main__", "_entry"),
)
LAYER_OF = {name: i for i, names in enumerate(LAYERS) for name in names}


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in PKG.rglob("*.py")}


def _resolve(module: str, is_pkg: bool, level: int, target: str | None) -> str:
    base = module.split(".")
    if not is_pkg:
        base = base[:-1]
    if level > 1:
        base = base[: len(base) - (level - 1)]
    return ".".join(base + ([target] if target else []))


def _imports(modules: dict[str, Path]) -> list[tuple[str, str, list[str], int]]:
    """(importer, imported module, imported names, line) for every import statement in the package."""
    out = []
    for name, path in modules.items():
        is_pkg = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.split(".")[0] == "pendulab":
                        out.append((name, alias.name, [], node.lineno))
            elif isinstance(node, ast.ImportFrom):
                target = _resolve(name, is_pkg, node.level, node.module) if node.level else (node.module or "")
                if target.split(".")[0] != "pendulab":
                    continue
                names = [a.name for a in node.names]
                # "from . import x" imports the submodule x.
                subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in modules]
                rest = [n for n in names if f"{target}.{n}" not in modules]
                if rest or not subs:
                    out.append((name, target, rest, node.lineno))
                out.extend((name, s, [], node.lineno) for s in subs)
    return out


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for src, dst, _names, _line in _imports(modules):
        # Importing pendulab.a.b runs pendulab.a's __init__ too: count the deepest existing module.
        while dst not in modules and "." in dst:
            dst = dst.rsplit(".", 1)[0]
        if dst != src and dst in modules:
            graph[src].add(dst)
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    sys.setrecursionlimit(10000)

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
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

    for v in graph:
        if v not in index:
            visit(v)
    return out


def _layer(module: str) -> int | None:
    parts = module.split(".")
    return LAYER_OF.get(parts[1]) if len(parts) > 1 else None


def test_no_import_cycles_counting_imports_inside_functions():
    graph = _graph()
    # Package __init__ files re-export their children: an edge child -> own package __init__ is not allowed
    # either (it would make the package import order-dependent), so nothing is exempt.
    assert _cycles(graph) == []


def test_every_module_has_a_layer():
    missing = sorted(m for m in _modules() if m != "pendulab" and _layer(m) is None)
    assert missing == [], f"add these to LAYERS and docs/architecture.md: {missing}"


def test_lower_layers_never_import_higher_ones():
    bad = []
    for src, dst, _names, line in _imports(_modules()):
        ls, ld = _layer(src), _layer(dst)
        if ls is not None and ld is not None and ld > ls:
            bad.append(f"{src}:{line} imports {dst}")
    assert bad == []


def test_no_private_names_imported_across_subpackages():
    bad = []
    for src, dst, names, line in _imports(_modules()):
        if dst.split(".")[:2] == src.split(".")[:2]:
            continue
        private = [n for n in names if n.startswith("_") and not n.startswith("__")]
        private += [p for p in dst.split(".")[2:] if p.startswith("_") and not p.startswith("__")]
        if private:
            bad.append(f"{src}:{line} imports {private} from {dst}")
    assert bad == []


def test_import_linter_contracts_hold():
    exe = shutil.which("lint-imports")
    if exe is None:
        pytest.skip("import-linter is not installed (it is in the test extra: pip install -e '.[test]')")
    proc = subprocess.run([exe, "--no-cache"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
