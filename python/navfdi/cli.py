"""The ``navfdi`` command line."""

from __future__ import annotations

from typing import Any

import argparse
import os
import sys
import traceback
import warnings
from pathlib import Path

from navfdi import _core

# The command line's own process: pyarrow (under pandas) allocates from the system heap, which
# gives freed memory back, rather than its default pool, which keeps it (13 MB more at the peak
# of a day-length `navfdi gnss`). A user's setting wins; the library alone leaves it alone.
os.environ.setdefault("ARROW_DEFAULT_MEMORY_POOL", "system")


def _seed(text: str) -> int:
    """argparse type: an integer seed in 0 .. 2**64 - 1."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if not 0 <= v < 2**64:
        raise argparse.ArgumentTypeError(f"{text} is outside 0 .. 2**64 - 1")
    return v


def _positive(text: str) -> int:
    """argparse type: a positive integer (``1000`` or ``1e3``)."""
    try:
        f = float(text)
        v = int(f)
    except (ValueError, OverflowError):
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive integer") from None
    if v != f or v < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive integer")
    return v


def _cn0_slope(text: str) -> float | str:
    """argparse type: ``auto`` or a C/N0 weighting slope in [0, ``_core.CN0_SLOPE_MAX``]
    (variance decades per 10 dB-Hz)."""
    if text == "auto":
        return text
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not 0.0 <= v <= _core.CN0_SLOPE_MAX:
        raise argparse.ArgumentTypeError(f"{text!r} is not a slope in [0, {_core.CN0_SLOPE_MAX:g}] or 'auto'")
    return v


def _keep_series(text: str) -> list[int]:
    """argparse type: comma-separated run indices."""
    out = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        try:
            out.append(int(part))
        except ValueError:
            raise argparse.ArgumentTypeError(f"{part!r} is not a run index; give comma-separated integers, e.g. 0,5,17") from None
    return out


def check_output_dir(out: str) -> Path:
    """Check, before any work, that ``out`` can be used as an output directory: not empty,
    not an existing file, and writable (or creatable under a writable parent). Creates
    nothing. Raises ``ValueError`` naming the problem."""
    if not out.strip():
        raise ValueError("--out: empty path; give a directory for the outputs")
    path = Path(out)
    if path.exists():
        if not path.is_dir():
            raise ValueError(f"--out {out}: exists and is not a directory")
        if not os.access(path, os.W_OK | os.X_OK):
            raise ValueError(f"--out {out}: directory is not writable")
        return path
    parent = path.absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise ValueError(f"--out {out}: {parent} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"--out {out}: cannot create it, {parent} is not writable")
    return path


def _one_line_warnings() -> None:
    def show(message, category, filename, lineno, file=None, line=None):  # noqa: ANN001
        print(f"navfdi: warning: {message}", file=sys.stderr)

    warnings.showwarning = show


def _headline_line(result: Any) -> str:
    """One line with the numbers that matter first (per variant for a scenario with
    variants): the navigation error and the deciding detections."""
    from navfdi._text import fit

    runs = getattr(result, "runs", None) or {"": result}
    parts = []
    for name, run in runs.items():
        head = run._headline()
        items = [f"{k} {v:.3g}" for k, v in list(head.items())[:3] if isinstance(v, (int, float))]
        parts.append((f"{name}: " if name else "") + ", ".join(items))
    return fit("headline — " + "; ".join(parts))


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``navfdi`` command; returns the process exit code.

    Every error is printed as one line ``navfdi: error: ...`` with exit code 2 (``--debug``
    prints the traceback instead); an interrupt (Ctrl-C) exits with 130.
    """
    parser = argparse.ArgumentParser(prog="navfdi", description="Fault detection and isolation for integrated navigation.")
    parser.add_argument("--version", action="version", version=f"navfdi {_core.__version__}")
    parser.add_argument("--debug", action="store_true", help="show Python tracebacks of errors")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="run the chi-square, SPRT and joint detectors on a simulated ramp and step fault")
    demo.add_argument("--seed", type=_seed, default=0, help="random seed (default 0)")
    demo.add_argument("--pf", type=float, default=1e-3, help="false-alarm probability (default 1e-3)")
    demo.add_argument("--pm", type=float, default=1e-3, help="missed-detection probability (default 1e-3)")
    run = sub.add_parser("run", help="simulate and filter a scenario; print per-fault tables and write outputs")
    run.add_argument("scenario", help="bundled scenario name (see `navfdi scenarios`) or a TOML file")
    run.add_argument("--seed", type=_seed, default=0, help="random seed (default 0)")
    run.add_argument("--out", default=None, help="output directory for events.csv, timeseries.parquet, summary.json and figures")
    run.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    run.add_argument("--set", action="append", default=[], metavar="PATH=VALUE", help='override a scenario field, e.g. --set "faults[0].magnitude=30 m" or --set "sensors[0].rate=2 Hz" (repeatable; the --sweep syntax with one value)')
    cal = sub.add_parser("calibrate", help="estimate a loosely coupled scenario's IMU noise, gyro bias, boresight (pitch, yaw) and IMU time offset from its own logs")
    cal.add_argument("scenario", help="bundled scenario name or a TOML file")
    cal.add_argument("--out", default=None, metavar="FILE.toml", help="write the scenario with the calibrated values (a TOML file scenario)")
    sc = sub.add_parser("scenarios", help="list the bundled scenarios, show or export one as TOML")
    show = sc.add_mutually_exclusive_group()
    show.add_argument("--show", metavar="NAME", default=None, help="print a bundled scenario's TOML")
    show.add_argument("--export", nargs=2, metavar=("NAME", "PATH"), default=None, help="write a bundled scenario's TOML to PATH (to edit and run with `navfdi run PATH`)")
    mc = sub.add_parser("montecarlo", help="Monte-Carlo campaign: runs × sweep points, run in parallel in Rust")
    mc.add_argument("scenario", help="bundled scenario name or a TOML file")
    mc.add_argument("--runs", type=_positive, required=True, help="runs per sweep point")
    mc.add_argument("--seed", type=_seed, default=0, help="campaign seed (default 0); run i uses (seed, i)")
    mc.add_argument("--sweep", action="append", default=[], metavar="PATH=v1,v2,...", help='vary a scenario field, e.g. --sweep "faults[0].magnitude=0.05 sigma/s,0.1 sigma/s" (repeatable: cartesian product)')
    where = mc.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_positive, default=None, help="threads in this process (default: all cores)")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS", help="run on a Dask cluster (pip install navfdi[dask])")
    mc.add_argument("--ship", default="scatter", metavar="scatter|DIR", help="with --scheduler and recorded logs: send each prepared log to every worker once (scatter, default) or write it to DIR, a directory every worker sees at that path, for each worker to read once")
    mc.add_argument("--out", default=None, help="directory for runs.parquet, summary.csv, campaign.json and plots")
    mc.add_argument("--keep-series", type=_keep_series, default=[], metavar="RUN,...", help="run indices whose time series to keep (written as series_pPOINT_rRUN.parquet)")
    mc.add_argument("--chunk-size", type=_positive, default=None, help="runs per chunk (default 16)")
    gn = sub.add_parser("gnss", help="single-point positioning with satellite FDE on a RINEX 3 observation file")
    gn.add_argument("obs", help="RINEX 3 observation file (plain or .gz)")
    gn.add_argument("nav", help="RINEX 3 navigation file with the broadcast ephemerides")
    gn.add_argument("--systems", default="G", help="systems to use: G (GPS), E (Galileo), C (BeiDou), J (QZSS), e.g. G,E (default G)")
    gn.add_argument("--mask", default="10 deg", help="elevation mask, e.g. '10 deg' (default 10 deg)")
    gn.add_argument("--alpha", type=float, default=0.01, help="false-alarm probability of the global test (default 0.01)")
    gn.add_argument("--k", type=float, default=None, help="w-test critical value (default: two-sided normal quantile of alpha)")
    gn.add_argument("--no-exclusion", action="store_true", help="weighted least squares only (the test is still reported)")
    gn.add_argument("--weighting", choices=["elevation", "rtklib", "cn0", "auto"], default="auto", help="pseudorange variance model: elevation (0.3^2 + 0.3^2/sin^2 el m^2), rtklib, cn0 (the elevation model times 10^(slope (ref - C/N0)/10), for low-cost receivers; see --cn0-slope) or auto (default: the one of elevation and cn0 whose fault-free statistics have the shape of a fitting model's; elevation on a file without C/N0)")
    gn.add_argument("--cn0-slope", type=_cn0_slope, default="auto", metavar="SLOPE|auto", help="variance decades per 10 dB-Hz of the cn0 model, in [0, 3] (1: the sigma-epsilon model; 0: no C/N0 term); auto (default): the slope that gives the clean residuals one spread at every C/N0, estimated from the file and used where above 1")
    gn.add_argument("--cn0-reference", type=float, default=45.0, metavar="DBHZ", help="C/N0 (dB-Hz) at which --weighting cn0 gives the elevation model (default 45)")
    gn.add_argument("--test", choices=["global", "wtest", "both", "auto"], default="global", help="what opens the exclusion loop: the global chi-square test (default), data snooping (the largest |w| against k0, alpha shared over the satellites: more powerful for one faulty satellite among many, less with few), both (each at alpha/2) or auto (per epoch the one of the two with the smaller minimal detectable bias)")
    gn.add_argument("--power", type=float, default=0.8, metavar="BETA0", help="power at which the minimal detectable biases are computed (default 0.8)")
    gn.add_argument("--noise", default=None, metavar="auto|FACTOR", help="scale every system's sigma: 'auto' (default) estimates the factor from the file without the injected faults (the whole file's statistic, or, when that is over twice the factor found with the faults excluded, the latter), or give a number (1: the sigma model as it is)")
    gn.add_argument("--noise-factor", action="append", default=[], metavar="SYS=F", help="factor on a system's sigma, e.g. C=3 (repeatable)")
    gn.add_argument("--code", action="append", default=[], metavar="SYS=CODE", help="force a system's pseudorange code, e.g. E=C1X (repeatable; default: the first of the documented priority the file holds)")
    gn.add_argument("--integrity", default=None, metavar="ALLOCATION", help="add protection levels (ARAIM and snapshot RAIM) and the integrity state per epoch with this allocation: lpv200, or an allocation file (TOML: [allocation] probabilities and tol_pl, [limits] hal/val/emt, [ism]; absent keys keep LPV-200's; docs/integrity.md)")
    gn.add_argument("--fault", action="append", default=[], metavar="SAT:SHAPE:SIZE:START:END", help="inject a fault, e.g. G13:step:20m:100s:200s or G29:ramp:0.5m/s:100s:300s (times from the first epoch; repeatable)")
    truth = gn.add_mutually_exclusive_group()
    truth.add_argument("--truth", default=None, metavar="LAT,LON,H", help="reference position (deg, deg, m) for the error statistics")
    truth.add_argument("--truth-file", default=None, metavar="FILE", help="file whose first line is 'LAT LON H' (deg, deg, m)")
    gn.add_argument("--out", default=None, help="directory for solution.csv, satellites.parquet, summary.json and figures")
    gn.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    args = parser.parse_args(argv)
    _one_line_warnings()
    try:
        return _dispatch(args)
    except BrokenPipeError:
        # The reader went away (e.g. `navfdi run … | head`): stop quietly, like other tools.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141
    except KeyboardInterrupt:
        print("navfdi: interrupted", file=sys.stderr)
        return 130
    except Exception as e:  # noqa: BLE001 - the CLI turns every error into one line
        if args.debug:
            traceback.print_exc()
        else:
            print(f"navfdi: error: {_describe(e)}", file=sys.stderr)
        return 2


def _noise_scale(v: str | None) -> float | str:
    """``--noise``: ``auto`` (also without the option) or a positive factor."""
    if v is None:
        return "auto"
    if v.strip().lower() == "auto":
        return "auto"
    try:
        return float(v)
    except ValueError:
        raise ValueError(f"--noise {v!r}: 'auto' or a positive number") from None


def _describe(e: BaseException) -> str:
    """One line for an exception: the message, prefixed where the type says more."""
    msg = " ".join(str(e).split()) or type(e).__name__
    if isinstance(e, MemoryError):
        return msg if "needs about" in msg else f"out of memory: {msg}"
    if isinstance(e, ValueError):
        return msg
    if isinstance(e, OSError):
        return f"{e.strerror or msg}: {e.filename}" if e.filename else msg
    return f"{type(e).__name__}: {msg} (this is a bug in navfdi; --debug shows the traceback)"


def _dispatch(args: argparse.Namespace) -> int:
    if getattr(args, "out", None) is not None:
        check_output_dir(args.out)
    if args.command == "demo":
        from navfdi.demo import report

        print(report(seed=args.seed, pf=args.pf, pm=args.pm))
    elif args.command == "calibrate":
        from navfdi.calibrate import calibrate, write_calibrated

        c = calibrate(args.scenario)
        print("\n".join(c.lines()))
        if args.out:
            src = Path(args.scenario)
            if src.suffix != ".toml":
                from navfdi._bundled import exported_toml

                tmp = Path(args.out)
                if tmp.exists():
                    raise ValueError(f"--out: {tmp} exists; remove it or choose another path")
                tmp.write_text(exported_toml(args.scenario), encoding="utf-8")
                src = tmp
            elif Path(args.out).exists() and Path(args.out).resolve() != src.resolve():
                raise ValueError(f"--out: {args.out} exists; remove it or choose another path")
            print(f"wrote {write_calibrated(src, c, args.out)} (run it with: navfdi run {args.out})")
    elif args.command == "scenarios":
        from navfdi._bundled import exported_toml
        from navfdi.scenario import bundled_scenarios, bundled_toml, load_scenario

        if args.show:
            print(bundled_toml(args.show), end="")
        elif args.export:
            name, path = args.export
            text = exported_toml(name)
            target = Path(path)
            if target.is_dir():
                target = target / f"{name}.toml"
            if target.exists():
                raise ValueError(f"--export: {target} exists; remove it or choose another path")
            target.write_text(text, encoding="utf-8")
            print(f"wrote {target} (run it with: navfdi run {target})")
        else:
            from navfdi._text import fit

            names = bundled_scenarios()
            width = max((len(n) for n in names), default=0)
            for name in names:
                desc = load_scenario(name).raw.get("description", "")
                print(fit(f"{name:<{width}}  {desc}"))
            print("\nnavfdi scenarios --show NAME prints one; --export NAME PATH writes it to edit.")
    elif args.command == "run":
        from navfdi._errors import ScenarioError
        from navfdi.montecarlo import parse_sweep
        from navfdi.runs import run_scenario
        from navfdi.scenario import load_scenario

        scenario = load_scenario(args.scenario)
        sets = parse_sweep(args.set, "--set")
        for path, vals in sets.items():
            if len(vals) != 1:
                raise ScenarioError(f"--set {path}: one value expected, got {len(vals)} ({', '.join(map(str, vals))}); use navfdi montecarlo --sweep for several")
        if sets:
            scenario = scenario.with_values({p: v[0] for p, v in sets.items()})
        result = run_scenario(scenario, seed=args.seed)
        print(f"scenario {result.scenario.name} ({result.scenario.source}), seed {args.seed}")
        print(_headline_line(result) + "\n")
        print(result.format_tables(), end="")
        if args.out:
            paths = result.write(args.out, figures=not args.no_figures)
            print("\n" + _wrote(paths, args.out))
        else:
            print(f"\nnothing written: add --out DIR for events.csv, timeseries.parquet, errors.csv, summary.json and figures")
    elif args.command == "montecarlo":
        return _montecarlo(args)
    elif args.command == "gnss":
        return _gnss(args)
    return 0


def _wrote(paths: list[Path], out: str) -> str:
    """``wrote N files to OUT/: a, b, …`` wrapped at 100 characters."""
    from navfdi._text import fit

    return fit(f"wrote {len(paths)} files to {out}/: " + ", ".join(p.name for p in paths))


def _gnss(args: argparse.Namespace) -> int:
    from navfdi import units
    from navfdi.gnss import GnssFault, gnss_solve, read_truth_file

    mask = units.parse(args.mask if " " in args.mask.strip() else f"{args.mask} deg", "angle", "--mask")
    faults = [GnssFault.parse(f, "--fault") for f in args.fault]
    truth = read_truth_file(args.truth_file) if args.truth_file else args.truth
    factors = {}
    for item in args.noise_factor:
        sys_, _, val = item.partition("=")
        try:
            factors[sys_.strip().upper()] = float(val)
        except ValueError:
            raise ValueError(f"--noise-factor {item!r}: expected SYS=FACTOR, e.g. C=3") from None
    codes = {}
    for item in args.code:
        sys_, sep, val = item.partition("=")
        if not sep or not sys_.strip() or not val.strip():
            raise ValueError(f"--code {item!r}: expected SYS=CODE, e.g. E=C1X")
        codes[sys_.strip().upper()] = val.strip()
    sol = gnss_solve(
        args.obs,
        args.nav,
        systems=args.systems,
        mask_deg=mask * 180 / 3.141592653589793,
        alpha=args.alpha,
        k=args.k,
        exclude=not args.no_exclusion,
        weighting=args.weighting,
        cn0_reference=args.cn0_reference,
        cn0_slope=args.cn0_slope,
        faults=faults,
        noise_factors=factors,
        codes=codes,
        noise_scale=_noise_scale(args.noise),
        test=args.test,
        power=args.power,
        truth=truth,
        progress=sys.stderr.isatty(),
        integrity=args.integrity,
    )
    print(sol.format_summary(), end="")
    if args.out:
        paths = sol.write(args.out, figures=not args.no_figures)
        print(_wrote(paths, args.out))
    else:
        print("nothing written: add --out DIR for solution.csv, satellites.parquet, summary.json and figures")
    return 0


def _probe_scheduler(address: str) -> None:
    """Open and close one TCP connection to a ``tcp://host:port`` Dask scheduler address.

    A refused or unroutable address fails here at once (Dask's client retries it for its whole
    10 s timeout); other address schemes are left to Dask. Raises OSError when unreachable.
    """
    import socket
    from urllib.parse import urlsplit

    parts = urlsplit(address)
    if parts.scheme != "tcp" or not parts.hostname or parts.port is None:
        return
    with socket.create_connection((parts.hostname, parts.port), timeout=5.0):
        pass


def _montecarlo(args: argparse.Namespace) -> int:
    from navfdi.montecarlo import montecarlo, parse_sweep

    sweep = parse_sweep(args.sweep)
    keep = args.keep_series
    client = None
    if args.scheduler:
        try:
            from dask.distributed import Client
        except ImportError:
            print("navfdi: error: --scheduler needs Dask: pip install 'navfdi[dask]'", file=sys.stderr)
            return 2
        try:
            _probe_scheduler(args.scheduler)
            client = Client(args.scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as e:
            raise ValueError(f"--scheduler {args.scheduler}: cannot reach the Dask scheduler ({' '.join(str(e).split())})") from None
    camp = montecarlo(args.scenario, runs=args.runs, seed=args.seed, sweep=sweep, workers=args.workers, client=client, chunk_size=args.chunk_size, keep_series=keep, ship=args.ship)
    print(camp.format_table(), end="")
    if camp.transfer is not None:
        print("\n" + camp.transfer.line())
    if args.out:
        paths = camp.write(args.out)
        import pandas as pd

        from navfdi.runs import ERROR_COLUMNS

        for (p, r), rec in camp.series.items():
            cols = {"t": rec["t"], **{f"error.{c}": rec["error"][:, i] for i, c in enumerate(ERROR_COLUMNS)}}
            for s in rec["subfilters"]:
                cols[f"{s['sensor']}.isolated"] = s["isolated"]
                for d in s["detectors"]:
                    for k in ("statistic", "threshold", "alarm"):
                        cols[f"{s['sensor']}.{d['name']}.{k}"] = d[k]
            path = Path(args.out) / f"series_p{p}_r{r}.parquet"
            pd.DataFrame(cols).to_parquet(path, index=False)
            paths.append(path)
        print("\n" + _wrote(paths, args.out) + (" (partial campaign)" if camp.partial else ""))
    else:
        print("\nnothing written: add --out DIR for runs.parquet, summary.csv, campaign.json and plots")
    if camp.partial:
        print("navfdi: interrupted; the finished runs are kept (marked partial)", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
