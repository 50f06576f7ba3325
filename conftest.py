"""Root test configuration (applies to ``tests/`` and ``benches/``).

Under pytest-xdist every worker is its own process on a machine with few cores: numpy's
OpenBLAS would start one busy-waiting thread per core in each worker, and the workers' BLAS
threads then spin against each other (a 2000 × 2000 product took 10× longer than alone on
2 cores). Each worker's BLAS therefore runs on one thread unless the caller chose otherwise;
this must happen before numpy is first imported, which is why it is here and not in a fixture.
"""

from __future__ import annotations

import os

if os.environ.get("PYTEST_XDIST_WORKER"):
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")
