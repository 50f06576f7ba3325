"""Shared test fixtures.

SIGINT: a test suite started in the background (``cmd &`` in a non-interactive shell, some CI
runners) inherits SIGINT ignored, and Python then installs no KeyboardInterrupt handler — in
itself or in the children it starts. The Ctrl-C tests restore the disposition they rely on.
"""

from __future__ import annotations

import importlib.util
import signal
from collections.abc import Callable, Iterator
from pathlib import Path
from types import ModuleType

import pytest


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.fixture
def sigint_child() -> Callable[[], None]:
    """``preexec_fn`` for a child that must receive SIGINT: its disposition back to the
    default, so the child's Python installs its KeyboardInterrupt handler."""
    return _default_sigint


@pytest.fixture
def sigint_handled() -> Iterator[None]:
    """SIGINT raises KeyboardInterrupt in this process for the test (restored after)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _load_docs_script(name: str) -> ModuleType:
    path = Path(__file__).resolve().parents[1] / "docs" / "scripts" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture
def docs_script() -> Callable[[str], ModuleType]:
    """Load a script of ``docs/scripts`` by name (without ``.py``) as a module: the tests use
    the generators and checks the documented tables are made with."""
    return _load_docs_script
