"""Paper 004 (ultra-tight) speed: one ``liu2022`` run of the three variants, and the sweep.

    python benches/bench_liu2022.py            # one run, best of 7, beside its parts
    python benches/bench_liu2022.py --sweep    # also the 4 slopes x 2 C/N0 x 100 runs campaign

One run = simulation + 3 variants x (8 channels x 12 500 prefilter steps + 250 navigation
epochs), through ``_core.run_variants`` (the Rust loop, GIL released; records converted to
numpy). The reference in the same process is the channel prefilter alone (``navfdi.Prefilter``
steps are Python calls, so the core figure comes from ``cargo bench --bench gnss --
prefilter_step``); targets (issue): run <= 60 ms, sweep <= 60 s on 2 cores.
"""

from __future__ import annotations

import sys
import time

import navfdi
from navfdi import _core
from problem import best


def main() -> None:
    sc = navfdi.load_scenario("liu2022")
    js = [sc.base().with_value("ultra_tight.method", v).to_json() for v in ("m1", "m2", "m3")]
    _core.run_variants(js, 1, 0)
    t3 = best(lambda: _core.run_variants(js, 1, 0))
    print(f"liu2022, one run, three variants: {t3 * 1e3:.1f} ms (target <= 60 ms)")
    for v, j in zip(("m1", "m2", "m3"), js):
        print(f"  {v} alone (with its own simulation): {best(lambda j=j: _core.run_variants([j], 1, 0)) * 1e3:.1f} ms")
    if "--sweep" in sys.argv:
        from navfdi.montecarlo import montecarlo

        t0 = time.perf_counter()
        montecarlo(
            "liu2022",
            runs=100,
            progress=False,
            sweep={"faults[0].magnitude": ["0.05 m/s", "0.1 m/s", "0.2 m/s", "0.5 m/s"], "ultra_tight.cn0": ["48 dB-Hz", "28 dB-Hz"]},
        )
        print(f"sweep 4 slopes x 2 C/N0 x 100 runs x 3 variants: {time.perf_counter() - t0:.1f} s (target <= 60 s)")


if __name__ == "__main__":
    main()
