"""The shape of the code (docs/ARCHITECTURE.md): the import graphs of the Rust core,
the binding crate and the Python package have no cycle between files, imports only point down
the layers, no architecture and no building block imports the simulator, and no source file
is over 900 lines (the hand-written stub ``_core.pyi`` aside).

The graphs are read from the source text: ``use crate::…``, ``crate::…`` paths and
``super::…`` in Rust (comments, doc links and ``#[cfg(test)]`` modules left out), ``import``
and ``from … import`` in Python (``TYPE_CHECKING`` imports included: they are edges too).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "rust" / "navfdi-core" / "src"
PY = ROOT / "rust" / "navfdi-py" / "src"
PKG = ROOT / "python" / "navfdi"
MAX_LINES = 900

# The core's layers, lowest first: a module may import from its own layer (without cycles)
# and the layers below it, never from a layer above.
CORE_LAYERS = [
    {"error", "validate", "linalg", "memory", "cancel"},
    {"kalman", "stats", "run"},
    {"detect", "ins", "gnss", "fusion", "integrity"},
    {"spec"},
    {"stream", "record", "metrics"},
    {"arch", "sim", "logs"},
    {"montecarlo"},
    {"lib"},
]

PY_LAYERS = [
    {"_core", "units", "_intervals", "_filter", "_json", "_errors", "_text", "_bundled", "_schema"},
    {"_terrain", "_fields", "_lc_schema", "_logtime", "_imu_warnings", "_gnss_geometry", "_gnss_noise", "_gnss_plots", "_gnss_coverage", "_gnss_auto"},
    {"frames"},
    {"scenario"},
    {"record", "consistency", "demo", "gnss", "report", "integrity", "logs", "gnss_integrity", "simlog", "_timeseries", "gnss_logs", "gnsslogger", "rosbag", "calibrate", "_pos_forms"},
    {"plots", "plots_logged"},
    {"runs", "montecarlo", "_dask"},
    {"federated", "cli", "__init__", "__main__"},
]


def _rust_module_of(path: Path, src: Path) -> list[str]:
    rel = path.relative_to(src).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] in ("mod", "lib"):
        parts = parts[:-1]
    return parts


def _rust_file(mod: list[str], src: Path) -> Path | None:
    if not mod:
        return src / "lib.rs"
    p = src.joinpath(*mod)
    for cand in (p.with_suffix(".rs"), p / "mod.rs"):
        if cand.exists():
            return cand
    return None


def _resolve(path: list[str], src: Path) -> Path | None:
    """The file of the longest prefix of a module path that is a file."""
    for n in range(len(path), -1, -1):
        f = _rust_file(path[:n], src)
        if f is not None:
            return f
    return None


def _strip_rust(text: str) -> str:
    text = text.split("#[cfg(test)]", 1)[0]
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return "\n".join(line.split("//", 1)[0] for line in text.splitlines())


PATH = re.compile(r"\b(crate|super)((?:::[A-Za-z_][A-Za-z0-9_]*)+)(::\{([^{}]*)\})?")


def rust_graph(src: Path) -> dict[Path, set[Path]]:
    graph: dict[Path, set[Path]] = {}
    for f in sorted(src.rglob("*.rs")):
        here = _rust_module_of(f, src)
        edges: set[Path] = set()
        for m in PATH.finditer(_strip_rust(f.read_text())):
            root, rest, _, group = m.groups()
            base = [] if root == "crate" else here[:-1]
            segs = base + [s for s in rest.split("::") if s]
            targets = [segs]
            if group:
                for item in group.split(","):
                    item = item.strip().split(" as ")[0].split("::")[0].strip()
                    if item and item not in ("self", "*"):
                        targets.append(segs + [item])
            for t in targets:
                tf = _resolve(t, src)
                if tf is not None and tf != f:
                    edges.add(tf)
        graph[f] = edges
    return graph


def python_graph(pkg: Path) -> dict[Path, set[Path]]:
    graph: dict[Path, set[Path]] = {}
    stub = {"_core": pkg / "_core.pyi"}
    for f in sorted(pkg.glob("*.py")):
        edges: set[Path] = set()
        for node in ast.walk(ast.parse(f.read_text())):
            names: list[str] = []
            if isinstance(node, ast.ImportFrom) and node.module:
                if node.module == "navfdi":
                    names = [a.name for a in node.names]
                elif node.module.startswith("navfdi."):
                    names = [node.module.split(".")[1]]
            elif isinstance(node, ast.Import):
                names = [a.name.split(".")[1] for a in node.names if a.name.startswith("navfdi.")]
            for n in names:
                t = stub.get(n, pkg / f"{n}.py")
                if t.exists() and t != f:
                    edges.add(t)
        graph[f] = edges
    return graph


def find_cycle(graph: dict[Path, set[Path]]) -> list[Path] | None:
    state: dict[Path, int] = {}
    stack: list[Path] = []

    def visit(n: Path) -> list[Path] | None:
        state[n] = 1
        stack.append(n)
        for m in sorted(graph.get(n, ())):
            if state.get(m) == 1:
                return stack[stack.index(m):] + [m]
            if state.get(m) is None:
                c = visit(m)
                if c:
                    return c
        stack.pop()
        state[n] = 2
        return None

    for n in sorted(graph):
        if n not in state:
            c = visit(n)
            if c:
                return c
    return None


def _layer(name: str, layers: list[set[str]]) -> int:
    for i, group in enumerate(layers):
        if name in group:
            return i
    raise AssertionError(f"{name} is in no layer: add it to the layer list (and docs/ARCHITECTURE.md)")


def _top(f: Path, src: Path) -> str:
    mod = _rust_module_of(f, src)
    return mod[0] if mod else "lib"


@pytest.mark.parametrize("src", [CORE, PY], ids=["navfdi-core", "navfdi-py"])
def test_rust_import_graph_has_no_cycle(src: Path) -> None:
    cycle = find_cycle(rust_graph(src))
    assert cycle is None, " -> ".join(str(p.relative_to(src)) for p in cycle or [])


def test_python_import_graph_has_no_cycle() -> None:
    cycle = find_cycle(python_graph(PKG))
    assert cycle is None, " -> ".join(p.name for p in cycle or [])


def test_core_imports_point_down() -> None:
    bad = []
    for f, edges in rust_graph(CORE).items():
        lf = _layer(_top(f, CORE), CORE_LAYERS)
        for t in edges:
            if _layer(_top(t, CORE), CORE_LAYERS) > lf:
                bad.append(f"{f.relative_to(CORE)} -> {t.relative_to(CORE)}")
    assert not bad, "imports from a lower layer up to a higher one:\n" + "\n".join(sorted(bad))


def test_python_imports_point_down() -> None:
    bad = []
    for f, edges in python_graph(PKG).items():
        lf = _layer(f.stem, PY_LAYERS)
        for t in edges:
            if _layer(t.stem, PY_LAYERS) > lf:
                bad.append(f"{f.name} -> {t.name}")
    assert not bad, "\n".join(sorted(bad))


def test_architectures_and_building_blocks_never_import_the_simulator() -> None:
    graph = rust_graph(CORE)
    bad = [
        f"{f.relative_to(CORE)} -> {t.relative_to(CORE)}"
        for f, edges in graph.items()
        for t in edges
        if _top(f, CORE) in {"arch", "gnss", "fusion", "detect", "ins", "spec", "stream", "record", "metrics"}
        and _top(t, CORE) == "sim"
    ]
    assert not bad, "\n".join(bad)


def test_the_graph_reader_sees_imports() -> None:
    """The checks above could pass on a reader that finds nothing: it must see known edges."""
    g = rust_graph(CORE)
    assert CORE / "spec" / "mod.rs" in g[CORE / "arch" / "tight.rs"]
    assert CORE / "stream.rs" in g[CORE / "arch" / "federated.rs"]
    assert CORE / "gnss" / "snapshot.rs" in g[CORE / "arch" / "tight.rs"]  # `use crate::gnss::snapshot::{…}`
    assert CORE / "ins" / "earth.rs" in g[CORE / "sim" / "noise.rs"] or CORE / "ins" / "mod.rs" in g[CORE / "sim" / "noise.rs"]
    assert PKG / "scenario.py" in python_graph(PKG)[PKG / "runs.py"]
    a, b, c = Path("a"), Path("b"), Path("c")
    assert find_cycle({a: {b}, b: {c}, c: {a}}) == [a, b, c, a]
    assert find_cycle({a: {b}, b: {c}, c: set()}) is None


def test_no_source_file_over_900_lines() -> None:
    files = [*CORE.rglob("*.rs"), *PY.rglob("*.rs"), *PKG.glob("*.py"), *(ROOT / "tests").glob("*.py"), *(ROOT / "benches").glob("*.py")]
    long = {str(f.relative_to(ROOT)): n for f in files if (n := len(f.read_text().splitlines())) > MAX_LINES}
    assert not long, long
