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

A geodetic station's day is made too, since real station files carry what the rover file does
not (four systems with GLONASS and BeiDou, 9–15 observation types per system with carrier
phase and signal strength on three to five frequencies, a long header): the bundled ACOR cut
(EUREF A Coruña, RINEX 3.04, 30 s, 25 epochs, 38 satellites) repeated to 2 875 epochs (a full
day at 30 s), its epoch times moved to the rover's day so that the bundled navigation file
has ephemerides for them (the geometry is then not ACOR's: reading and solving memory only).
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


def day_file(path: Path, copies: int = 10, source: Path = DATA / "rover.obs.gz", step: float | None = None,
             start: dt.datetime | None = None) -> int:
    """Write ``copies`` copies of the observation file ``source`` to ``path``, copy k's epoch
    times moved on by k × ``step`` s (default: its number of epochs, a 1 Hz file's span) and
    the whole moved to begin at ``start`` (default: where it begins); returns the number of
    epochs."""
    lines = gzip.open(source, "rt").read().split("\n")
    end = next(i for i, line in enumerate(lines) if "END OF HEADER" in line)
    epochs: list[list[str]] = []
    for line in lines[end + 1 :]:
        if line.startswith(">"):
            epochs.append([line])
        elif epochs and line:
            epochs[-1].append(line)
    step = float(len(epochs)) if step is None else step

    def when(head: str) -> dt.datetime:
        f = head.split()
        return dt.datetime(*map(int, f[1:6])) + dt.timedelta(seconds=float(f[6]))

    shift = (start - when(epochs[0][0])) if start is not None else dt.timedelta(0)
    t0 = when(epochs[0][0]) + shift
    first = f"{t0.year:6d}{t0.month:6d}{t0.day:6d}{t0.hour:6d}{t0.minute:6d}{t0.second + t0.microsecond / 1e6:13.7f}"
    header = [first + line[43:] if "TIME OF FIRST OBS" in line else line
              for line in lines[: end + 1] if "TIME OF LAST OBS" not in line]
    with path.open("w") as out:
        out.write("\n".join(header) + "\n")
        for k in range(copies):
            for e in epochs:
                t = when(e[0]) + shift + dt.timedelta(seconds=k * step)
                sec = t.second + t.microsecond / 1e6
                out.write(f"> {t:%Y %m %d %H %M}{sec:11.7f}{e[0][29:]}\n" + "\n".join(e[1:]) + "\n")
    return copies * len(epochs)


def stopped_peak_mb(cmd: list[str]) -> tuple[float, bool]:
    """Peak resident set size (MB) of a command, by ``/usr/bin/time -v``, and whether it
    stopped with ``navfdi gnss``'s "no epoch solved" error (a day file whose geometry is not a
    receiver's: it is read and solved, its tables built, and the run stops before its summary
    and outputs); any other failure raises."""
    out = subprocess.run(["/usr/bin/time", "-v", *cmd], capture_output=True, text=True)
    if out.returncode and "no epoch solved" not in out.stderr:
        raise subprocess.CalledProcessError(out.returncode, cmd, out.stdout, out.stderr)
    kb = next(int(line.split(":")[1]) for line in out.stderr.splitlines() if "Maximum resident set size" in line)
    return kb / 1024, bool(out.returncode)


def peak_mb(cmd: list[str]) -> float:
    """Peak resident set size (MB) of a command that must succeed."""
    mb, stopped = stopped_peak_mb(cmd)
    if stopped:
        raise RuntimeError(f"{' '.join(cmd)}: no epoch solved")
    return mb


def main() -> None:
    if not Path("/usr/bin/time").exists():
        sys.exit("needs /usr/bin/time (Debian package 'time')")
    acor = DATA.parent / "rinex_formats" / "ACOR00ESP_R_20213550000_01D_30S_MO.rnx.gz"
    with tempfile.TemporaryDirectory() as tmp:
        base = peak_mb([sys.executable, "-c", "import navfdi.cli"])
        print(f"the interpreter with navfdi's imports alone: {base:.0f} MB")
        days = {
            "bundled rover file (301 epochs at 1 Hz: the fixed footprint)": None,
            "rover x10 (1 Hz, 57 satellites, 2 systems used of 5)": lambda p: day_file(p),
            "ACOR station day (30 s, 4 systems, 9-15 types)": lambda p: day_file(p, 115, acor, 750.0, dt.datetime(2024, 6, 24, 0, 0)),
        }
        for label, make in days.items():
            obs = Path(tmp) / "day.obs"
            if make is None:
                obs, n = DATA / "rover.obs.gz", 301
            else:
                n = make(obs)
            size = obs.stat().st_size / 1e6
            # The σ model as given: the repeated files' geometry is not a receiver's, so the
            # default's estimates would call their residuals what they are — not code noise
            # (an error on the 1 Hz copies). The default's peak is measured on the real file.
            cmd = [sys.executable, "-m", "navfdi", "gnss", str(obs), str(DATA / "base.nav"), "--systems", "G,E", "--weighting", "elevation", "--noise", "1"]
            summary, stopped = stopped_peak_mb(cmd)
            if stopped:
                line = (f"{label}: {n} epochs, {size:.1f} MB — navfdi gnss {summary:.0f} MB peak, read, solved and tabled (no epoch has a "
                        "solution on this geometry, so the run stops there with its error: no summary or outputs)")
            else:
                written = peak_mb([*cmd, "--out", str(Path(tmp) / "out")])
                line = f"{label}: {n} epochs, {size:.1f} MB — navfdi gnss {summary:.0f} MB peak (summary only), {written:.0f} MB (--out: tables, figures, report)"
            if make is None:
                default = peak_mb(cmd[:-4])
                line += f"; the default (sigma model estimated from the file) {default:.0f} MB"
            if shutil.which("rnx2rtkp"):
                rtk = peak_mb(["rnx2rtkp", "-p", "0", "-m", "10", "-sys", "G,E", "-o", str(Path(tmp) / "out.pos"), str(obs), str(DATA / "base.nav")])
                line += f"; rnx2rtkp {rtk:.0f} MB"
            print(line)


if __name__ == "__main__":
    main()
