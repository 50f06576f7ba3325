"""The ``navfdi`` command line."""

from __future__ import annotations

import argparse
import sys

from navfdi import _core


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``navfdi`` command; returns the process exit code."""
    parser = argparse.ArgumentParser(prog="navfdi", description="Fault detection and isolation for integrated navigation.")
    parser.add_argument("--version", action="version", version=f"navfdi {_core.__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="run the chi-square, SPRT and joint detectors on a simulated ramp and step fault")
    demo.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    demo.add_argument("--pf", type=float, default=1e-3, help="false-alarm probability (default 1e-3)")
    demo.add_argument("--pm", type=float, default=1e-3, help="missed-detection probability (default 1e-3)")
    run = sub.add_parser("run", help="simulate and filter a scenario; print per-fault tables and write outputs")
    run.add_argument("scenario", help="bundled scenario name (see `navfdi scenarios`) or a TOML file")
    run.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    run.add_argument("--out", default=None, help="output directory for events.csv, timeseries.parquet, summary.json and figures")
    run.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    sub.add_parser("scenarios", help="list the bundled scenarios")
    args = parser.parse_args(argv)
    try:
        if args.command == "demo":
            from navfdi.demo import report

            print(report(seed=args.seed, pf=args.pf, pm=args.pm))
        elif args.command == "scenarios":
            from navfdi.scenario import bundled_scenarios, load_scenario

            for name in bundled_scenarios():
                desc = load_scenario(name).raw.get("description", "")
                print(f"{name:<14} {desc}")
        elif args.command == "run":
            from navfdi.federated import run_scenario

            result = run_scenario(args.scenario, seed=args.seed)
            print(f"scenario {result.scenario.name} ({result.scenario.source}), seed {args.seed}\n")
            print(result.format_tables(), end="")
            if args.out:
                paths = result.write(args.out, figures=not args.no_figures)
                print(f"\nwrote {len(paths)} files to {args.out}/: " + ", ".join(p.name for p in paths))
    except ValueError as e:
        print(f"navfdi: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
