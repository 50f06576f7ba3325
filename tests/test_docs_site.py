"""The documentation site: it builds with ``mkdocs build --strict`` (a broken link, anchor or
API reference fails), every page of ``docs/`` is in it, and its API reference lists every
public name (``docs/reference/api.md`` is what ``docs/scripts/api_reference.py`` writes)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_api_reference_is_generated_and_complete() -> None:
    import navfdi

    r = subprocess.run([sys.executable, str(ROOT / "docs" / "scripts" / "api_reference.py"), "--check"], capture_output=True)
    assert r.returncode == 0, "docs/reference/api.md is stale: run python docs/scripts/api_reference.py"
    text = (ROOT / "docs" / "reference" / "api.md").read_text(encoding="utf-8")
    for name in navfdi.__all__:
        if not name.startswith("__"):
            assert f".{name}\n" in text, name


def test_every_page_is_in_the_site_nav() -> None:
    conf = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    for page in (ROOT / "docs").rglob("*.md"):
        rel = page.relative_to(ROOT / "docs").as_posix()
        assert f": {rel}" in conf, f"{rel} is not in mkdocs.yml's nav"


def test_site_builds_strict(tmp_path) -> None:
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings")
    r = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT, capture_output=True, text=True, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"}, timeout=600,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    api = (tmp_path / "site" / "reference" / "api" / "index.html").read_text(encoding="utf-8")
    assert 'id="navfdi._core.KalmanFilter"' in api and 'id="navfdi.gnss.gnss_solve"' in api
