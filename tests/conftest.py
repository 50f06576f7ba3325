"""Shared test fixtures.

SIGINT: a test suite started in the background (``cmd &`` in a non-interactive shell, some CI
runners) inherits SIGINT ignored, and Python then installs no KeyboardInterrupt handler — in
itself or in the children it starts. The Ctrl-C tests restore the disposition they rely on.
"""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterator

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
