"""Peak memory and wall time of the log commands on long 100 Hz logs, against a bare Parquet read.

    python benchmarks/bench_memory.py [--hours 20,76] [--rate-hz 100] [--dir DIR] [--commands navigate,truth,...]
    python benchmarks/bench_memory.py --quick          # 17 h and 34 h at 100 Hz

For every log length (hours, comma separated; 76 h at 100 Hz = 27.4 M samples is the target case) a log is
simulated once with the package's own simulator (`gyrodrift.ins.simulate`, written to ``DIR/<h>h/imu.parquet``
and kept there for the next run when ``--dir`` is given). Then, each in a fresh Python process:

* ``read``: the bare pyarrow read of the columns `navigate` reads (``t_s``, the six increments, ``temp_c`` and
  the three true attitude columns), ``ParquetFile.iter_batches`` of 100 000 rows with every column converted to
  numpy, pyarrow's defaults;
* ``read-nobuf``: the same with ``pre_buffer=False`` (what `gyrodrift.logs` does: with pre-buffering pyarrow
  keeps every column chunk read until the file is closed, so the bare read itself grows with the file);
* ``navigate LOG --out DIR`` (whole log, state every 1 s);
* ``truth LOG --hours H-4`` (alignment + 72 h at 76 h: two reads of 2 and 3 navigators, more if refined);
* ``features LOG --out runs.csv`` (alignment + 12 h: reads the first 16 h only, whatever the log length);
* ``evaluate LOG --drift-deg-h 0.003 --hours H-4 --out DIR``.

Each child runs the command through the CLI entry point (`gyrodrift.cli.main`) and reports its own peak
resident set size (``resource.getrusage(RUSAGE_SELF).ru_maxrss``) and wall time. The report prints, per
command and length, the peak RSS [MB] and the time [s], and the ratio of ``navigate`` to the bare reads of the
same log in the same run (target: <= 2.5). Targets (issue 8): peak RSS independent of the log length and
<= 400 MB at 76 h. With ``--repeat N`` each command runs N times and the best time is kept (a shared machine
only ever makes a run slower). Never fails on a slow machine: it only reports.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CHILD = r"""
import json, resource, sys, time
args, report = json.loads(sys.argv[1]), sys.argv[2]
t0 = time.perf_counter()
if args[0] in ("read", "read-nobuf"):
    import numpy as np
    import pyarrow.parquet as pq
    cols = ["t_s", "dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s", "dv_z_m_s", "temp_c",
            "true_pitch_deg", "true_roll_deg", "true_yaw_deg"]
    n = 0
    pf = pq.ParquetFile(args[1], pre_buffer=args[0] == "read")
    for batch in pf.iter_batches(batch_size=100_000, columns=cols):
        arrays = [np.asarray(batch.column(i).to_numpy(zero_copy_only=False), dtype=np.float64) for i in range(11)]
        n += len(arrays[0])
else:
    from gyrodrift.cli import main
    try:
        main(args, standalone_mode=False)
    except SystemExit as exc:
        if exc.code:
            raise
wall = time.perf_counter() - t0
rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
with open(report, "w") as fh:
    json.dump({"wall_s": wall, "rss_mb": rss_mb}, fh)
"""


def _scenario(hours: float, rate_hz: float):
    from gyrodrift.ins import Scenario

    # A paper-like run: reciprocating table, noise on gyros and accelerometers, warming up, tilted base.
    return Scenario.from_dict(
        {
            "run": {"duration_h": hours, "rate_hz": rate_hz, "seed": 1},
            "gyro": {"bias_deg_h": [0.005, -0.004, 0.003], "arw_deg_rth": 0.0005},
            "accel": {"bias_ug": [30.0, -20.0, 10.0], "vrw_ug_rthz": 5.0},
            "temperature": {"start_c": 20.0, "end_c": 35.0, "tau_h": 2.0},
            "attitude": {"pitch_deg": 0.3, "yaw_deg": 40.0},
        },
        source="<bench-memory>",
    )


def _log(folder: Path, hours: float, rate_hz: float) -> Path:
    from gyrodrift.ins import simulate

    path = folder / f"{hours:g}h" / "imu.parquet"
    if not path.exists():
        t0 = time.perf_counter()
        simulate(_scenario(hours, rate_hz), out_dir=path.parent)
        print(f"simulated {path} ({path.stat().st_size / 1e6:.0f} MB) in {time.perf_counter() - t0:.1f} s")
    return path


def _run(args: list[str]) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "report.json"
        done = subprocess.run(
            [sys.executable, "-c", CHILD, json.dumps(args), str(report)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, "MPLBACKEND": "Agg"},
        )
        if done.returncode != 0:
            return {"error": done.stderr.strip().splitlines()[-1] if done.stderr.strip() else f"exit {done.returncode}"}
        return json.loads(report.read_text())


def _command(name: str, log: Path, hours: float, out: Path) -> list[str]:
    nav_h = f"{hours - 4.0:g}"
    if name in ("read", "read-nobuf"):
        return [name, str(log)]
    if name == "navigate":
        return ["navigate", str(log), "--out", str(out / "nav"), "--quiet"]
    if name == "truth":
        return ["truth", str(log), "--hours", nav_h, "--quiet"]
    if name == "features":
        return ["features", str(log), "--out", str(out / "runs.csv"), "--quiet"]
    if name == "evaluate":
        return ["evaluate", str(log), "--drift-deg-h", "0.003", "--hours", nav_h, "--out", str(out / "ev"), "--quiet"]
    raise ValueError(f"unknown command {name!r}")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", default="20,76", help="log lengths [h], comma separated (each >= 16)")
    ap.add_argument("--rate-hz", type=float, default=100.0)
    ap.add_argument("--quick", action="store_true", help="17 h and 34 h (about a minute)")
    ap.add_argument("--dir", type=Path, default=None, help="keep the simulated logs here (reused next time)")
    ap.add_argument("--commands", default="read,read-nobuf,navigate,truth,features,evaluate")
    ap.add_argument("--repeat", type=int, default=1, help="runs per command: the best time, the largest RSS")
    args = ap.parse_args(argv)
    lengths = [17.0, 34.0] if args.quick else [float(h) for h in args.hours.split(",")]
    commands = args.commands.split(",")
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.dir or Path(tmp)
        results: dict[tuple[str, float], dict] = {}
        for hours in lengths:
            log = _log(folder, hours, args.rate_hz)
            n = int(round(hours * 3600 * args.rate_hz))
            print(f"\n{hours:g} h at {args.rate_hz:g} Hz ({n / 1e6:.1f} M samples):")
            for name in commands:
                out = Path(tmp) / "out" / f"{hours:g}-{name}"
                out.mkdir(parents=True, exist_ok=True)
                runs = [_run(_command(name, log, hours, out)) for _ in range(args.repeat)]
                good = [r for r in runs if "error" not in r]
                r = (
                    runs[0]
                    if not good
                    else {"wall_s": min(x["wall_s"] for x in good), "rss_mb": max(x["rss_mb"] for x in good)}
                )
                results[name, hours] = r
                if "error" in r:
                    print(f"  {name:9s} FAILED: {r['error']}")
                else:
                    print(f"  {name:9s} peak RSS {r['rss_mb']:7.0f} MB   wall {r['wall_s']:7.2f} s")
            nav = results.get(("navigate", hours), {})
            for ref in ("read", "read-nobuf"):
                read = results.get((ref, hours), {})
                if "wall_s" in nav and "wall_s" in read:
                    print(f"  navigate / {ref}: {nav['wall_s'] / read['wall_s']:.2f} x (target <= 2.5)")
        print("\npeak RSS [MB] by length: " + ", ".join(f"{h:g} h" for h in lengths))
        for name in commands:
            cells = [results[name, h].get("rss_mb") for h in lengths]
            print(f"  {name:9s} " + "  ".join("failed" if c is None else f"{c:7.0f}" for c in cells))


if __name__ == "__main__":
    main()
