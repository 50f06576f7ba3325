"""A campaign's chunks on a Dask cluster (the ``client=`` backend of :func:`navfdi.montecarlo`).

A simulated scenario travels as its JSON with each chunk (a few kB; each worker prepares it
once and keeps it). A campaign on recorded logs ships each sweep
point's prepared source (:class:`navfdi._core.LoggedSource`: IMU samples, GNSS streams or
satellite ranges, reference and the fault-free datum, a few MB) **once per worker**, chosen by
``ship``:

- ``"scatter"`` (default): the client sends its bytes to every worker before the first chunk
  (``Client.scatter(..., broadcast=True)``); the chunks refer to the worker's copy;
- a directory every worker sees at the same path (a shared file system): the client writes
  each source there once (``<scenario>-<point>-<hash>.navsrc``, kept for later campaigns on
  the same source) and each worker reads it at its first chunk.

Either way the source is encoded once, and each worker decodes it at its first chunk and keeps
it (by the hash of its bytes). The chunk protocol is the local one (same tasks, same per-run
seeds), so the runs are bit-identical to an in-process campaign. What was shipped and the workers' peak memory
are reported (:class:`Transfer`, ``Campaign.transfer``, ``campaign.json``).
"""

from __future__ import annotations

import hashlib
import os
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

SHIP_SCATTER = "scatter"


@dataclass
class Transfer:
    """What a Dask campaign shipped, and what its workers used.

    Attributes
    ----------
    ship : str
        ``"scatter"``, the shared directory the sources were read from, or ``"scenario"``
        (a simulated scenario: its JSON travels with each chunk).
    sources : int
        Prepared sources shipped (one per sweep point of a campaign on recorded logs).
    bytes_per_worker : int
        Bytes of prepared sources each worker received or read, once (0 for a simulated
        scenario).
    ship_seconds : float
        Wall time spent shipping them (s): encoding and the scatter, or writing the files,
        plus the slowest worker's first read and decode.
    workers : int
        Workers that ran chunks.
    peak_worker_rss : dict
        ``{worker address: peak resident memory (bytes)}`` of each worker process over the
        campaign (``ru_maxrss``; 0 where the platform has no ``resource`` module).
    wall_seconds : float
        Wall time of the whole campaign (s), shipping included.
    """

    ship: str
    sources: int = 0
    bytes_per_worker: int = 0
    ship_seconds: float = 0.0
    workers: int = 0
    peak_worker_rss: dict[str, int] = field(default_factory=dict)
    wall_seconds: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        """The fields as a JSON-ready dict."""
        return asdict(self)

    def line(self) -> str:
        """One line for the console: bytes shipped per worker, the time it took and its share
        of the campaign's wall time, and the largest worker peak memory."""
        peak = max(self.peak_worker_rss.values(), default=0)
        share = f" ({100 * self.ship_seconds / self.wall_seconds:.1f} % of {self.wall_seconds:.1f} s)" if self.wall_seconds else ""
        what = f"{self.sources} prepared source(s), {self.bytes_per_worker / 1e6:.2f} MB per worker by {self.ship}" if self.sources else "scenario JSON with each chunk"
        mem = f"; peak worker memory {peak / 1e6:.0f} MB" if peak else ""
        return f"dask: {self.workers} worker(s); shipped {what} in {self.ship_seconds:.2f} s{share}{mem}"


def _peak_rss() -> int:
    """This process's peak resident memory (bytes), 0 where unknown."""
    try:
        import resource
    except ImportError:  # Windows
        return 0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(rss if sys.platform == "darwin" else rss * 1024)


def _worker() -> str:
    try:
        from dask.distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return f"pid {os.getpid()}"


#: Prepared sources decoded in this worker process, by the hash of their bytes.
_DECODED: dict[str, Any] = {}


def logged_chunk(key: str, source: bytes | str, seed: int, start: int, count: int, keep: tuple[int, ...]) -> tuple[dict[str, Any], str, int, float]:
    """One chunk of a campaign on recorded logs, run on a worker: ``source`` is the prepared
    source's bytes (the worker's scattered copy) or the path of its file, ``key`` their hash;
    they are decoded at the worker's first chunk and kept. Returns the chunk, the worker's
    address, its peak memory (bytes) and the seconds spent reading and decoding the source here
    (0 when it was already decoded)."""
    from navfdi import _core

    load = 0.0
    if key not in _DECODED:
        t = time.perf_counter()
        blob = Path(source).read_bytes() if isinstance(source, str) else source
        if len(_DECODED) >= 8:
            _DECODED.pop(next(iter(_DECODED)))
        _DECODED[key] = _core.LoggedSource.from_bytes(blob)
        load = time.perf_counter() - t
    chunk = _DECODED[key].run_chunk(seed, start, count, 1, list(keep))
    return chunk, _worker(), _peak_rss(), load


def scenario_chunk(chunk_fn: Any, *args: Any) -> tuple[dict[str, Any], str, int, float]:
    """``chunk_fn(*args)`` (one chunk of a simulated campaign) run on a worker, returned as
    :func:`logged_chunk` returns."""
    return chunk_fn(*args), _worker(), _peak_rss(), 0.0


def ship_sources(client: Any, name: str, prepared: list[Any], ship: str | os.PathLike[str]) -> tuple[list[tuple[str, Any]], Transfer]:
    """Ship each prepared source to the workers once, encoded once
    (:meth:`navfdi._core.LoggedSource.to_bytes`); returns what the chunks take as their
    source — ``(hash, scatter future of the bytes or file path)`` — and the transfer so far."""
    t = time.perf_counter()
    blobs = [p.to_bytes() for p in prepared]
    keys = [hashlib.sha256(b).hexdigest()[:16] for b in blobs]
    size = sum(len(b) for b in blobs)
    if str(ship) == SHIP_SCATTER:
        handles = [(k, client.scatter(b, broadcast=True, hash=False)) for k, b in zip(keys, blobs)]
        return handles, Transfer(SHIP_SCATTER, len(prepared), size, time.perf_counter() - t)
    folder = Path(ship)
    if not folder.is_dir():
        raise ValueError(f"ship = {str(ship)!r}: not a directory; give \"scatter\" or a directory every Dask worker sees at this path")
    paths = []
    for i, (key, blob) in enumerate(zip(keys, blobs)):
        path = folder / f"{name}-{i}-{key}.navsrc"
        if not (path.is_file() and path.stat().st_size == len(blob)):
            tmp = path.with_suffix(f".tmp{os.getpid()}")
            tmp.write_bytes(blob)
            tmp.replace(path)
        paths.append((key, str(path.resolve())))
    return paths, Transfer(str(folder.resolve()), len(prepared), size, time.perf_counter() - t)


def run_chunks(client: Any, tasks: list[tuple[int, int, int]], seed: int, keep: tuple[int, ...], sources: list[Any] | None, jsons: list[str],
               chunk_fn: Any, transfer: Transfer, done: list[tuple[int, dict[str, Any]]], bar: Any) -> None:
    """Submit every task (``sources``: the shipped sources of a logged campaign, else
    ``chunk_fn(jsons[point], seed, start, count, 1, keep)`` runs a simulated one), collect the chunks into ``done`` as they finish (updating ``bar``)
    and fill ``transfer``'s worker figures; Ctrl-C cancels what has not run and re-raises."""
    from dask.distributed import as_completed

    def submit(p: int, s: int, c: int) -> Any:
        kept = tuple(k for k in keep if s <= k < s + c)
        if sources is not None:
            return client.submit(logged_chunk, *sources[p], int(seed), s, c, kept, pure=False)
        return client.submit(scenario_chunk, chunk_fn, jsons[p], int(seed), s, c, 1, kept, pure=False)

    futures = {submit(p, s, c): (p, s, c) for p, s, c in tasks}
    load = 0.0
    try:
        for fut in as_completed(futures):
            p, s, c = futures[fut]
            chunk, worker, rss, took = fut.result()
            done.append((p, chunk))
            transfer.peak_worker_rss[worker] = max(rss, transfer.peak_worker_rss.get(worker, 0))
            load = max(load, took)
            if bar is not None:
                bar.update(c)
    except KeyboardInterrupt:
        for fut in futures:
            fut.cancel()
        raise
    finally:
        transfer.workers = len(transfer.peak_worker_rss)
        transfer.ship_seconds += load
