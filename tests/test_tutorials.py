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

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "tutorials.md"


def _blocks(text: str) -> list[tuple[str, str]]:
    return [(m.group(1), m.group(2)) for m in re.finditer(r"^```(\w+)\n(.*?)^```$", text, flags=re.S | re.M)]


def test_tutorials_run_as_written(tmp_path: Path, monkeypatch) -> None:
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "data").symlink_to(ROOT / "tests" / "data")
    monkeypatch.chdir(tmp_path)
    blocks = _blocks(PAGE.read_text(encoding="utf-8"))
    kinds = {k for k, _ in blocks}
    assert kinds == {"bash", "python", "toml"}, kinds
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
    assert (tmp_path / "drive-mc" / "runs.parquet").is_file() and (tmp_path / "mc" / "report.html").is_file()
