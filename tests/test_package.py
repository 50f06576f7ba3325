"""Package-level checks: stubs match the extension, the package type-checks, the CLI works."""

from __future__ import annotations

import subprocess
from pathlib import Path
import sys

import pytest

import navfdi


def run(*args, **kw):
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=300, **kw)


def test_stubtest_passes():
    out = run("-m", "mypy.stubtest", "navfdi._core")
    assert out.returncode == 0, out.stdout + out.stderr


def test_package_type_checks():
    out = run("-m", "mypy", "-p", "navfdi")
    assert out.returncode == 0, out.stdout + out.stderr


def test_public_names_are_documented():
    """Every public name, and every public method and property of public classes, has a docstring."""
    import inspect

    missing = []
    for name in navfdi.__all__:
        obj = getattr(navfdi, name)
        if name == "__version__":
            assert isinstance(obj, str)
            continue
        if not (obj.__doc__ or "").strip():
            missing.append(name)
        if inspect.isclass(obj):
            for attr, value in vars(obj).items():
                if not attr.startswith("_") and not (getattr(value, "__doc__", None) or "").strip():
                    missing.append(f"{name}.{attr}")
    assert missing == []


def test_demo_reports_both_faults_for_every_detector():
    out = run("-m", "navfdi", "demo", "--seed", "0")
    assert out.returncode == 0, out.stderr
    rows = [line.split() for line in out.stdout.splitlines()]
    by = {(r[0], r[1]): r for r in rows if r and r[0] in ("chi2", "sprt", "joint") and r[1] in ("ramp", "step")}
    # SPRT misses the step (still in alarm from the ramp); chi-square and joint find both.
    assert "missed" in by[("sprt", "step")]
    assert "never" in by[("sprt", "ramp")]
    for det in ("chi2", "joint"):
        assert "missed" not in by[(det, "ramp")] and "missed" not in by[(det, "step")]
    # The joint detector raises on the ramp no later than chi-square (it is the SPRT's alarm).
    raised = lambda r: float(r[5])  # noqa: E731  (detector, fault name (3 words), window, raised)
    assert raised(by[("joint", "ramp")]) <= raised(by[("chi2", "ramp")])


def test_cli_reports_bad_parameters_cleanly():
    out = run("-m", "navfdi", "demo", "--pf", "1.5")
    assert out.returncode == 2
    assert "pf" in out.stderr and "Traceback" not in out.stderr


@pytest.mark.parametrize("flag", ["--version", "--help"])
def test_cli_flags(flag):
    out = run("-m", "navfdi", flag)
    assert out.returncode == 0 and "navfdi" in out.stdout


def test_guide_examples_run(tmp_path):
    """Every Python block of docs/guide.md runs, in order, as one script."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "guide.md").read_text(encoding="utf-8")
    blocks, inside, cur = [], False, []
    for line in text.splitlines():
        if line.startswith("```python"):
            inside, cur = True, []
        elif line.startswith("```") and inside:
            inside = False
            blocks.append("\n".join(cur))
        elif inside:
            cur.append(line)
    assert blocks, "docs/guide.md has no python example"
    script = tmp_path / "example.py"
    script.write_text("\n\n".join(blocks), encoding="utf-8")
    out = run(str(script))
    assert out.returncode == 0, out.stderr


def test_cli_unwritable_output_is_a_clear_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    out = run("-m", "navfdi", "run", "yang2013", "--out", str(blocker / "sub"))
    assert out.returncode == 2
    assert "is not a directory" in out.stderr and "Traceback" not in out.stderr
    assert out.stdout == ""  # refused before the run, not after it
    assert blocker.read_text() == "not a directory"


def _features(package: str, edges: str) -> dict[tuple[str, str], set[str]]:
    """{(crate, version): {feature list as printed}} of `cargo tree -p package -e edges`."""
    import shutil
    from pathlib import Path

    if shutil.which("cargo") is None:
        pytest.skip("cargo is not installed")
    root = Path(__file__).resolve().parents[1]
    out = subprocess.run(
        ["cargo", "tree", "--offline", "-q", "-p", package, "-e", edges, "-f", "{p} {f}", "--prefix", "none"],
        cwd=root, capture_output=True, text=True, timeout=120,
    )
    if out.returncode != 0:
        pytest.skip(f"cargo tree unavailable offline: {out.stderr.strip()[:200]}")
    found: dict[tuple[str, str], set[str]] = {}
    for line in out.stdout.splitlines():
        parts = line.replace(" (*)", "").split()
        if len(parts) < 2:
            continue
        feats = parts[2] if len(parts) > 2 and not parts[2].startswith("(") else ""
        found.setdefault((parts[0], parts[1]), set()).add(feats)
    return found


def test_the_wheel_and_the_rust_tests_build_the_same_dependencies():
    """The Quick start's `cargo test --release` reuses what `pip install` built only if every
    dependency the two share has the same features (rust/navfdi-core/Cargo.toml): a changed
    dependency would silently double the build time and target/."""
    wheel = _features("navfdi-py", "normal,build")
    tests = _features("navfdi-core", "normal,build,dev")
    differ = {k: (wheel[k], tests[k]) for k in set(wheel) & set(tests) if wheel[k] != tests[k]}
    assert not differ, f"features differ between the wheel and the Rust tests: {differ}"


def test_import_navfdi_leaves_pandas_out():
    """`import navfdi` loads numpy and the core, not pandas (and the pyarrow it loads, ~72 MB
    resident): a day-length RINEX file is parsed and solved before pandas arrives
    (item 7: 137 MB peak for `navfdi gnss` on benches/bench_memory.py's file)."""
    import subprocess
    import sys

    code = "import sys, navfdi, navfdi.cli, navfdi.gnss, navfdi.logs; print(sorted(m for m in ('pandas', 'pyarrow', 'matplotlib') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "[]"


def test_freed_heap_is_handed_back():
    """The glibc workaround of `navfdi.gnss._release_freed_memory` (malloc_trim): memory freed
    below a live allocation stays resident without it (glibc trims only the top of the heap),
    and is handed back with it. A dropped run's records are such memory."""
    import platform
    import subprocess
    import sys

    if platform.system() != "Linux" or platform.libc_ver()[0] != "glibc":
        pytest.skip("malloc_trim is glibc's")
    code = (
        "from navfdi.gnss import _release_freed_memory\n"
        "rss = lambda: int(open('/proc/self/statm').read().split()[1]) * 4096 / 2**20\n"
        "blocks = [bytes(1000) + bytes([i % 256]) for i in range(200_000)]\n"
        "pin = bytes(1000) + b'x'\n"
        "del blocks\n"
        "freed = rss()\n"
        "_release_freed_memory()\n"
        "print(freed, rss())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    freed, trimmed = float(out[0]), float(out[1])
    assert freed - trimmed > 100, (freed, trimmed)


def test_no_internal_tracking_numbers_in_what_users_read():
    """The project's issue numbers stay out of the package, the docs, the benchmarks and the
    scenario descriptions."""
    import re

    root = Path(__file__).resolve().parent.parent
    pattern = re.compile(r"\bissue ?#?\d+", re.IGNORECASE)
    hits = []
    for folder in ("python", "docs", "benches", "rust"):
        for p in (root / folder).rglob("*"):
            if p.is_file() and p.suffix in (".py", ".pyi", ".md", ".toml", ".rs") and "target" not in p.parts:
                for i, line in enumerate(p.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
                    if pattern.search(line):
                        hits.append(f"{p.relative_to(root)}:{i}")
    for p in (root / "README.md",):
        hits += [f"README.md:{i}" for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1) if pattern.search(line)]
    assert hits == []
