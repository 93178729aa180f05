"""The house rules, enforced: imports go one way and nothing imports the CLI.

Every ``import`` in ``dam/`` and ``baselines/`` is parsed, function-local ones included
(a cycle hidden inside a function is still a cycle).
"""

import ast
from pathlib import Path

import pytest

import dam

ROOT = Path(dam.__file__).resolve().parent.parent

# A module may import from its own rank or lower (README, "Architecture").
RANKS = {
    "dam._version": 0,
    "dam._lazy": 0,
    "dam._compat": 0,
    "dam.corpus": 0,
    "dam.base": 1,
    "dam._params": 1,
    "dam.modelfile": 1,
    "dam.registry": 1,
    "dam.plotting": 1,
    "dam.progress": 1,
    "dam.model": 2,
    "dam.datasets": 3,
    "dam.crossmap": 3,
    "dam.speech": 3,
    "dam.export": 4,
    "dam.evaluation": 4,
    "dam.evaluation.metrics": 1,  # scores arrays and duck-typed models; Synthesizer.score uses it
    "dam.testing": 5,
    "dam.cli": 6,
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path) -> list[tuple[int, str]]:
    """``(line, imported module)`` for every import in ``path``, relative ones resolved."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    me = _module_name(path)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module
            submodules = [f"{mod}.{a.name}" for a in node.names if _is_module(f"{mod}.{a.name}")]
            # `from dam.corpus import io` imports the module dam.corpus.io (and runs dam.corpus's
            # __init__, which is lazy); `from dam import x` of a non-module is the package root
            if len(submodules) < len(node.names):
                out.append((node.lineno, mod))
            out += [(node.lineno, m) for m in submodules]
    return out


def _is_module(name: str) -> bool:
    p = ROOT.joinpath(*name.split("."))
    return p.with_suffix(".py").exists() or (p / "__init__.py").exists()


def _rank(module: str) -> int | None:
    """The rank of the longest prefix of ``module`` in RANKS."""
    matches = [p for p in RANKS if module == p or module.startswith(p + ".")]
    return RANKS[max(matches, key=len)] if matches else None


SOURCES = sorted(p for d in ("dam", "baselines") for p in (ROOT / d).rglob("*.py") if p.is_file())


def test_every_dam_module_has_a_rank():
    missing = [
        _module_name(p) for p in SOURCES if _module_name(p).startswith("dam.") and _rank(_module_name(p)) is None
    ]
    assert not missing, f"add these to RANKS (and the README's architecture section): {missing}"


@pytest.mark.parametrize(
    "path", [p for p in SOURCES if _module_name(p).startswith("dam.")], ids=lambda p: _module_name(p)
)
def test_dam_imports_go_down(path):
    me = _module_name(path)
    bad = []
    for line, mod in _imports(path):
        if mod.startswith("baselines"):
            bad.append(f"line {line}: {mod} (dam never imports baselines; register them by entry point)")
            continue
        if not (mod == "dam" or mod.startswith("dam.")):
            continue
        target = _rank(mod)
        if mod == "dam" and me != "dam":
            bad.append(f"line {line}: imports the package root `dam` (import from the module that defines it)")
        elif target is not None and target > _rank(me):
            bad.append(f"line {line}: {mod} (rank {target}) from rank {_rank(me)}")
    assert not bad, f"{me} imports upward:\n" + "\n".join(bad)


@pytest.mark.parametrize(
    "path", [p for p in SOURCES if _module_name(p).startswith("baselines")], ids=lambda p: _module_name(p)
)
def test_baselines_use_the_public_interface(path):
    bad = []
    for line, mod in _imports(path):
        if not (mod == "dam" or mod.startswith("dam.")):
            continue
        parts = mod.split(".")
        # `dam`, a subpackage's __init__ (dam.corpus) or a public top-level module (dam.progress);
        # never a module inside a subpackage, never the CLI
        public = mod == "dam" or (len(parts) == 2 and not parts[1].startswith("_"))
        if not public or mod.startswith("dam.cli"):
            bad.append(f"line {line}: {mod}")
    assert not bad, f"{_module_name(path)} reaches inside dam:\n" + "\n".join(bad)


def test_no_import_cycles():
    graph: dict[str, set[str]] = {}
    names = {_module_name(p) for p in SOURCES}
    for p in SOURCES:
        me = _module_name(p)
        deps = set()
        for _, mod in _imports(p):
            # the longest known module that `mod` names
            while mod and mod not in names:
                mod = mod.rpartition(".")[0]
            # a package's __init__ re-exporting its own modules lazily is not a dependency
            if mod and mod != me and not me.startswith(mod + "."):
                deps.add(mod)
        graph[me] = deps
    # Tarjan's strongly connected components
    index, low, stack, on, sccs, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
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
                sccs.append(sorted(comp))

    import sys

    sys.setrecursionlimit(10000)
    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert not sccs, f"import cycles: {sccs}"


def test_nothing_imports_the_cli():
    bad = [
        f"{_module_name(p)}:{line}"
        for p in SOURCES
        if not _module_name(p).startswith("dam.cli")
        for line, mod in _imports(p)
        if mod.startswith("dam.cli")
    ]
    assert not bad, bad


def test_import_dam_is_light():
    import subprocess
    import sys

    code = (
        "import sys, dam; heavy = [m for m in ('scipy', 'sklearn', 'matplotlib', 'jax', 'praatio') "
        "if m in sys.modules]; print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_old_import_paths_warn_and_work():
    import importlib
    import sys
    import warnings

    from dam._compat import MOVED

    for old, new in MOVED.items():
        parent, _, attr = old.rpartition(".")
        before = getattr(sys.modules[parent], attr, None)
        sys.modules.pop(old, None)
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                mod = importlib.import_module(old)
            assert mod is importlib.import_module(new)
            assert any(issubclass(w.category, DeprecationWarning) and new in str(w.message) for w in caught), old
        finally:  # importing dam.compare binds the module over the function dam.compare: undo for later tests
            sys.modules.pop(old, None)
            if before is None:
                vars(sys.modules[parent]).pop(attr, None)
            else:
                setattr(sys.modules[parent], attr, before)
