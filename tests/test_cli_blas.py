"""The command line's process runs numpy's BLAS on one thread (OpenBLAS's workers spin for
about 0.1 s of CPU after numpy loads); the library imported by a user's program leaves BLAS
as the user set it."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

PROBE = (
    "import sys; sys.argv = [{argv!r}]\n"
    "{pre}\n"
    "import navfdi, os\n"
    "print(os.environ.get('OPENBLAS_NUM_THREADS', 'unset'))\n"
)


def _probe(argv: str, pre: str = "", env_value: str | None = None) -> str:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if env_value is not None:
        env["OPENBLAS_NUM_THREADS"] = env_value
    out = subprocess.run([sys.executable, "-c", PROBE.format(argv=argv, pre=pre)], env=env,
                         capture_output=True, text=True, timeout=120, check=True)
    return out.stdout.strip()


@pytest.mark.parametrize("argv", ["/usr/local/bin/navfdi", "-m"])
def test_the_command_line_runs_blas_on_one_thread(argv: str) -> None:
    assert _probe(argv) == "1"


def test_a_users_program_keeps_its_blas_threads() -> None:
    assert _probe("/home/user/analysis.py") == "unset"


def test_a_users_setting_wins() -> None:
    assert _probe("/usr/local/bin/navfdi", env_value="4") == "4"


def test_numpy_loaded_first_is_left_alone() -> None:
    # Too late to matter once numpy has started its threads: nothing is set.
    assert _probe("/usr/local/bin/navfdi", pre="import numpy") == "unset"
