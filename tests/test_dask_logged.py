"""Campaigns on recorded logs on a Dask cluster: the prepared source shipped once per worker
(scattered, or written to a directory the workers read), results bit-identical to the
in-process campaign, transfer and worker memory reported."""

from __future__ import annotations

import hashlib
import json
import pickle
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import navfdi
from navfdi import _core, logs
from navfdi.scenario import load_scenario

distributed = pytest.importorskip("dask.distributed")


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, distributed.Client(cluster) as c:
        yield c


def _digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _same_campaign(local, remote, tmp_path):
    """Equal runs tables, and byte-identical runs.parquet and summary.csv files."""
    pd.testing.assert_frame_equal(local.runs, remote.runs)
    a, b = tmp_path / "local", tmp_path / "remote"
    local.write(a, figures=False)
    remote.write(b, figures=False)
    for name in ("runs.parquet", "summary.csv"):
        assert _digest(a / name) == _digest(b / name), name


@pytest.mark.parametrize("ship", ["scatter", "dir"])
def test_drive_lc_campaign_on_a_cluster_equals_the_local_one(client, tmp_path, ship):
    local = navfdi.montecarlo("drive_lc", runs=6, seed=4, chunk_size=2, keep_series=[3], progress=False)
    where = "scatter" if ship == "scatter" else str(tmp_path)
    remote = navfdi.montecarlo("drive_lc", runs=6, seed=4, chunk_size=2, keep_series=[3], progress=False, client=client, ship=where)
    assert remote.backend.startswith("dask") and not remote.partial
    _same_campaign(local, remote, tmp_path)
    np.testing.assert_array_equal(local.series[(0, 3)]["error"], remote.series[(0, 3)]["error"])
    # Two variants: two prepared sources, each shipped once to each worker, whatever the
    # number of chunks (6 runs × 2 variants in chunks of 2).
    t = remote.transfer
    sc = load_scenario("drive_lc")
    want = sum(len(logs.logged_source(v).to_bytes()) for _, v in sc.variants())
    assert t.sources == 2 and t.bytes_per_worker == want
    assert t.workers == 2 and all(r > 50e6 for r in t.peak_worker_rss.values())
    assert 0 < t.ship_seconds < t.wall_seconds
    if ship == "dir":
        files = sorted(tmp_path.glob("drive_lc-*.navsrc"))
        assert len(files) == 2 and t.ship == str(tmp_path.resolve())
    info = json.loads((tmp_path / "remote" / "campaign.json").read_text())
    assert info["transfer"]["bytes_per_worker"] == want and info["transfer"]["sources"] == 2
    assert "MB per worker" in t.line() and "peak worker memory" in t.line()


def test_walk_tc_with_protection_levels_ships_its_datum(client, tmp_path):
    """A tight logged campaign with filter protection levels: the fault-free datum travels
    with the source (computed once, not per chunk) and the integrity table is the local one."""
    sc = load_scenario("walk_tc").with_values({"tight.integrity": {}}, create=True)
    local = navfdi.montecarlo(sc, runs=2, seed=1, chunk_size=1, progress=False)
    remote = navfdi.montecarlo(sc, runs=2, seed=1, chunk_size=1, progress=False, client=client)
    _same_campaign(local, remote, tmp_path)
    pd.testing.assert_frame_equal(local.integrity_summary(), remote.integrity_summary())
    assert len(remote.integrity_summary()) and remote.transfer.sources == len(sc.variant_names())


def test_interrupted_cluster_campaign_keeps_finished_runs(client, monkeypatch, tmp_path):
    from dask import distributed as d

    real_ac = d.as_completed

    def two_then_ctrl_c(futures):
        for k, f in enumerate(real_ac(futures)):
            if k == 2:
                raise KeyboardInterrupt
            yield f

    monkeypatch.setattr(d, "as_completed", two_then_ctrl_c)
    camp = navfdi.montecarlo("drive_lc", runs=8, seed=2, chunk_size=2, progress=False, client=client)
    assert camp.partial and camp.runs.groupby(["point", "run"]).ngroups == 4
    camp.write(tmp_path, figures=False)
    assert json.loads((tmp_path / "campaign.json").read_text())["partial"] is True


def test_prepared_source_round_trip_and_bad_bytes():
    src = logs.logged_source(load_scenario("drive_lc"))
    blob = src.to_bytes()
    back = _core.LoggedSource.from_bytes(blob)
    again = pickle.loads(pickle.dumps(src))
    a, b, c = (s.run_chunk(7, 0, 2, 1) for s in (src, back, again))
    for k in ("pos_rms", "hor_rms", "delay", "detected", "fault_start"):
        np.testing.assert_array_equal(np.asarray(a[k], float), np.asarray(b[k], float))
        np.testing.assert_array_equal(np.asarray(a[k], float), np.asarray(c[k], float))
    assert back.epochs == src.epochs and back.cells == src.cells
    with pytest.raises(navfdi.FileFormatError, match="not a navfdi prepared source"):
        _core.LoggedSource.from_bytes(b"PK\x03\x04" + blob[4:])
    with pytest.raises(navfdi.FileFormatError, match="truncated or corrupted"):
        _core.LoggedSource.from_bytes(blob[: len(blob) // 2])
    with pytest.raises(navfdi.FileFormatError, match="after the end"):
        _core.LoggedSource.from_bytes(blob + b"\0\0")
    version = _core.__version__.encode()
    other = blob.replace(version, b"9" * len(version), 1)
    with pytest.raises(navfdi.FileFormatError, match=r"written by navfdi 9+, and this is navfdi"):
        _core.LoggedSource.from_bytes(other)


def test_ship_is_checked(client, tmp_path):
    with pytest.raises(ValueError, match="only a campaign on a Dask cluster"):
        navfdi.montecarlo("drive_lc", runs=1, progress=False, ship=str(tmp_path))
    with pytest.raises(ValueError, match="not a directory|a directory every Dask worker"):
        navfdi.montecarlo("drive_lc", runs=1, progress=False, client=client, ship=str(tmp_path / "nowhere"))


def test_montecarlo_cli_on_a_scheduler(client, tmp_path):
    address = client.scheduler_info()["address"]
    out = tmp_path / "mc"
    proc = subprocess.run(
        [sys.executable, "-m", "navfdi", "montecarlo", "drive_lc", "--runs", "2", "--scheduler", address, "--out", str(out)],
        capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "dask: 2 worker(s); shipped 2 prepared source(s)" in proc.stdout
    info = json.loads((out / "campaign.json").read_text())
    assert info["backend"].startswith("dask") and info["transfer"]["workers"] == 2
