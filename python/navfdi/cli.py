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
    args = parser.parse_args(argv)
    try:
        if args.command == "demo":
            from navfdi.demo import report

            print(report(seed=args.seed, pf=args.pf, pm=args.pm))
    except ValueError as e:
        print(f"navfdi: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
