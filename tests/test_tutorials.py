"""docs/tutorials.md runs as written: its Python blocks in order in one namespace, its TOML
blocks written to the file their first line names (``# file: NAME``), its shell blocks'
``navfdi`` commands, all in a scratch directory that sees the repository's ``tests/data``."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "tutorials.md"


def _blocks(text: str) -> list[tuple[str, str]]:
    return [(m.group(1), m.group(2)) for m in re.finditer(r"^```(\w+)\n(.*?)^```$", text, flags=re.S | re.M)]


def _sections() -> dict[str, str]:
    """The page's numbered tutorials (``## N. Title``) by number; each one stands alone."""
    text = PAGE.read_text(encoding="utf-8")
    parts = re.split(r"^## (\d+)\. .*$", text, flags=re.M)
    return {parts[i]: parts[i + 1] for i in range(1, len(parts), 2)}


# What each tutorial leaves behind for its reader, beyond its own asserts.
PRODUCTS = {"1": ["rinex-run/summary.json"], "2": ["drive-mc/runs.parquet"], "3": ["mc/report.html"], "4": []}


def test_the_page_has_the_tutorials_this_test_knows() -> None:
    sections = _sections()
    assert sorted(sections) == sorted(PRODUCTS)
    kinds = {k for body in sections.values() for k, _ in _blocks(body)}
    assert kinds == {"bash", "python", "toml"}, kinds
    assert len(_blocks(PAGE.read_text(encoding="utf-8"))) == sum(len(_blocks(b)) for b in sections.values())


@pytest.mark.parametrize("number", sorted(PRODUCTS))
def test_tutorial_runs_as_written(number: str, tmp_path: Path, monkeypatch) -> None:
    """One tutorial's blocks in order, in one namespace and a scratch directory of its own
    (the tutorials run in parallel under pytest-xdist)."""
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "data").symlink_to(ROOT / "tests" / "data")
    monkeypatch.chdir(tmp_path)
    blocks = _blocks(_sections()[number])
    assert blocks, f"tutorial {number} has no code"
    namespace: dict = {"__name__": "__tutorial__"}
    env = {**os.environ, "MPLBACKEND": "Agg"}
    for kind, body in blocks:
        if kind == "python":
            exec(compile(body, str(PAGE), "exec"), namespace)  # noqa: S102 - the page's own examples
        elif kind == "toml":
            first = body.splitlines()[0]
            assert first.startswith("# file: "), "a TOML block of the tutorials names its file"
            Path(first[len("# file: "):].strip()).write_text(body, encoding="utf-8")
        else:
            for line in body.replace("\\\n", " ").splitlines():
                if not line.strip() or line.lstrip().startswith("#"):
                    continue
                args = shlex.split(line, comments=True)
                assert args[0] == "navfdi", f"the tutorials' shell blocks run navfdi only: {line}"
                r = subprocess.run([sys.executable, "-m", "navfdi", *args[1:]], capture_output=True, text=True, env=env)
                assert r.returncode == 0, f"{line}\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}"
    for product in PRODUCTS[number]:
        assert (tmp_path / product).is_file(), product
