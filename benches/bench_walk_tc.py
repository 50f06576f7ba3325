"""Speed of the tight filter on the recorded walk.

    python benches/bench_walk_tc.py            # prints the figures of benches/README.md
    python -m pytest benches/bench_walk_tc.py --benchmark-enable

* the whole walk (20 455 IMU samples, 536 epochs with 8–10 GPS + Galileo satellites) through
  the strapdown INS, the 18-state filter and the innovation FDE, in process (files already
  read): ``LoggedSource.run`` with one variant, GIL released;
* the tight update with FDE per GNSS epoch: the run minus the same run with every GNSS epoch
  removed (an outage over the whole walk: mechanisation and propagation only), per epoch;
* the filter protection levels: the same run with ``[tight.integrity]`` (the bank of
  sub-filters, one per satellite, the separation test and the levels), with white range
  errors and with per-satellite range-error states (the walk's fitted a = 0.49, τ = 6.7 s),
  per GNSS epoch and as a ratio to the plain tight epoch (whole run per epoch, and the GNSS
  part: the run minus the INS-only run);
* 200 Monte-Carlo runs of ``walk_tc`` (3 variants, faults drawn per run) on all cores.
"""

from __future__ import annotations

import time

import numpy as np

from bench_drive_lc import best
from navfdi import load_scenario, logs, montecarlo


def _setup():
    sc = load_scenario("walk_tc").with_value("faults", [])
    return sc, logs.logged_source(sc)


def main() -> None:
    sc, src = _setup()
    for name, v in sc.variants():
        run = best(lambda: src.run([v.to_json()]), 9)
        print(f"whole walk, {name}: {run * 1e3:.1f} ms (target 500 ms)")
    inn = sc.variants()[0][1]
    blind = inn.with_value("sensors[0].outages", [["-1 s", "1000 s"]], create=True)
    src_blind = logs.logged_source(blind)
    full = best(lambda: src.run([inn.to_json()]), 9)
    ins_only = best(lambda: src_blind.run([blind.to_json()]), 9)
    rec = src.run([inn.to_json()])[0]
    used = np.asarray(rec["satellites"]["used"])
    n = int((used > 0).sum())
    print(f"tight update with FDE: ({full * 1e3:.1f} − {ins_only * 1e3:.1f}) ms / {n} epochs = {(full - ins_only) / n * 1e6:.1f} µs per epoch at {used[used > 0].mean():.1f} satellites (target 15 µs at 25)")
    epochs = len(rec["t"])
    for label, extra in (("white range errors", {}), ("range-error states", {"tight.range_states": {"fraction": 0.49, "tau": "6.7 s"}})):
        pl = inn.with_values({"tight.integrity": {}, **extra}, create=True)
        src_pl = logs.logged_source(pl)
        t_pl = best(lambda: src_pl.run([pl.to_json()]), 5)
        print(f"filter PL ({label}): {t_pl * 1e3:.1f} ms = {t_pl / epochs * 1e6:.0f} µs per epoch, {t_pl / full:.1f}x the plain tight run; "
              f"GNSS part {(t_pl - ins_only) / n * 1e6:.0f} µs = {(t_pl - ins_only) / (full - ins_only):.1f}x the plain tight update (target 20x a plain tight epoch)")
    t = time.perf_counter()
    montecarlo("walk_tc", runs=200, seed=0, progress=False)
    print(f"200 Monte-Carlo runs x 3 variants: {time.perf_counter() - t:.1f} s")


def test_walk_filter(benchmark) -> None:
    sc, src = _setup()
    v = sc.variants()[0][1].to_json()
    recs = benchmark(src.run, [v])
    assert np.isfinite(recs[0]["nav"][-1, 0])


if __name__ == "__main__":
    main()
