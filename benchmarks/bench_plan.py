"""The planner (`gyrodrift plan`) against simulated campaigns: predicted vs measured share of runs within the budget.

    python benchmarks/bench_plan.py [--runs 100] [--grades 0.0002,0.0005] [--spans-h 10,16,24] [--lat-deg 40]
                                    [--seed 2311] [--workers 2] [--out DIR] [--json FILE]

For each noise grade (ARW [deg/sqrt(h)]; VRW 2 ug/sqrt(Hz) at ARW <= 0.0003, else 5, the default campaign's
grades): one campaign (`gyrodrift.fleet`) of `--runs` 76 h static runs at `--lat-deg`, 10 Hz, reciprocating
table, random heading, horizontal gyro biases and axial drift, constant temperature (the planner's thermal term is
zero), options ``align_h = 4``, ``features_h = T - 4`` (T the first span), ``truth_h = 72``: each run's smoother
over the first T hours, its noise-free twin's truth and its linear 72 h error curves. Only the smoother depends on
the span: for every other span the bench runs the smoother alone over the first T hours of the same simulated runs
(the campaign's scenarios, simulated again on the fly; `smooth_log` with the campaign's time line at that span and
the run's own noise, as the campaign does), kept in ``smoother-spanT.json`` beside the campaign. Measured per
point (grade, span):

- the share of runs whose 72 h position error after compensating the smoother's drift is within the budget
  (1 nmi), with its binomial 1-sigma sqrt(p (1 - p) / n); the planner's predicted share beside it
  (target: within 5 percentage points at >= 100 runs per point) and the binomial 1-sigma of n runs were the
  prediction right (p the predicted share: the spread the difference would have from the sampling alone);
- the smoother's reported 1-sigma (mean over the runs) against the planner's (target: within 10 %), and the RMS of
  the z-scores (smoother drift - the noise-free twin's truth) / reported sigma (the smoother's calibration on the
  drift that matters for the 72 h);
- the floor: the share within the budget and the 95 % quantile after compensating the twin's truth (the exact
  drift) against the planner's floor (the noise over the mission and the alignment's leftovers);
- the correlation of the drift error (twin's truth - smoother) with the floor's east error at 72 h, measured (with
  its 1-sigma (1 - r^2) / sqrt(n - 1)) and predicted (the planner's cross term), and the share the planner predicts
  with the two taken independent;
- the share a Gaussian with the runs' own error covariance gives (what the planner would say with the measured
  covariance: the gap to the measured share is the sampling and the shape, the gap to the prediction the model).

Only reports; never fails on a slow machine. The campaign folders are kept under `--out` (default: a temporary
folder, removed) and reused by a rerun (finished runs and smoother spans are skipped).
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

from gyrodrift.earth import NMI_M
from gyrodrift.fleet.campaign import run_campaign
from gyrodrift.fleet.spec import parse_campaign
from gyrodrift.fleet.store import read_runs
from gyrodrift.procedure.noise import SensorNoise
from gyrodrift.procedure.plan import MissionBudget, identification_curve, mission_error_model, norm_cdf

CAMPAIGN = """
[campaign]
name = "{name}"
count = {runs}
seed = {seed}

[options]
align_h = 4.0
features_h = {features_h}
truth_h = 72.0

[base.site]
lat_deg = {lat}

[base.run]
duration_h = 76.0
rate_hz = 10.0

[base.gyro]
bias_deg_h = [0.0, 0.0, 0.002]
arw_deg_rth = {arw}

[base.accel]
vrw_ug_rthz = {vrw}

[base.temperature]
start_c = 25.0
end_c = 25.0
t0_c = 25.0

[vary."gyro.bias_deg_h[0]"]
dist = "normal"
mean = 0.0
std = 0.003

[vary."gyro.bias_deg_h[1]"]
dist = "normal"
mean = 0.0
std = 0.003

[vary."gyro.bias_deg_h[2]"]
dist = "normal"
mean = 0.002
std = 0.0008

[vary."attitude.yaw_deg"]
dist = "uniform"
low = -180.0
high = 180.0
"""


def vrw_for(arw: float) -> float:
    return 2.0 if arw <= 0.0003 else 5.0


def campaign_at(arw: float, span_h: float, args, base_span_h: float):
    """The grade's campaign (named after its first span `base_span_h`) with the time line of `span_h`: the same
    runs (seed, draws), only ``features_h`` differs."""
    name = f"plan-arw{arw:g}-span{base_span_h:g}"
    text = CAMPAIGN.format(
        name=name,
        runs=args.runs,
        seed=args.seed,
        features_h=span_h - 4.0,
        lat=args.lat_deg,
        arw=arw,
        vrw=vrw_for(arw),
    )
    return parse_campaign(tomllib.loads(text), source=name), text


def smoother_at_span(arw: float, span_h: float, args, base_span_h: float, indices, folder: Path):
    """The smoother's drift and reported 1-sigma [deg/h] over the first `span_h` of each run `indices` of the
    grade's campaign (module docs), cached in ``folder/smoother-span{span_h}.json``."""
    from gyrodrift.files.atomic import atomic_write
    from gyrodrift.fleet.science import noise_model
    from gyrodrift.ins.simulate import scenario_log
    from gyrodrift.procedure.smoother import smooth_log

    campaign, _ = campaign_at(arw, span_h, args, base_span_h)
    cache = folder / f"smoother-span{span_h:g}.json"
    done = json.loads(cache.read_text()) if cache.exists() else {}
    for i in (int(i) for i in indices):
        if str(i) not in done:
            scn = campaign.scenario(i)
            res = smooth_log(scenario_log(scn), timeline=campaign.timeline, noise=noise_model(scn))
            done[str(i)] = [float(res.navigation_drift_deg_h), float(res.navigation_drift_std_deg_h)]
            with atomic_write(cache, what="smoother cache") as fh:
                fh.write(json.dumps(done))
    got = np.array([done[str(int(i))] for i in indices], dtype=float).reshape(-1, 2)
    return got[:, 0], got[:, 1]


def run_point(out: Path, arw: float, span_h: float, args, base_span_h: float) -> dict:
    campaign, text = campaign_at(arw, base_span_h, args, base_span_h)
    folder = out / campaign.name
    t0 = time.perf_counter()
    run_campaign(campaign, folder, text=text, workers=args.workers, quiet=True)
    runs = read_runs(folder)
    failed = int(len(runs) - np.count_nonzero(runs.ok))
    runs = runs.select(runs.ok & np.isfinite(runs.numbers("drift_smoother_deg_h")))
    if span_h == base_span_h:
        d_hat, sigma_rep = runs.numbers("drift_smoother_deg_h"), runs.numbers("drift_smoother_std_deg_h")
    else:
        d_hat, sigma_rep = smoother_at_span(arw, span_h, args, base_span_h, runs.numbers("index"), folder)
    wall = time.perf_counter() - t0
    n = len(runs)
    budget = MissionBudget()
    err = runs.errors_nmi(d_hat)[:, -1]
    floor = runs.errors_nmi(runs.numbers("drift_effective_deg_h"))[:, -1]
    z = (d_hat - runs.numbers("drift_effective_deg_h")) / sigma_rep
    noise = SensorNoise(arw_deg_rth=arw, vrw_ug_rthz=vrw_for(arw))
    t_start = time.perf_counter()
    curve = identification_curve(noise, [span_h], lat_deg=args.lat_deg, mission_h=budget.hours)
    sigma_plan, cross = float(curve.drift_std_deg_h[0]), curve.cross_m_deg_h[0]
    mission = mission_error_model(args.lat_deg, noise, hours=budget.hours, alignment_cov_m2=curve.alignment_cov_m2)
    predicted = mission.share_within(sigma_plan, budget.error_nmi, cross)
    independent = mission.share_within(sigma_plan, budget.error_nmi)
    plan_s = time.perf_counter() - t_start
    # The drift error's correlation with the floor's east error, measured and predicted (the planner's cross term).
    c = runs.curves
    ge = np.array([x[-1] for x in c["curve_east_per_deg_h"]], dtype=float)
    floor_east = np.array([x[-1] for x in c["curve_east0_m"]], dtype=float) + runs.numbers("drift_effective_deg_h") * ge
    d_err = runs.numbers("drift_effective_deg_h") - d_hat
    corr_measured = float(np.corrcoef(d_err, floor_east)[0, 1])
    # The error vectors after compensating the smoother's drift: the runs' own covariance in the planner's formula.
    gn = np.array([x[-1] for x in c["curve_north_per_deg_h"]], dtype=float)
    north = np.array([x[-1] for x in c["curve_north0_m"]], dtype=float) + d_hat * gn
    east = np.array([x[-1] for x in c["curve_east0_m"]], dtype=float) + d_hat * ge
    share_measured_cov = norm_cdf(np.cov(np.vstack([north, east])), budget.error_nmi * NMI_M)
    corr_predicted = float(cross[1] / (sigma_plan * np.sqrt(mission.floor_cov_m2[1][1])))
    measured = float(np.mean(err <= budget.error_nmi))
    floor_share = float(np.mean(floor <= budget.error_nmi))
    return {
        "arw_deg_rth": arw,
        "span_h": span_h,
        "runs": n,
        "failed": failed,
        "campaign_wall_s": wall,
        "planner_s": plan_s,
        "sigma_planner_deg_h": sigma_plan,
        "sigma_smoother_mean_deg_h": float(np.mean(sigma_rep)),
        "sigma_ratio": sigma_plan / float(np.mean(sigma_rep)),
        "z_rms": float(np.sqrt(np.mean(z**2))),
        "share_predicted": predicted,
        "share_predicted_independent": independent,
        "corr_measured": corr_measured,
        "corr_measured_std": (1.0 - corr_measured**2) / math.sqrt(max(n - 1, 1)),
        "share_gauss_measured_cov": share_measured_cov,
        "corr_predicted": corr_predicted,
        "share_measured": measured,
        "share_measured_std": math.sqrt(max(measured * (1 - measured), 1e-12) / n),
        "share_binomial_std": math.sqrt(predicted * (1 - predicted) / n),
        "floor_share_predicted": mission.share_within(0.0, budget.error_nmi),
        "floor_share_measured": floor_share,
        "floor_q95_predicted_nmi": mission.quantile_nmi(0.0, 0.95),
        "floor_q95_measured_nmi": float(np.quantile(floor, 0.95)),
        "q95_predicted_nmi": mission.quantile_nmi(sigma_plan, 0.95, cross),
        "q95_measured_nmi": float(np.quantile(err, 0.95)),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=100, help="runs per point (default 100)")
    ap.add_argument("--grades", default="0.0002,0.0005", help="ARW grades [deg/sqrt(h)], comma-separated")
    ap.add_argument("--spans-h", default="10,16,24", help="observation spans [h], comma-separated")
    ap.add_argument("--lat-deg", type=float, default=40.0)
    ap.add_argument("--seed", type=int, default=2311, help="the campaigns' seed (another seed: other runs)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=None, help="keep the campaigns here (default: a temporary folder)")
    ap.add_argument("--json", type=Path, default=None, help="also write the rows as JSON")
    args = ap.parse_args()
    grades = [float(g) for g in args.grades.split(",")]
    spans = [float(s) for s in args.spans_h.split(",")]
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_plan_"))
    rows = []
    try:
        for arw in grades:
            for span in spans:
                row = run_point(out, arw, span, args, spans[0])
                rows.append(row)
                diff = row["share_measured"] - row["share_predicted"]
                print(
                    f"ARW {arw:g} span {span:g} h, {row['runs']} runs ({row['failed']} failed, campaign "
                    f"{row['campaign_wall_s']:.0f} s wall, planner {row['planner_s']:.2f} s): within 1 nmi at 72 h "
                    f"predicted {100 * row['share_predicted']:.1f} %, measured {100 * row['share_measured']:.1f} "
                    f"+- {100 * row['share_measured_std']:.1f} % (diff {100 * diff:+.1f} pp, binomial 1-sigma at the "
                    f"prediction {100 * row['share_binomial_std']:.1f} pp; drift error taken "
                    f"independent of the floor: {100 * row['share_predicted_independent']:.1f} %; a Gaussian with the "
                    f"runs' own covariance: {100 * row['share_gauss_measured_cov']:.1f} %); corr(d - d_hat, floor "
                    f"east) measured {row['corr_measured']:+.2f} +- {row['corr_measured_std']:.2f}, predicted "
                    f"{row['corr_predicted']:+.2f}; "
                    f"sigma planner {row['sigma_planner_deg_h']:.3e} / smoother {row['sigma_smoother_mean_deg_h']:.3e} "
                    f"deg/h (x{row['sigma_ratio']:.3f}), z rms {row['z_rms']:.2f}; 95 % quantile predicted "
                    f"{row['q95_predicted_nmi']:.2f}, measured {row['q95_measured_nmi']:.2f} nmi; floor within 1 nmi "
                    f"predicted {100 * row['floor_share_predicted']:.1f} %, "
                    f"measured {100 * row['floor_share_measured']:.1f} %, "
                    f"floor 95 % quantile predicted {row['floor_q95_predicted_nmi']:.2f}, measured "
                    f"{row['floor_q95_measured_nmi']:.2f} nmi",
                    flush=True,
                )
    finally:
        if args.json is not None:
            args.json.write_text(json.dumps(rows, indent=1))
        if args.out is None:
            shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
