"""Campaign throughput: runs per hour per core (previous and current per-run path), where the CPU time goes, the
floor, LocalCluster scaling, memory.

    python benchmarks/bench_campaign.py [--campaign examples/campaigns/default.toml] [--profile-runs 4]
                                        [--runs 40] [--hours H] [--memory-hours 24,48,72,144]
                                        [--skip-profile] [--skip-cluster] [--skip-memory]
    python benchmarks/bench_campaign.py --skip-profile --skip-memory --runs 40 --hours 12   # scaling only, short

1. Per run, in this process: `--profile-runs` runs of the campaign, each processed by the previous path
   (``[options] verify = true``: the truths' verification reads, the twin's own truth) and by the current one,
   alternately (load drifts hit both alike). CPU seconds per stage (the rows' ``cpu_*`` columns) and in all;
   runs per hour per core = 3600 / CPU seconds per run; the two paths' results compared.
2. The floor: every call into the core is wrapped (`CoreMeter`) to count the samples it handles (simulated with
   and without noise, navigator, aligner and smoother updates) and the CPU seconds spent inside; the core's own
   samples per CPU second are measured in this same run (best of 3 on the campaign's first scenario); floor =
   sum of samples / rate (+ the smoother's backward passes). CPU / floor is what the Python around the core
   costs.
3. `--runs` runs (truth span `--hours` if given, else the campaign's) on a dask LocalCluster with 1 worker, then
   with 2 (fresh folders; the workers started and warm, one short run each, before the clock starts): wall
   time, speed-up, parallel efficiency (speed-up / 2), the CPU seconds per run in the workers (the rows'
   ``cpu_total_s``: if it grows with 2 workers, the machine is short of cores, not the campaign of parallelism)
   and the rows compared (timings and worker names aside).
4. Resident memory of one worker process (a fresh subprocess per point, sampled every 10 ms) before and during
   one run whose truth span is each of `--memory-hours` (log = 4 h alignment + that span): memory vs run length.

The machine is shared: numbers are for this run only (the load average is printed); the ratios in one run are
what matter. Never fails on a slow machine: it only reports.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

from gyrodrift.fleet.campaign import run_campaign
from gyrodrift.fleet.science import process_run
from gyrodrift.fleet.spec import Campaign, parse_campaign
from gyrodrift.fleet.store import STAGES, read_runs

VOLATILE = {"worker"} | {f"{k}_{s}_s" for k in ("t", "cpu") for s in (*STAGES, "total")}
KINDS = ("sim_noisy", "sim_clean", "navigator", "aligner", "smoother", "smoother_backward")
"""What the core does for a run: samples simulated with / without noise, navigator, aligner and smoother
updates, and the smoother's backward passes (``result()``, counted in calls)."""


class CoreMeter:
    """Wraps `gyrodrift._core`'s simulator, navigator, aligner and smoother while installed: samples handled and
    CPU seconds spent inside the core per kind (`KINDS`)."""

    NAMES = ("ImuSimulator", "Navigator", "Aligner", "Smoother")

    def __init__(self) -> None:
        self.samples = dict.fromkeys(KINDS, 0)
        self.cpu = dict.fromkeys(KINDS, 0.0)
        self._saved: dict = {}

    def reset(self) -> None:
        self.samples = dict.fromkeys(KINDS, 0)
        self.cpu = dict.fromkeys(KINDS, 0.0)

    def _add(self, kind: str, n: int, t0: float) -> None:
        self.cpu[kind] += time.process_time() - t0
        self.samples[kind] += n

    def install(self) -> CoreMeter:
        from gyrodrift import _core

        self._saved = {n: getattr(_core, n) for n in self.NAMES}
        real, meter = self._saved, self

        class Wrapped:
            core_name = ""

            def __init__(self, config):
                self._o = real[self.core_name](config)

            def __getattr__(self, name):
                if name == "_o":
                    raise AttributeError(name)
                return getattr(self._o, name)

        class Simulator(Wrapped):
            core_name = "ImuSimulator"

            def __init__(self, config):
                super().__init__(config)
                noisy = (
                    config.gyro_arw_rad_rts,
                    config.accel_vrw_m_s_rts,
                    config.gyro_bias_instability_rad_s,
                    config.gyro_rrw_rad_s_rts,
                )
                self._kind = "sim_noisy" if any(noisy) else "sim_clean"

            def next_chunk(self, n):
                t = time.process_time()
                c = self._o.next_chunk(n)
                meter._add(self._kind, 0 if c is None else len(c["t_s"]), t)
                return c

        class Navigator(Wrapped):
            core_name = "Navigator"

            def process(self, dtheta, dv, *rest):
                t = time.process_time()
                out = self._o.process(dtheta, dv, *rest)
                meter._add("navigator", len(dtheta), t)
                return out

        class Aligner(Wrapped):
            core_name = "Aligner"
            STATE_NAMES = getattr(real["Aligner"], "STATE_NAMES", [])

            def process(self, dtheta, dv, *rest):
                t = time.process_time()
                k = self._o.process(dtheta, dv, *rest)
                meter._add("aligner", int(k), t)
                return k

        class Smoother(Wrapped):
            core_name = "Smoother"

            def process(self, dtheta, dv, *rest):
                t = time.process_time()
                k = self._o.process(dtheta, dv, *rest)
                meter._add("smoother", int(k), t)
                return k

            def result(self):
                t = time.process_time()
                r = self._o.result()
                meter._add("smoother_backward", 1, t)
                return r

        for name, cls in zip(self.NAMES, (Simulator, Navigator, Aligner, Smoother), strict=True):
            setattr(_core, name, cls)
        return self

    def uninstall(self) -> None:
        from gyrodrift import _core

        for name, cls in self._saved.items():
            setattr(_core, name, cls)


def core_rates(campaign, meter: CoreMeter) -> dict[str, float]:
    """Samples per CPU second inside the core per kind (the smoother's backward pass: CPU seconds per call),
    best of 3 on the campaign's first scenario (8 h of navigation)."""
    from gyrodrift.fleet.science import noise_model
    from gyrodrift.ins.simulate import scenario_log
    from gyrodrift.procedure import align_log, navigate_after_alignment
    from gyrodrift.procedure.smoother import smooth_log

    timeline = campaign.timeline
    best = dict.fromkeys(KINDS, 0.0)
    for _ in range(3):
        meter.reset()
        scn = campaign.scenario(0)
        log = scenario_log(scn)
        alignment = align_log(log, timeline=timeline)
        smooth_log(log, timeline=timeline, noise=noise_model(scn))
        navigate_after_alignment(log, alignment, [0.0], 8.0, threads=1)
        twin = scenario_log(campaign.scenario(0, noise=False))
        for _chunk in twin.chunks(100_000, stop=twin.samples_for(8 * 3600.0)):
            pass
        for k in KINDS:
            if meter.cpu[k] > 0:
                rate = meter.samples[k] / meter.cpu[k] if k != "smoother_backward" else meter.cpu[k] / meter.samples[k]
                better = rate > best[k] if k != "smoother_backward" else (best[k] == 0 or rate < best[k])
                best[k] = rate if better else best[k]
    return best


def floor_s(samples: dict[str, float], rates: dict[str, float]) -> float:
    """CPU seconds the core needs for `samples` at its best rates (the floor of the work)."""
    return sum(
        samples[k] * rates[k] if k == "smoother_backward" else samples[k] / rates[k]
        for k in KINDS
        if samples[k] and rates[k]
    )


def with_options(campaign_path: str, **options) -> Campaign:
    data = tomllib.loads(Path(campaign_path).read_text(encoding="utf-8"))
    data.setdefault("options", {}).update(options)
    if "truth_h" in options:
        align_h = float(data["options"].get("align_h", 4.0))
        data.setdefault("base", {}).setdefault("run", {})["duration_h"] = align_h + float(options["truth_h"])
    return parse_campaign(data, source=campaign_path)


def profile(campaign_path: str, n_runs: int, meter: CoreMeter) -> dict:
    paths = {"previous": with_options(campaign_path, verify=True), "current": with_options(campaign_path)}
    out: dict = {name: {"rows": [], "cpu": [], "samples": [], "core_cpu": []} for name in paths}
    for i in range(n_runs):
        order = list(paths) if i % 2 == 0 else list(reversed(paths))
        for name in order:
            meter.reset()
            t = time.process_time()
            row = process_run(paths[name], i)
            out[name]["cpu"].append(time.process_time() - t)
            assert row["error"] is None, row["error"]
            out[name]["rows"].append(row)
            out[name]["samples"].append(dict(meter.samples))
            out[name]["core_cpu"].append(dict(meter.cpu))
    return out


def compare(a: list[dict], b: list[dict]) -> dict:
    """Largest differences between two paths' rows: drifts [deg/h], error curves [nmi] within 0.002 deg/h of
    the truth, and whether every other scalar is identical."""
    from gyrodrift.fleet.store import CURVE_COLUMNS, CampaignRuns

    out = {"drift": 0.0, "effective": 0.0, "curves_nmi": 0.0}
    identical = True
    for x, y in zip(a, b, strict=True):
        out["drift"] = max(out["drift"], abs(x["drift_deg_h"] - y["drift_deg_h"]))
        out["effective"] = max(out["effective"], abs(x["drift_effective_deg_h"] - y["drift_effective_deg_h"]))
        runs = [CampaignRuns({}, {k: np.array([r[k]], float) for k in CURVE_COLUMNS}) for r in (x, y)]
        for d in x["drift_deg_h"] + np.array([-0.002, 0.0, 0.002]):
            ex, ey = (r.errors_nmi([d])[0] for r in runs)
            out["curves_nmi"] = max(out["curves_nmi"], float(np.max(np.abs(ex - ey))))
        for k, v in x.items():
            if isinstance(v, float) and k not in VOLATILE and k not in ("drift_deg_h", "drift_effective_deg_h"):
                identical = identical and bool(v == y[k] or (np.isnan(v) and np.isnan(y[k])))
    return {**out, "other_identical": identical}


def cluster(campaign, n_runs: int, warm) -> dict:
    """`n_runs` of `campaign` on a LocalCluster of 1 then 2 workers; each worker first processes run 0 of the
    short campaign `warm` (its first run imports the procedure's modules: about 1.3 s of CPU) before the clock."""
    from gyrodrift.fleet.cluster import dask_client

    out: dict = {}
    folders = {}
    for workers in (1, 2):
        folder = Path(tempfile.mkdtemp(prefix=f"bench_campaign_{workers}w_"))
        shutil.rmtree(folder)
        t = time.perf_counter()
        with dask_client(workers=workers) as client:
            client.run(process_run, warm, 0)  # workers started and warm before the clock
            out[f"{workers}w_start_s"] = time.perf_counter() - t
            t = time.perf_counter()
            s = run_campaign(campaign, folder, scheduler=client.scheduler.address, limit=n_runs, text="bench")
            out[f"{workers}w_s"] = time.perf_counter() - t
        assert s.done == n_runs and s.failed == 0
        rows = read_runs(folder, curves=False)
        out[f"{workers}w_cpu_per_run_s"] = float(np.mean(rows.numbers("cpu_total_s")))
        out[f"{workers}w_wall_per_run_s"] = float(np.mean(rows.numbers("t_total_s")))
        # the share of the wall time the workers spent inside runs: 1 = no worker waited for the client
        out[f"{workers}w_busy"] = float(np.sum(rows.numbers("t_total_s"))) / (workers * out[f"{workers}w_s"])
        folders[workers] = folder
    a, b = read_runs(folders[1]), read_runs(folders[2])
    assert a.curves is not None and b.curves is not None
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
from gyrodrift.fleet.science import process_run
from gyrodrift.fleet.spec import parse_campaign
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


def load() -> str:
    with open("/proc/loadavg") as fh:
        return " ".join(fh.read().split()[:3])


def report_profile(p: dict, rates: dict[str, float], n_runs: int, name: str) -> None:
    prev, cur = p["previous"], p["current"]
    print(f"per run, CPU s ({n_runs} runs of {name}; previous = [options] verify = true):")
    print(f"  {'stage':<10} {'previous':>9} {'current':>9}")
    for stage in (*STAGES, "total"):
        a = np.mean([r[f"cpu_{stage}_s"] for r in prev["rows"]])
        b = np.mean([r[f"cpu_{stage}_s"] for r in cur["rows"]])
        print(f"  {stage:<10} {a:9.3f} {b:9.3f}")
    cpu = {k: float(np.mean(v["cpu"])) for k, v in p.items()}
    rh = {k: 3600.0 / v for k, v in cpu.items()}
    print(
        f"runs per hour per core (CPU time): previous {rh['previous']:.0f}, current {rh['current']:.0f} "
        f"(x{rh['current'] / rh['previous']:.2f}; target 3000: {rh['current'] / 3000:.2f}x)"
    )
    for k, v in p.items():
        samples = {kind: float(np.mean([s[kind] for s in v["samples"]])) for kind in KINDS}
        core = float(np.mean([sum(c.values()) for c in v["core_cpu"]]))
        fl = floor_s(samples, rates)
        print(
            f"  {k}: core work per run: simulated {samples['sim_noisy'] / 1e6:.2f} M noisy + "
            f"{samples['sim_clean'] / 1e6:.2f} M noise-free samples, navigator {samples['navigator'] / 1e6:.2f} M, "
            f"aligner {samples['aligner'] / 1e6:.2f} M, smoother {samples['smoother'] / 1e6:.2f} M updates "
            f"+ {samples['smoother_backward']:.0f} backward pass(es) -> floor {fl:.3f} s "
            f"({3600 / fl:.0f} runs/h/core); CPU inside the core {core:.3f} s; CPU / floor {cpu[k] / fl:.2f}"
        )
    c = compare(prev["rows"], cur["rows"])
    print(
        f"current - previous: drift {c['drift']:.1e} deg/h, effective drift {c['effective']:.1e} deg/h, "
        f"error curves {c['curves_nmi']:.1e} nmi (within 0.002 deg/h of the truth), "
        f"other scalars identical: {c['other_identical']}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--campaign", default="examples/campaigns/default.toml")
    ap.add_argument("--profile-runs", type=int, default=4)
    ap.add_argument("--runs", "--cluster-runs", dest="runs", type=int, default=40)
    ap.add_argument("--hours", type=float, default=None, help="truth span of the cluster runs [h] (>= features_h)")
    ap.add_argument("--memory-hours", default="24,48,72,144")
    ap.add_argument("--skip-profile", action="store_true")
    ap.add_argument("--skip-cluster", action="store_true")
    ap.add_argument("--skip-memory", action="store_true")
    args = ap.parse_args()
    base = with_options(args.campaign)
    print(f"load average at start: {load()} on {os.cpu_count()} CPUs")
    if not args.skip_profile and args.profile_runs > 0:
        meter = CoreMeter().install()
        try:
            rates = core_rates(base, meter)
            print(
                "core rates (CPU, best of 3): simulator "
                f"{rates['sim_noisy'] / 1e6:.1f} M samples/s with noise, {rates['sim_clean'] / 1e6:.1f} M without; "
                f"navigator {rates['navigator'] / 1e6:.1f} M/s; aligner {rates['aligner'] / 1e6:.2f} M/s; "
                f"smoother {rates['smoother'] / 1e6:.2f} M/s + {rates['smoother_backward']:.3f} s per backward pass"
            )
            p = profile(args.campaign, args.profile_runs, meter)
        finally:
            meter.uninstall()
        report_profile(p, rates, args.profile_runs, base.name)
        print(f"load average after the profile: {load()}")
    if not args.skip_cluster:
        c = base if args.hours is None else with_options(args.campaign, truth_h=args.hours)
        r = cluster(c, args.runs, with_options(args.campaign, truth_h=base.options.get("features_h", 12.0)))
        hours = f"{args.hours:g} h truth span" if args.hours is not None else "the campaign's runs"
        print(
            f"LocalCluster, {args.runs} runs ({hours}), workers warm: wall 1 worker {r['1w_s']:.1f} s, 2 workers "
            f"{r['2w_s']:.1f} s: speed-up {r['speedup']:.2f}, parallel efficiency {r['efficiency']:.2f}, "
            f"rows identical: {r['identical_rows']}"
        )
        print(
            f"  per run in the workers: CPU {r['1w_cpu_per_run_s']:.3f} s (1 worker) / {r['2w_cpu_per_run_s']:.3f} s "
            f"(2 workers), wall {r['1w_wall_per_run_s']:.3f} s / {r['2w_wall_per_run_s']:.3f} s; cluster start "
            f"{r['1w_start_s']:.1f} s / {r['2w_start_s']:.1f} s (not timed); workers busy inside runs "
            f"{r['1w_busy']:.0%} / {r['2w_busy']:.0%} of the wall time; load average now {load()}"
        )
    if not args.skip_memory:
        for m in memory(args.campaign, [float(h) for h in args.memory_hours.split(",")]):
            if m.get("error"):
                print(f"memory, {m['hours']:g} h truth: failed: {m['error']}")
            else:
                print(
                    f"memory, {m['hours']:g} h truth span (log {4 + m['hours']:g} h): peak RSS during the run "
                    f"{m['peak_mb']:.0f} MB (before it {m['start_mb']:.0f} MB: +{m['peak_mb'] - m['start_mb']:.0f} "
                    f"MB), {m['t_s']:.1f} s"
                )
    print(f"this process peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")


if __name__ == "__main__":
    main()
