"""Campaign throughput: runs per hour per core, where the time goes, the floor, LocalCluster scaling, memory.

    python benchmarks/bench_campaign.py [--campaign examples/campaigns/default.toml] [--profile-runs 4]
                                        [--cluster-runs 40] [--memory-hours 24,48,72,144] [--skip-cluster]

1. Per run (`gyrodrift.campaign.process_run` in this process, `--profile-runs` runs of the campaign): wall and
   CPU time per stage (align, passes = 12 h features + 72 h truth, smoother, noise-free twin), and runs per
   hour per core from the CPU time (a loaded machine stretches wall time, not CPU time).
2. The floor: every navigation pass of a run is counted (navigator sample updates, and the samples the
   simulator generates for each read of the on-the-fly log); the navigator's and the simulator's samples/s are
   measured in this same run on the campaign's first scenario; floor = updates / navigator rate + simulated
   samples / simulator rate. The ratio run time / floor says how much is overhead.
3. `--cluster-runs` runs on a dask LocalCluster with 1 worker, then with 2 (fresh folders): speed-up, parallel
   efficiency (speed-up / 2), and the two stores compared row by row (timings and worker names aside).
4. Resident memory of one worker process (a fresh subprocess per point, sampled every 10 ms) before and during
   one run whose truth span is each of `--memory-hours` (log = 4 h alignment + that span): memory vs run length.

The machine is shared: numbers are for this run only; the ratios in one run are what matter. Never fails on a
slow machine: it only reports.
"""

from __future__ import annotations

import argparse
import json
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gyrodrift.campaign import load_campaign, process_run, read_runs, run_campaign

VOLATILE = {"worker", "t_align_s", "t_passes_s", "t_smoother_s", "t_twin_s", "t_total_s"}


def count_passes():
    """Wrap the streaming engine so every navigation pass is counted: (navigator updates, simulated samples)."""
    import gyrodrift.procedure.passes as passes

    counts = {"nav_updates": 0, "sim_samples": 0, "reads": 0}
    original = passes.run_navigators

    def counting(log, navs, *, n_samples, start=0, **kw):
        counts["nav_updates"] += n_samples * len(navs)
        counts["sim_samples"] += start + n_samples
        counts["reads"] += 1
        return original(log, navs, n_samples=n_samples, start=start, **kw)

    passes.run_navigators = counting
    return counts


def component_rates(campaign) -> dict[str, float]:
    """Navigator and simulator samples/s on the campaign's first scenario (1 h, best of 3)."""
    from gyrodrift import _core
    from gyrodrift.ins.simulate import iter_core_chunks
    from gyrodrift.logs import ImuLog
    from gyrodrift.procedure import align_log

    scn = campaign.scenario(0)
    n = int(round(3600 * scn.run.rate_hz))
    best_sim = np.inf
    for _ in range(3):
        t = time.process_time()
        got = 0
        for c in iter_core_chunks(scn, 100_000):
            got += len(c["t_s"])
            if got >= n:
                break
        best_sim = min(best_sim, (time.process_time() - t) / got)
    chunks = []
    got = 0
    for c in iter_core_chunks(scn, 100_000):
        chunks.append((np.ascontiguousarray(c["dtheta_rad"]), np.ascontiguousarray(c["dv_m_s"])))
        got += len(c["t_s"])
        if got >= n:
            break
    alignment = align_log(ImuLog.from_scenario(scn))
    best_nav = np.inf
    for _ in range(3):
        nav = _core.Navigator(alignment.navigator_config())
        t = time.process_time()
        for dth, dv in chunks:
            nav.process(dth, dv, 600)  # states kept every 60 s at 10 Hz, as the passes keep them
        best_nav = min(best_nav, (time.process_time() - t) / got)
    return {"navigator_samples_s": 1.0 / best_nav, "simulator_samples_s": 1.0 / best_sim}


def profile(campaign, n_runs: int) -> dict:
    counts = count_passes()
    rows, cpu = [], []
    for i in range(n_runs):
        t = time.process_time()
        rows.append(process_run(campaign, i))
        cpu.append(time.process_time() - t)
    assert all(r["error"] is None for r in rows), [r["error"] for r in rows]
    stages = {
        k: float(np.mean([r[k] for r in rows]))
        for k in ("t_align_s", "t_passes_s", "t_smoother_s", "t_twin_s", "t_total_s")
    }
    per_run = {k: v / n_runs for k, v in counts.items()}
    return {"runs": n_runs, "wall_s": stages, "cpu_s": float(np.mean(cpu)), "per_run": per_run}


def cluster(campaign, n_runs: int) -> dict:
    out: dict = {}
    folders = {}
    for workers in (1, 2):
        folder = Path(tempfile.mkdtemp(prefix=f"bench_campaign_{workers}w_"))
        shutil.rmtree(folder)
        t = time.perf_counter()
        s = run_campaign(campaign, folder, dask_workers=workers, limit=n_runs, text="bench")
        out[f"{workers}w_s"] = time.perf_counter() - t
        assert s.done == n_runs and s.failed == 0
        folders[workers] = folder
    a, b = read_runs(folders[1]), read_runs(folders[2])
    same = all(
        (np.array_equal(a[k], b[k], equal_nan=True) if a[k].dtype.kind == "f" else list(a[k]) == list(b[k]))
        for k in a.columns
        if k not in VOLATILE
    ) and all(np.array_equal(a.curves[k], b.curves[k], equal_nan=True) for k in a.curves)
    out["speedup"] = out["1w_s"] / out["2w_s"]
    out["efficiency"] = out["speedup"] / 2
    out["identical_rows"] = bool(same)
    for f in folders.values():
        shutil.rmtree(f, ignore_errors=True)
    return out


_MEMORY_CHILD = """
import json, sys, threading, time, tomllib
import psutil
from gyrodrift.campaign import parse_campaign, process_run
data = tomllib.loads(open(sys.argv[1]).read())
h = float(sys.argv[2])
data.setdefault("options", {})["truth_h"] = h
data["base"]["run"]["duration_h"] = 4.0 + h
c = parse_campaign(data, source=sys.argv[1])
proc = psutil.Process()
before = proc.memory_info().rss
peak = [before]
done = threading.Event()
def watch():
    while not done.is_set():
        peak[0] = max(peak[0], proc.memory_info().rss)
        time.sleep(0.01)
t = threading.Thread(target=watch)
t.start()
r = process_run(c, 0)
done.set()
t.join()
print(json.dumps({"hours": h, "error": r["error"], "start_mb": before / 2**20, "peak_mb": peak[0] / 2**20,
                  "t_s": r["t_total_s"]}))
"""


def memory(path: str, hours: list[float]) -> list[dict]:
    out = []
    for h in hours:
        res = subprocess.run([sys.executable, "-c", _MEMORY_CHILD, path, str(h)], capture_output=True, text=True)
        out.append(
            json.loads(res.stdout.strip().splitlines()[-1])
            if res.returncode == 0
            else {"hours": h, "error": res.stderr[-300:]}
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--campaign", default="examples/campaigns/default.toml")
    ap.add_argument("--profile-runs", type=int, default=4)
    ap.add_argument("--cluster-runs", type=int, default=40)
    ap.add_argument("--memory-hours", default="24,48,72,144")
    ap.add_argument("--skip-cluster", action="store_true")
    args = ap.parse_args()
    campaign = load_campaign(args.campaign)
    with open("/proc/loadavg") as fh:
        print(f"load average at start: {fh.read().split()[:3]} on {__import__('os').cpu_count()} CPUs")
    rates = component_rates(campaign)
    print(
        f"navigator {rates['navigator_samples_s'] / 1e6:.1f} M samples/s, simulator "
        f"{rates['simulator_samples_s'] / 1e6:.1f} M samples/s (CPU time, best of 3)"
    )
    p = profile(campaign, args.profile_runs)
    w = p["wall_s"]
    print(
        f"per run ({p['runs']} runs of {campaign.name}, wall s): align {w['t_align_s']:.2f}, "
        f"passes {w['t_passes_s']:.2f}, smoother {w['t_smoother_s']:.2f}, twin {w['t_twin_s']:.2f}, "
        f"total {w['t_total_s']:.2f}; CPU {p['cpu_s']:.2f} s"
    )
    runs_h = 3600.0 / p["cpu_s"]
    print(f"runs per hour per core (CPU time): {runs_h:.0f} (target 3000: {runs_h / 3000:.2f}x)")
    pr = p["per_run"]
    floor = pr["nav_updates"] / rates["navigator_samples_s"] + pr["sim_samples"] / rates["simulator_samples_s"]
    print(
        f"navigation passes per run: {pr['reads']:.1f} reads, {pr['nav_updates'] / 1e6:.1f} M navigator updates, "
        f"{pr['sim_samples'] / 1e6:.1f} M simulated samples -> floor {floor:.2f} s "
        f"(nav {pr['nav_updates'] / rates['navigator_samples_s']:.2f} s + "
        f"sim {pr['sim_samples'] / rates['simulator_samples_s']:.2f} s); "
        f"CPU time / floor {p['cpu_s'] / floor:.2f}"
    )
    if not args.skip_cluster:
        c = cluster(campaign, args.cluster_runs)
        print(
            f"LocalCluster, {args.cluster_runs} runs: 1 worker {c['1w_s']:.1f} s, 2 workers {c['2w_s']:.1f} s, "
            f"speed-up {c['speedup']:.2f}, parallel efficiency {c['efficiency']:.2f}, "
            f"rows identical: {c['identical_rows']}"
        )
    for m in memory(args.campaign, [float(h) for h in args.memory_hours.split(",")]):
        if m.get("error"):
            print(f"memory, {m['hours']:g} h truth: failed: {m['error']}")
        else:
            print(
                f"memory, {m['hours']:g} h truth span (log {4 + m['hours']:g} h): peak RSS during the run "
                f"{m['peak_mb']:.0f} MB (before it {m['start_mb']:.0f} MB: +{m['peak_mb'] - m['start_mb']:.0f} MB), "
                f"{m['t_s']:.1f} s"
            )
    print(f"this process peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")


if __name__ == "__main__":
    main()
