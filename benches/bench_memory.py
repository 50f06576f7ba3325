"""Peak memory of `navfdi gnss` on a day-length observation file, beside RTKLIB's `rnx2rtkp`
on the same file (a full-day 30 s file ≤ 150 MB peak).

    python benches/bench_memory.py

No full-day file is bundled, so one is made: the bundled rover file's 301 epochs (1 Hz,
57 satellites of five systems, 15–20 observation types each) repeated ten times, each copy's
epoch times moved on by 301 s, gives 3 010 epochs and 35 MB of RINEX 3 text, more than a
30 s day (2 880 epochs) of a geodetic station. Its pseudoranges repeat, so the solutions
are not meaningful (the global test alarms): this measures reading and solving memory only.
Both programs run as processes (GPS + Galileo, C1C, 10° mask), their peak resident set size
from ``/usr/bin/time -v``; the Python interpreter with navfdi's imports (numpy and the core:
pandas is imported where tables are built) alone is measured too.
"""

from __future__ import annotations

import datetime as dt
import gzip
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "rinex"


def day_file(path: Path, copies: int = 10) -> int:
    """Write the repeated rover file to ``path``; returns its number of epochs."""
    lines = gzip.open(DATA / "rover.obs.gz", "rt").read().split("\n")
    end = next(i for i, line in enumerate(lines) if "END OF HEADER" in line)
    epochs: list[list[str]] = []
    for line in lines[end + 1 :]:
        if line.startswith(">"):
            epochs.append([line])
        elif epochs and line:
            epochs[-1].append(line)
    with path.open("w") as out:
        out.write("\n".join(lines[: end + 1]) + "\n")
        for k in range(copies):
            for e in epochs:
                f = e[0].split()
                t = dt.datetime(*map(int, f[1:6])) + dt.timedelta(seconds=float(f[6]) + k * len(epochs))
                sec = t.second + t.microsecond / 1e6
                out.write(f"> {t:%Y %m %d %H %M}{sec:11.7f}{e[0][29:]}\n" + "\n".join(e[1:]) + "\n")
    return copies * len(epochs)


def peak_mb(cmd: list[str]) -> float:
    """Peak resident set size (MB) of a command, by ``/usr/bin/time -v``."""
    out = subprocess.run(["/usr/bin/time", "-v", *cmd], capture_output=True, text=True, check=True)
    kb = next(int(line.split(":")[1]) for line in out.stderr.splitlines() if "Maximum resident set size" in line)
    return kb / 1024


def main() -> None:
    if not Path("/usr/bin/time").exists():
        sys.exit("needs /usr/bin/time (Debian package 'time')")
    with tempfile.TemporaryDirectory() as tmp:
        obs = Path(tmp) / "day.obs"
        n = day_file(obs)
        size = obs.stat().st_size / 1e6
        base = peak_mb([sys.executable, "-c", "import navfdi.cli"])
        ours = peak_mb([sys.executable, "-m", "navfdi", "gnss", str(obs), str(DATA / "base.nav"), "--systems", "G,E"])
        print(f"day file: {n} epochs, {size:.1f} MB of RINEX 3")
        print(f"navfdi gnss: {ours:.0f} MB peak (the interpreter with navfdi's imports alone: {base:.0f} MB)")
        if shutil.which("rnx2rtkp"):
            rtk = peak_mb(["rnx2rtkp", "-p", "0", "-m", "10", "-sys", "G,E", "-o", str(Path(tmp) / "out.pos"), str(obs), str(DATA / "base.nav")])
            print(f"rnx2rtkp: {rtk:.0f} MB peak")
        else:
            print("rnx2rtkp: not installed (Debian package 'rtklib')")


if __name__ == "__main__":
    main()
