"""Fleet campaigns: a campaign file -> many simulated runs, processed in workers, stored run by run.

A campaign file (TOML, docs/campaigns.md) holds

- ``[campaign]``: ``name``, ``count`` (runs), ``seed`` (integer >= 0);
- ``[base]``: a scenario (the sections and keys of docs/scenarios.md) every run starts from;
- ``[grades.NAME]``: optional noise grades, each a table of noise keys (``arw_deg_rth``, ``vrw_ug_rthz``,
  ``bias_instability_deg_h``, ``correlation_s``, ``rrw_deg_h_rth``) set on the run's gyro/accel;
- ``[vary."SECTION.KEY"]`` or ``[vary."SECTION.KEY[i]"]`` (one element of a vector key) and ``[vary.grade]``:
  a distribution, ``dist`` = ``uniform`` (``low``, ``high``), ``normal`` (``mean``, ``std``), ``log_uniform``
  (``low`` > 0, ``high``) or ``choice`` (``values``, a list).

Run ``i`` (0-based) draws its parameters and its simulator seed from ``numpy.random.SeedSequence(seed,
spawn_key=(i,))`` (the i-th child of ``SeedSequence(seed).spawn``): any run is regenerated alone, whatever the
count, the order of completion or the workers (`Campaign.scenario`).

Per run (`process_run`, in the worker; nothing written there): the scenario is simulated on the fly
(`gyrodrift.ins.simulate.scenario_log`), aligned, navigated for the 12 h features and the 72 h truth
(`extract_features` with the truth: one read for both), the 12 h curve fit; the linear 72 h error curves
(north/east error of the uncompensated navigation and their sensitivity per deg/h of compensated drift, the
secant between two navigated drifts), from which the position error after compensating any drift ``d`` is
``hypot(n0 + d gn, e0 + d ge)`` without navigating again; the smoother estimate (when
`gyrodrift.procedure.smoother` exists); and the simulated effective drift, the truth of the run's noise-free
twin (same scenario and seed, ARW/VRW/bias instability/RRW off). A run that fails is a row with its error.

The store (`CampaignStore`, folder ``DIR``): ``DIR/campaign.toml`` (the campaign file as given),
``DIR/campaign.json`` (its resolved content and hash), ``DIR/runs/run-NNNNNN.parquet`` (one row per run,
each written atomically by `gyrodrift.files.atomic.atomic_write`). A run is done when its file is whole and holds
that run (`CampaignStore.verify`, checked on every resume and read); a rerun skips it and runs a damaged one
again, so an interrupted campaign (SIGINT, kill -9 of the client or of a worker) resumes without duplicates or
half-written runs. A campaign whose every run is too short is refused before anything is simulated
(`check_feasible`). The results are one Parquet dataset (`read_runs`, ``pyarrow.dataset`` over ``DIR/runs``).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import hashlib
import importlib.util
import json
import math
import multiprocessing
import os
import re
import socket
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gyrodrift.errors import GyrodriftError, InputError, OptionError, OutputError
from gyrodrift.files.toml_input import read_toml
from gyrodrift.runs.table import SMOOTHER_THERMAL_COLUMNS

__all__ = [
    "CAMPAIGN_FORMAT",
    "Campaign",
    "CampaignError",
    "CampaignFailedError",
    "CampaignRuns",
    "CampaignStore",
    "CampaignSummary",
    "Distribution",
    "NOISE_KEYS",
    "check_feasible",
    "linear_error_nmi",
    "load_campaign",
    "process_run",
    "read_runs",
    "run_campaign",
    "run_table",
    "trial_drift_deg_h",
    "write_run_table",
]

CAMPAIGN_FORMAT = "gyrodrift-campaign/1"
DISTRIBUTIONS = {
    "uniform": ("low", "high"),
    "normal": ("mean", "std"),
    "log_uniform": ("low", "high"),
    "choice": ("values",),
}
NOISE_KEYS = {
    "arw_deg_rth": "gyro",
    "bias_instability_deg_h": "gyro",
    "correlation_s": "gyro",
    "rrw_deg_h_rth": "gyro",
    "vrw_ug_rthz": "accel",
}
"""Noise-grade keys and the scenario section each sets; the noise-free twin sets every one but correlation_s to 0."""
TWIN_OFF = ("arw_deg_rth", "bias_instability_deg_h", "rrw_deg_h_rth", "vrw_ug_rthz")
BOOL_COLUMNS = ("truth_verified", "label_flagged")
"""The yes/no columns of a run (empty when unknown)."""
STAGES = ("align", "passes", "smoother", "twin")
"""The timed stages of a run (columns ``t_STAGE_s`` wall and ``cpu_STAGE_s`` CPU seconds, and ``_total``)."""
TIMELINE_KEYS = ("align_h", "features_h", "truth_h")
"""`[options]` keys shortening the procedure's time line (tests and quick looks; default 4 h, 12 h, 72 h)."""
_PATH_RE = re.compile(r"^(?P<section>[a-z_]+)\.(?P<key>[a-z0-9_]+)(?:\[(?P<index>[0-9]+)\])?$")
_RUN_FILE_RE = re.compile(r"^run-(?P<index>[0-9]{6})\.parquet$")
CURVE_COLUMNS = ("curve_t_h", "curve_north0_m", "curve_east0_m", "curve_north_per_deg_h", "curve_east_per_deg_h")
"""The linear 72 h error curves of a run (float32 lists): time since the end of alignment [h], uncompensated
north/east position error [m], and their change per deg/h of compensated z drift [m/(deg/h)]."""


class CampaignError(InputError):
    """A campaign file or folder that cannot be used (the message names the file and key)."""


class CampaignFailedError(GyrodriftError, RuntimeError):
    """Every run of a campaign failed (the message says how many and the first error)."""


@dataclass(frozen=True)
class Distribution:
    """One parameter's distribution: ``kind`` in ``DISTRIBUTIONS`` and its arguments."""

    kind: str
    args: tuple[Any, ...]

    def sample(self, rng: np.random.Generator) -> Any:
        """One draw (a float, or one of the ``choice`` values)."""
        if self.kind == "uniform":
            return float(rng.uniform(self.args[0], self.args[1]))
        if self.kind == "normal":
            return float(rng.normal(self.args[0], self.args[1]))
        if self.kind == "log_uniform":
            return float(math.exp(rng.uniform(math.log(self.args[0]), math.log(self.args[1]))))
        values = self.args[0]
        return values[int(rng.integers(len(values)))]

    def to_dict(self) -> dict[str, Any]:
        return {"dist": self.kind, **dict(zip(DISTRIBUTIONS[self.kind], self.args, strict=True))}


@dataclass(frozen=True)
class RunSpec:
    """What defines run ``index``: its id, simulator seed, sampled parameters and scenario mapping."""

    index: int
    run: str
    seed: int
    params: dict[str, Any]
    grade: str | None
    scenario: dict[str, dict[str, Any]]


@dataclass(frozen=True)
class Campaign:
    """A validated campaign (`load_campaign`). ``source`` names the file in error messages."""

    name: str
    count: int
    seed: int
    base: dict[str, dict[str, Any]]
    vary: dict[str, Distribution]
    grades: dict[str, dict[str, float]] = field(default_factory=dict)
    source: str = "<campaign>"
    options: dict[str, Any] = field(default_factory=dict)

    def resolved(self) -> dict[str, Any]:
        """The content that defines the runs (JSON-able); two campaigns with the same one give the same runs."""
        return {
            "format": CAMPAIGN_FORMAT,
            "name": self.name,
            "count": self.count,
            "seed": self.seed,
            "base": self.base,
            "grades": self.grades,
            "vary": {k: v.to_dict() for k, v in sorted(self.vary.items())},
            "options": self.options,
        }

    def digest(self) -> str:
        """SHA-256 of `resolved` (canonical JSON): what a store compares to refuse another campaign."""
        text = json.dumps(self.resolved(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    @property
    def param_names(self) -> list[str]:
        """The varied parameters in sampling order (sorted paths; ``grade`` last)."""
        return sorted(k for k in self.vary if k != "grade") + (["grade"] if "grade" in self.vary else [])

    def spec(self, index: int) -> RunSpec:
        """Run `index`: parameters drawn from ``SeedSequence(seed, spawn_key=(index,))``."""
        if not 0 <= index < self.count:
            raise OptionError(f"run {index} is not in this campaign (0 .. {self.count - 1})")
        ss = np.random.SeedSequence(self.seed, spawn_key=(index,))
        params_ss, noise_ss = ss.spawn(2)
        rng = np.random.default_rng(params_ss)
        seed = int(noise_ss.generate_state(1, np.uint64)[0] >> np.uint64(1))  # 63 bits: an int64 column
        scenario = json.loads(json.dumps(self.base))
        scenario.setdefault("run", {})["seed"] = seed
        params: dict[str, Any] = {}
        grade = None
        defaults = self.base_defaults()
        for name in self.param_names:
            value = self.vary[name].sample(rng)
            params[name] = value
            if name == "grade":
                grade = str(value)
                for key, v in self.grades[grade].items():
                    scenario.setdefault(NOISE_KEYS[key], {})[key] = v
            else:
                _set_path(scenario, name, value, defaults)
        return RunSpec(index, run_id(index), seed, params, grade, scenario)

    def base_defaults(self) -> dict[str, dict[str, Any]]:
        from gyrodrift.ins.scenario import Scenario

        return Scenario().to_toml_dict()

    def scenario(self, index: int, *, noise: bool = True):
        """The `gyrodrift.ins.Scenario` of run `index`; ``noise=False`` is its noise-free twin."""
        from gyrodrift.ins.scenario import Scenario

        data = self.spec(index).scenario
        if not noise:
            for key in TWIN_OFF:
                data.setdefault(NOISE_KEYS[key], {})[key] = 0.0
        return Scenario.from_dict(data, source=f"{self.source} run {index}")


def run_id(index: int) -> str:
    """The run's id in tables and file names: ``r000042``."""
    return f"r{index:06d}"


def _set_path(scenario: dict, path: str, value: Any, defaults: Mapping[str, Mapping[str, Any]]) -> None:
    m = _PATH_RE.match(path)
    assert m is not None  # checked by load_campaign
    sec, key, index = m["section"], m["key"], m["index"]
    table = scenario.setdefault(sec, {})
    if index is None:
        table[key] = value
    else:
        vec = list(table.get(key, defaults[sec][key]))
        vec[int(index)] = value
        table[key] = vec


def _fail(source: str, key: str, msg: str) -> CampaignError:
    return CampaignError(f"{source}: {key}: {msg}")


def _number(source: str, where: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise _fail(source, where, f"expected a finite number, got {v!r}")
    return float(v)


def _distribution(source: str, where: str, table: Any) -> Distribution:
    if not isinstance(table, dict):
        raise _fail(source, where, f"expected a table with dist = one of {', '.join(DISTRIBUTIONS)}")
    kind = table.get("dist")
    if kind not in DISTRIBUTIONS:
        raise _fail(source, f"{where}.dist", f"expected one of {', '.join(DISTRIBUTIONS)}, got {kind!r}")
    names = DISTRIBUTIONS[kind]
    unknown = sorted(set(table) - {"dist", *names})
    missing = [n for n in names if n not in table]
    if unknown or missing:
        raise _fail(
            source,
            where,
            f"dist = {kind!r} takes {', '.join(names)}" + (f"; unknown {unknown[0]!r}" if unknown else ""),
        )
    if kind == "choice":
        values = table["values"]
        if not isinstance(values, list) or not values:
            raise _fail(source, f"{where}.values", "expected a non-empty list")
        return Distribution(kind, (tuple(values),))
    a, b = (_number(source, f"{where}.{n}", table[n]) for n in names)
    if kind == "normal" and not b >= 0:
        raise _fail(source, f"{where}.std", f"must be >= 0, got {b:g}")
    if kind in ("uniform", "log_uniform") and not a <= b:
        raise _fail(source, f"{where}.high", f"must be >= low ({a:g}), got {b:g}")
    if kind == "log_uniform" and not a > 0:
        raise _fail(source, f"{where}.low", f"must be > 0 for log_uniform, got {a:g}")
    return Distribution(kind, (a, b))


def parse_campaign(data: Mapping[str, Any], source: str = "<campaign>") -> Campaign:
    """Validate a TOML-shaped mapping into a `Campaign` (every error names `source` and the key)."""
    from gyrodrift.ins.scenario import Scenario

    unknown = sorted(set(data) - {"campaign", "base", "vary", "grades", "options"})
    if unknown:
        raise _fail(source, f"[{unknown[0]}]", "unknown section (expected campaign, base, vary, grades, options)")
    head = data.get("campaign", {})
    if not isinstance(head, dict):
        raise _fail(source, "[campaign]", "expected a table")
    bad = sorted(set(head) - {"name", "count", "seed"})
    if bad:
        raise _fail(source, f"[campaign] {bad[0]}", "unknown key (expected name, count, seed)")
    count, seed = head.get("count"), head.get("seed", 0)
    for key, v in (("count", count), ("seed", seed)):
        if isinstance(v, bool) or not isinstance(v, int) or v < (1 if key == "count" else 0):
            raise _fail(source, f"[campaign] {key}", f"expected an integer >= {1 if key == 'count' else 0}, got {v!r}")
    assert isinstance(count, int) and isinstance(seed, int)  # checked just above
    if count > 1_000_000:
        raise _fail(source, "[campaign] count", f"at most 1000000 runs, got {count}")
    name = head.get("name", Path(source).stem)
    if not isinstance(name, str):
        raise _fail(source, "[campaign] name", f"expected a string, got {name!r}")
    base = data.get("base", {})
    if not isinstance(base, dict):
        raise _fail(source, "[base]", "expected a scenario table (docs/scenarios.md)")
    Scenario.from_dict(base, source=f"{source}: [base]")  # scenario errors name the file and key
    defaults = Scenario().to_toml_dict()
    grades: dict[str, dict[str, float]] = {}
    for gname, g in (data.get("grades") or {}).items():
        if not isinstance(g, dict) or not g:
            raise _fail(source, f"[grades.{gname}]", f"expected a table of {', '.join(NOISE_KEYS)}")
        for key, v in g.items():
            if key not in NOISE_KEYS:
                raise _fail(
                    source, f"[grades.{gname}] {key}", f"unknown noise key (expected one of {', '.join(NOISE_KEYS)})"
                )
            _number(source, f"[grades.{gname}] {key}", v)
        grades[gname] = {k: float(v) for k, v in g.items()}
    vary: dict[str, Distribution] = {}
    for path, table in (data.get("vary") or {}).items():
        where = f'[vary."{path}"]'
        dist = _distribution(source, where, table)
        if path == "grade":
            if dist.kind != "choice":
                raise _fail(source, f"{where}.dist", "the noise grade takes dist = 'choice' over [grades] names")
            for v in dist.args[0]:
                if v not in grades:
                    raise _fail(
                        source, f"{where}.values", f"unknown grade {v!r} (defined: {', '.join(grades) or 'none'})"
                    )
        else:
            m = _PATH_RE.match(path)
            if m is None or m["section"] not in defaults or m["key"] not in defaults[m["section"]]:
                raise _fail(source, where, "expected a scenario key SECTION.KEY or SECTION.KEY[i] of docs/scenarios.md")
            if m["key"] == "seed":
                raise _fail(source, where, "the seed of each run derives from [campaign] seed; it is not varied")
            default = defaults[m["section"]][m["key"]]
            if isinstance(default, list) != (m["index"] is not None):
                raise _fail(
                    source,
                    where,
                    f"{'a vector key takes an index [i]' if isinstance(default, list) else 'not a vector key'}",
                )
            if m["index"] is not None and int(m["index"]) >= len(default):
                raise _fail(source, where, f"index out of range (the key has {len(default)} elements)")
            for value in (
                dist.args[0] if dist.kind == "choice" else dist.args[:1] if dist.kind == "normal" else dist.args
            ):
                trial = json.loads(json.dumps(base))
                _set_path(trial, path, value, defaults)
                try:
                    Scenario.from_dict(trial, source="")
                except InputError as exc:
                    raise _fail(
                        source, where, f"the value {value!r} makes no valid run: {str(exc).lstrip(': ')}"
                    ) from None
        vary[path] = dist
    if grades and "grade" not in vary:
        raise _fail(source, "[vary.grade]", "grades are defined but no [vary.grade] chooses among them")
    options = dict(data.get("options") or {})
    bad = sorted(set(options) - {"smoother", "verify", *TIMELINE_KEYS})
    if bad:
        raise _fail(
            source, f"[options] {bad[0]}", f"unknown key (expected smoother, verify, {', '.join(TIMELINE_KEYS)})"
        )
    for key in ("smoother", "verify"):
        if key in options and not isinstance(options[key], bool):
            raise _fail(source, f"[options] {key}", f"expected true or false, got {options[key]!r}")
    for key in TIMELINE_KEYS:
        if key in options:
            v = _number(source, f"[options] {key}", options[key])
            if not v > 0 or (key == "features_h" and v != int(v)):
                raise _fail(
                    source,
                    f"[options] {key}",
                    f"expected {'whole ' if key == 'features_h' else ''}hours > 0, got {v:g}",
                )
    try:
        _timeline(options)
    except ValueError as exc:
        raise _fail(source, "[options]", str(exc)) from None
    campaign = Campaign(name, count, seed, base, vary, grades, source, options)
    campaign.scenario(0)  # a sampled run must be a valid scenario too (errors name the run)
    return campaign


def _largest(dist: Distribution) -> float:
    """The largest value `dist` can draw (inf when unbounded: a normal with std > 0; NaN for a non-number)."""
    if dist.kind == "choice":
        values = [v for v in dist.args[0] if isinstance(v, int | float) and not isinstance(v, bool)]
        return float(max(values)) if len(values) == len(dist.args[0]) else math.nan
    if dist.kind == "normal":
        return float(dist.args[0]) if dist.args[1] == 0 else math.inf
    return float(dist.args[1])


def check_feasible(campaign: Campaign) -> None:
    """Refuse, before anything is simulated, a campaign whose every run would fail: runs shorter than the
    procedure's time line (``[options]`` align_h + the longer of features_h and truth_h) by more than one sample
    even at the longest duration the campaign can draw (`CampaignError` naming the keys). Runs of which only
    some are too short are left to fail one by one (their rows carry the error). A moving base (`_check_static`)
    must stand still over that whole time line in every run."""
    timeline = _timeline(campaign.options)
    need_h = timeline.align_h + max(timeline.features_h, timeline.truth_h)
    _check_static(campaign, need_h)
    first = campaign.scenario(0).run
    if "run.duration_h" in campaign.vary:
        longest_h, key = _largest(campaign.vary["run.duration_h"]), '[vary."run.duration_h"]'
    else:
        longest_h = first.duration_h
        key = "[base.run] duration_h" + ("" if "duration_h" in campaign.base.get("run", {}) else " (its default)")
    rate = campaign.vary.get("run.rate_hz")
    if rate is None:
        rates = [first.rate_hz]
    elif rate.kind == "choice":
        rates = [float(v) for v in rate.args[0]]  # numbers: each made a valid scenario (parse_campaign)
    else:  # one sample is longest at the lowest rate: the bounds decide (a normal has none)
        rates = [float(rate.args[0]), float(rate.args[1])] if rate.kind != "normal" else []
    if not rates or not all(math.isfinite(x) for x in [longest_h, *rates]):
        return  # unbounded or not numbers: some run may be long enough
    if all(longest_h * 3600.0 * r + 1.0 < need_h * 3600.0 * r for r in rates):  # short by more than one sample
        names = {k: "" if k in campaign.options else " (default)" for k in ("align_h", *TIMELINE_KEYS[1:])}
        raise _fail(
            campaign.source,
            key,
            f"every run lasts at most {longest_h:g} h, shorter than the {need_h:g} h the procedure needs "
            f"([options] align_h = {timeline.align_h:g}{names['align_h']} + the longer of features_h = "
            f"{timeline.features_h:g}{names['features_h']} and truth_h = {timeline.truth_h:g}{names['truth_h']}): "
            f"give duration_h >= {need_h:g} h or shorten the [options] time line",
        )


def _check_static(campaign: Campaign, need_h: float) -> None:
    """A campaign's procedure is a static base's: a route (``[base.trajectory]`` with segments; not a varied
    key) must not start before `need_h` [h] (the vehicle would move under the alignment, the features or the
    truth, and every run would give a wrong drift without an error). `CampaignError` naming the key otherwise."""
    route = campaign.scenario(0).trajectory
    if route is None or not route.segments or route.static_h >= need_h - 1e-9:
        return
    given = "static_h" in campaign.base.get("trajectory", {})
    raise _fail(
        campaign.source,
        "[base.trajectory] static_h" + ("" if given else " (default)"),
        f"the vehicle drives off at {route.static_h:g} h, before the {need_h:g} h of static base the procedure "
        "needs (align_h + the longer of features_h and truth_h, [options]): a campaign's runs are identified on a "
        f"static base; give static_h >= {need_h:g} h",
    )


def load_campaign(path: str | os.PathLike[str]) -> Campaign:
    """Read and validate a campaign file (TOML); `CampaignError` naming the file and key otherwise."""
    p = Path(path)
    data = read_toml(p, CampaignError, expected="a campaign TOML file")
    return parse_campaign(data, source=str(p))


# --- per-run processing (in the worker) ------------------------------------------------------------------


def _timeline(options: Mapping[str, Any]):
    from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline

    d = DEFAULT_TIMELINE
    return Timeline(
        align_h=float(options.get("align_h", d.align_h)),
        features_h=float(options.get("features_h", d.features_h)),
        truth_h=float(options.get("truth_h", d.truth_h)),
        coarse_s=d.coarse_s,
    )


def smoother_available() -> bool:
    """True once `gyrodrift.procedure.smoother` exists (the 16 h Kalman smoother)."""
    return importlib.util.find_spec("gyrodrift.procedure.smoother") is not None


def _noise_model(scenario):
    """The run's own noise model (its scenario's gyro and accelerometer noise keys), for the smoother and the
    truth's label sigma: a simulated run's noise is known, not measured."""
    from gyrodrift.procedure.noise import SensorNoise

    data = scenario.to_toml_dict()
    return SensorNoise.from_block({"gyro": data["gyro"], "accel": data["accel"]}, source="scenario")


SMOOTHER_COLUMNS = (
    "drift_smoother_deg_h",
    "drift_smoother_std_deg_h",
    *SMOOTHER_THERMAL_COLUMNS,
)
"""The smoother's columns of a run: its drift carried into navigation and 1-sigma [deg/h], and under its thermal
model k_z and its 1-sigma [deg/h/degC], cov(end drift, k_z) [(deg/h)^2/degC] and its prior 1-sigma of k_z
[deg/h/degC] (`gyrodrift.procedure.results.SMOOTHER_THERMAL_COLUMNS`; NaN under the constant model). A store
written before the last four existed reads them as NaN (`read_runs`)."""


def _smoother_step(log, noise, timeline) -> dict[str, float]:
    """The 16 h smoother's ``SMOOTHER_COLUMNS`` (the drift is the end-of-span drift under its thermal model; all
    NaN when the module is absent)."""
    if not smoother_available():
        return dict.fromkeys(SMOOTHER_COLUMNS, math.nan)
    from gyrodrift.procedure.smoother import smooth_log

    res = smooth_log(log, timeline=timeline, noise=noise)
    return {
        "drift_smoother_deg_h": float(res.navigation_drift_deg_h),
        "drift_smoother_std_deg_h": float(res.navigation_drift_std_deg_h),
        **res.thermal_columns(),
    }


def linear_error_nmi(north0_m, east0_m, north_per_deg_h, east_per_deg_h, drift_deg_h) -> np.ndarray:
    """Position error [nmi] after compensating `drift_deg_h` [deg/h], from linear error curves (north/east [m]
    and their sensitivities [m/(deg/h)]; numpy broadcasting)."""
    from gyrodrift.earth import NMI_M

    n = np.asarray(north0_m, float) + drift_deg_h * np.asarray(north_per_deg_h, float)
    e = np.asarray(east0_m, float) + drift_deg_h * np.asarray(east_per_deg_h, float)
    return np.hypot(n, e) / NMI_M


def process_run(campaign: Campaign, index: int, *, chunk_samples: int = 100_000) -> dict[str, Any]:
    """Everything the study needs about run `index`, as one row (see the module docstring); never raises for a
    failing run (the row carries ``error``)."""
    spec = campaign.spec(index)
    row: dict[str, Any] = {"run": spec.run, "index": index, "seed": spec.seed, "grade": spec.grade}
    row.update({param_column(k): v for k, v in spec.params.items() if k != "grade"})
    row["worker"] = f"{socket.gethostname()}-{os.getpid()}"
    t_start, cpu_start = time.perf_counter(), time.process_time()
    try:
        row.update(_measure(campaign, index, chunk_samples))
        row["error"] = None
    except Exception as exc:  # a failed run is a row with its error; the campaign goes on
        row["error"] = f"{type(exc).__name__}: {' '.join(str(exc).split())}"[:2000]
    row["t_total_s"] = time.perf_counter() - t_start
    row["cpu_total_s"] = time.process_time() - cpu_start
    return row


def param_column(name: str) -> str:
    """The run-table column of a varied parameter: ``site.lat_deg`` -> ``param_site_lat_deg``."""
    return "param_" + re.sub(r"[^a-z0-9_]+", "_", name).strip("_")


def trial_drift_deg_h(scenario, timeline) -> float:
    """Where a run's truth is linearised [deg/h]: the scenario's z drift (constant + temperature law) averaged over
    the truth span. A numerical choice only (the truth is still found by navigating and minimising): a trial
    within about 5e-4 deg/h of the answer makes the first linearisation exact to about 1e-7 deg/h, so the
    truth needs no verification read. 0.001 deg/h (`find_true_drift`'s default) when that average is within
    1e-4 deg/h of 0 or not finite."""
    t = scenario.temperature
    t_h = np.linspace(timeline.align_h, timeline.align_h + timeline.truth_h, 1001)
    with np.errstate(all="ignore"):
        if t.series_t_h is not None and t.series_temp_c is not None:
            temp = np.interp(t_h, np.asarray(t.series_t_h, float), np.asarray(t.series_temp_c, float))
        else:
            temp = t.end_c + (t.start_c - t.end_c) * np.exp(-t_h / t.tau_h)
        dtemp = temp - t.t0_c
        law = t.k1_deg_h_per_c * dtemp + t.k2_deg_h_per_c2 * dtemp**2 + t.k3_deg_h_per_c_per_h * np.gradient(temp, t_h)
        d = float(scenario.gyro.bias_deg_h[2] + np.mean(law))
    return d if math.isfinite(d) and abs(d) >= 1e-4 else 1e-3


@contextlib.contextmanager
def _stage(out: dict[str, Any], name: str) -> Iterator[None]:
    """Time a stage of a run into ``out``: ``t_NAME_s`` wall and ``cpu_NAME_s`` CPU seconds (the process's CPU
    time, which is the run's: a run keeps to one thread, ``threads=1`` on every read)."""
    w, c = time.perf_counter(), time.process_time()
    try:
        yield
    finally:
        out[f"t_{name}_s"] = time.perf_counter() - w
        out[f"cpu_{name}_s"] = time.process_time() - c


def _measure(campaign: Campaign, index: int, chunk_samples: int) -> dict[str, Any]:
    from gyrodrift.ins.simulate import scenario_log
    from gyrodrift.procedure import align_log, extract_features, find_true_drift, navigate_after_alignment
    from gyrodrift.procedure.truth import minimise_linear_criterion

    verify = bool(campaign.options.get("verify", False))
    out: dict[str, Any] = {}
    scn = campaign.scenario(index)
    out["arw_deg_rth"] = scn.gyro.arw_deg_rth
    out["vrw_ug_rthz"] = scn.accel.vrw_ug_rthz
    log = scenario_log(scn)
    timeline = _timeline(campaign.options)
    with _stage(out, "align"):
        alignment = align_log(log, timeline=timeline, chunk_samples=chunk_samples)
    with _stage(out, "passes"):
        noise = _noise_model(scn)
        truth_options: dict[str, Any] = {"threads": 1}  # a run keeps to one core: workers give the parallelism
        if not verify:  # one read: the features, and the truth linearised between 0 and the trial drift
            truth_options.update(verify=False, trial_deg_h=trial_drift_deg_h(scn, timeline))
        f = extract_features(
            log,
            with_truth=True,
            timeline=timeline,
            alignment=alignment,
            smoother=False,  # timed on its own below
            noise=noise,
            truth_options=truth_options,
            chunk_samples=chunk_samples,
        )
        truth = f.truth
        assert truth is not None and truth.base is not None and truth.trial is not None  # find_true_drift sets them
        base, d_star = truth.base, truth.drift_deg_h
        n0, e0 = base.north_m, base.east_m
        if not verify:  # the secant of the read: 0 -> trial, within about 5e-4 deg/h of d*
            gn = (truth.trial.north_m - n0) / truth.trial_deg_h
            ge = (truth.trial.east_m - e0) / truth.trial_deg_h
        else:
            opt = truth.optimum
            assert opt is not None
            if abs(d_star) >= 2e-4:  # the secant 0 -> d*: exact at both ends, estimates fall between or near them
                gn, ge = (opt.north_m - n0) / d_star, (opt.east_m - e0) / d_star
            else:  # too close to 0 for a secant: one more pass 0.001 deg/h away from d*, curves about d = 0
                extra = navigate_after_alignment(
                    log, alignment, [d_star + 1e-3], truth.hours, threads=1, chunk_samples=chunk_samples
                ).curves[0]
                gn, ge = (extra.north_m - opt.north_m) / 1e-3, (extra.east_m - opt.east_m) / 1e-3
                n0, e0 = opt.north_m - d_star * gn, opt.east_m - d_star * ge
    out.update(
        lat0_deg=f.lat0_deg,
        lat_deg=f.lat_deg,
        temp_start_c=f.temp_start_c,
        temp_end_c=f.temp_end_c,
        temp_min_c=f.temp_min_c,
        temp_max_c=f.temp_max_c,
        drift_deg_h=d_star,
        drift_std_deg_h=float(truth.drift_std_deg_h),
        label_flagged=bool(truth.flagged),
        truth_verified=bool(truth.verified) if verify else None,
        drift_curvefit_deg_h=f.drift_curvefit_deg_h,
        drift_curvefit_std_deg_h=f.drift_curvefit_std_deg_h,
        drift_align_deg_h=alignment.gyro_bias_deg_h[2],
        drift_align_std_deg_h=alignment.gyro_bias_std_deg_h[2],
        uncompensated_final_nmi=truth.uncompensated_nmi,
        hours_truth=truth.hours,
    )
    out.update(
        curve_t_h=np.asarray(base.t_h, np.float32).tolist(),
        curve_north0_m=np.asarray(n0, np.float32).tolist(),
        curve_east0_m=np.asarray(e0, np.float32).tolist(),
        curve_north_per_deg_h=np.asarray(gn, np.float32).tolist(),
        curve_east_per_deg_h=np.asarray(ge, np.float32).tolist(),
    )
    # --- the 16 h smoother: its own read of the first 16 h (a seventh of a run's simulation) ---
    out.update(dict.fromkeys(SMOOTHER_COLUMNS, math.nan))
    out["smoother_error"] = None
    with _stage(out, "smoother"):
        if campaign.options.get("smoother", True):
            try:  # a smoother failure is recorded beside the run's other results, which stay valid
                out.update(_smoother_step(log, noise, timeline))
            except Exception as exc:
                out["smoother_error"] = f"{type(exc).__name__}: {' '.join(str(exc).split())}"[:2000]
    # --- the noise-free twin: aligned on its own, navigated once at d* ---
    with _stage(out, "twin"):
        twin_scn = campaign.scenario(index, noise=False)
        twin_log = scenario_log(twin_scn)
        if verify:
            twin = find_true_drift(
                twin_log, timeline=timeline, noise=_noise_model(twin_scn), threads=1, chunk_samples=chunk_samples
            )
            out["drift_effective_deg_h"] = twin.drift_deg_h
        else:  # the twin's error differs from the run's by the noise's effect: its sensitivity to the drift is the
            # run's (same site, motion and sensor model), so one pass at d* and one linear step give its optimum
            twin_alignment = align_log(twin_log, timeline=timeline, chunk_samples=chunk_samples)
            at = navigate_after_alignment(
                twin_log, twin_alignment, [d_star], truth.hours, threads=1, chunk_samples=chunk_samples
            ).curves[0]
            step = minimise_linear_criterion(at.north_m, at.east_m, gn, ge, truth.criterion)
            out["drift_effective_deg_h"] = d_star + step
    return out


# --- the store -----------------------------------------------------------------------------------------


def _schema(campaign: Campaign):
    import pyarrow as pa

    f64, s = pa.float64(), pa.string()
    fields = [("run", s), ("index", pa.int64()), ("seed", pa.int64()), ("grade", s)]
    for name in campaign.param_names:
        if name == "grade":
            continue
        kind = campaign.vary[name]
        numeric = kind.kind != "choice" or all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in kind.args[0]
        )
        fields.append((param_column(name), f64 if numeric else s))
    fields += [(c, f64) for c in ("arw_deg_rth", "vrw_ug_rthz", "lat0_deg", "lat_deg")]
    fields += [(c, f64) for c in ("temp_start_c", "temp_end_c", "temp_min_c", "temp_max_c")]
    fields += [
        (c, f64)
        for c in (
            "drift_deg_h",
            "drift_std_deg_h",
            "drift_effective_deg_h",
            "drift_curvefit_deg_h",
            "drift_curvefit_std_deg_h",
            *SMOOTHER_COLUMNS,
            "drift_align_deg_h",
            "drift_align_std_deg_h",
            "uncompensated_final_nmi",
            "hours_truth",
        )
    ]
    fields += [(c, pa.bool_()) for c in BOOL_COLUMNS]
    fields += [(f"{k}_{c}_s", f64) for k in ("t", "cpu") for c in STAGES + ("total",)]
    fields += [("error", s), ("smoother_error", s), ("worker", s)]
    fields += [(c, pa.list_(pa.float32())) for c in CURVE_COLUMNS]
    return pa.schema(fields)


def _parquet_recogniser(head: bytes) -> bool:
    return head.startswith(b"PAR1")


@dataclass
class CampaignSummary:
    """What a `run_campaign` call did: runs total, already done before, done now, failed now, lost to broken
    workers, seconds, and whether a Ctrl-C stopped it before every run was done."""

    total: int
    skipped: int
    done: int
    failed: int
    lost: int
    elapsed_s: float
    interrupted: bool = False
    failed_before: int = 0
    """Of the `skipped` runs, those committed with an error."""
    redone: dict[int, str] = field(default_factory=dict)
    """The damaged run files found on resume (index -> what was wrong), run again."""
    first_error: str | None = None
    """The error of the lowest-index run that failed now (None when none did)."""

    @property
    def succeeded(self) -> int:
        """Runs of the store that finished without an error (committed before or now)."""
        return self.skipped - self.failed_before + self.done - self.failed


class CampaignStore:
    """The campaign folder: ``campaign.toml``, ``campaign.json`` and ``runs/run-NNNNNN.parquet``."""

    def __init__(self, path: str | os.PathLike[str]):
        self.path = Path(path)
        self.runs_dir = self.path / "runs"

    @classmethod
    def create_or_open(cls, path: str | os.PathLike[str], campaign: Campaign, text: str) -> CampaignStore:
        """Open the store of `campaign` at `path`, creating it if new or empty; refuse a folder holding another
        campaign or anything else (`OutputError`)."""
        from gyrodrift.files.atomic import atomic_write, atomic_write_json, recognise_json_format

        store = cls(path)
        p = store.path
        if p.exists() and not p.is_dir():
            raise OutputError(f"{p}: is a file, not a folder; give a new or empty folder to --out")
        manifest = p / "campaign.json"
        if manifest.exists():
            doc = store.manifest()
            if doc.get("digest") != campaign.digest():
                raise OutputError(
                    f"{p}: holds campaign {doc.get('name')!r} ({doc.get('source')}), not {campaign.source}; give "
                    "another --out folder (a campaign resumes only into its own folder)"
                )
            return store
        if p.exists() and any(p.iterdir()):
            raise OutputError(f"{p}: is not empty and holds no campaign; give a new or empty --out folder")
        store.runs_dir.mkdir(parents=True, exist_ok=True)
        with atomic_write(p / "campaign.toml", what="campaign file") as fh:
            fh.write(text)
        doc = {
            "format": CAMPAIGN_FORMAT,
            "name": campaign.name,
            "source": campaign.source,
            "digest": campaign.digest(),
            "resolved": campaign.resolved(),
        }
        atomic_write_json(doc, manifest, recognise=recognise_json_format(CAMPAIGN_FORMAT), what="campaign manifest")
        return store

    def manifest(self) -> dict[str, Any]:
        p = self.path / "campaign.json"
        try:
            doc = json.loads(p.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise InputError(f"{self.path}: not a campaign folder (no campaign.json)") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InputError(f"{p}: not a campaign manifest: {exc}") from None
        if not isinstance(doc, dict) or doc.get("format") != CAMPAIGN_FORMAT:
            raise InputError(f"{p}: not a campaign manifest (format {CAMPAIGN_FORMAT} expected)")
        return doc

    def campaign(self) -> Campaign:
        """The campaign of this folder (from its ``campaign.toml``)."""
        self.manifest()
        return load_campaign(self.path / "campaign.toml")

    def run_path(self, index: int) -> Path:
        return self.runs_dir / f"run-{index:06d}.parquet"

    def done(self) -> set[int]:
        """Indices of the run files present (committed whole by `write`; `verify` checks what they hold)."""
        if not self.runs_dir.is_dir():
            return set()
        return {int(m["index"]) for e in os.listdir(self.runs_dir) if (m := _RUN_FILE_RE.match(e))}

    def check_run(self, index: int, *, full: bool = False) -> tuple[str | None, bool]:
        """``(problem, ok)`` of run file `index`: ``problem`` None when it is a whole, readable Parquet file of
        exactly one row holding run `index` (its footer and metadata read, its index, run and error columns
        decoded; `full`: every column), else what is wrong (a truncated file, another run's row, an unreadable
        column); ``ok``: that row has no error."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        path = self.run_path(index)
        try:
            table = pq.ParquetFile(path).read(columns=None if full else ["index", "run", "error"])
        except (pa.ArrowException, OSError, ValueError) as exc:
            return f"not a readable Parquet file ({' '.join(str(exc).split())[:200] or type(exc).__name__})", False
        if table.num_rows != 1:
            return f"holds {table.num_rows} rows, one run expected", False
        missing = [c for c in ("index", "run", "error") if c not in table.column_names]
        if missing:
            return f"has no column {missing[0]}", False
        row = {c: table.column(c)[0].as_py() for c in ("index", "run", "error")}
        if row["index"] != index or row["run"] != run_id(index):
            return f"holds run {row['run']!r} (index {row['index']!r}), not {run_id(index)}", False
        return None, row["error"] is None

    def verify(self, *, full: bool = False) -> tuple[dict[int, bool], dict[int, str]]:
        """Check every run file (`check_run`): ``(good, damaged)``, ``good`` maps a whole run's index to True
        when it succeeded (False: a failed run, its error recorded), ``damaged`` a damaged one's to what is
        wrong. About 0.6 ms of CPU a file (`full`: every column decoded, about 2 ms)."""
        good: dict[int, bool] = {}
        damaged: dict[int, str] = {}
        for i in sorted(self.done()):
            problem, ok = self.check_run(i, full=full)
            if problem is None:
                good[i] = ok
            else:
                damaged[i] = problem
        return good, damaged

    def write(self, row: Mapping[str, Any], schema) -> None:
        """Commit one run atomically (temporary, fsync, rename): a kill leaves the run absent or whole."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        from gyrodrift.files.atomic import atomic_write

        path = self.run_path(int(row["index"]))
        table = pa.Table.from_pylist([{k: row.get(k) for k in schema.names}], schema=schema)
        with atomic_write(path, "wb", recognise=_parquet_recogniser, what="campaign run") as fh:
            pq.write_table(table, fh, compression="zstd")


@dataclass
class CampaignRuns:
    """The committed runs of a campaign as columns (`read_runs`), sorted by run index.

    ``columns``: one numpy array per scalar column (strings and missing values as object arrays);
    ``curves``: the linear error curves (``CURVE_COLUMNS``) as float64 arrays of shape (runs, points), or None.
    """

    columns: dict[str, np.ndarray]
    curves: dict[str, np.ndarray] | None = None

    def __len__(self) -> int:
        return len(self.columns["index"])

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def numbers(self, name: str) -> np.ndarray:
        """A numeric column as float64 (missing = NaN)."""
        return np.array([math.nan if v is None else v for v in self.columns[name]], dtype=float)

    @property
    def ok(self) -> np.ndarray:
        """Mask of the runs that finished without an error."""
        return np.array([e is None for e in self.columns["error"]], dtype=bool)

    def select(self, which) -> CampaignRuns:
        """The runs at indices or mask `which` (a new object)."""
        which = np.asarray(which)
        curves = None if self.curves is None else {k: v[which] for k, v in self.curves.items()}
        return CampaignRuns({k: v[which] for k, v in self.columns.items()}, curves)

    def errors_nmi(self, drift_deg_h) -> np.ndarray:
        """Position error [nmi], shape (runs, points), after compensating `drift_deg_h` [deg/h] per run, from the
        linear curves: ``hypot(n0 + d gn, e0 + d ge)`` (a static base: the error is linear in the drift)."""
        if self.curves is None:
            raise ValueError("the runs were read without their curves")
        d = np.asarray(drift_deg_h, float).reshape(-1, 1)
        c = self.curves
        return linear_error_nmi(
            c["curve_north0_m"], c["curve_east0_m"], c["curve_north_per_deg_h"], c["curve_east_per_deg_h"], d
        )


def read_runs(path: str | os.PathLike[str], *, curves: bool = True) -> CampaignRuns:
    """All committed runs of a campaign folder (one Parquet dataset over ``DIR/runs``), sorted by run index;
    ``curves=False`` leaves out the linear error curves. ``pyarrow.dataset.dataset(DIR / "runs")`` reads the
    same rows with any Parquet tool (pandas, polars)."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.dataset as ds

    store = CampaignStore(path)
    store.manifest()
    if not store.runs_dir.is_dir():
        raise InputError(f"{store.runs_dir}: no such folder: {store.path} is a campaign folder without its runs/")
    good, damaged = store.verify()
    _raise_damaged(store, damaged)
    campaign = store.campaign()
    files = [str(store.run_path(i)) for i in sorted(good)]  # the run files only: any other file there is not read
    try:
        # one schema over every run file and the current code's: a store written before a column existed
        # (resumed by newer code, or read as it is) gets that column as null in its older runs, whichever file
        # comes first
        found = ds.dataset(files, format="parquet")
        schemas = [f.physical_schema for f in found.get_fragments()] + [_schema(campaign)]
        dataset = ds.dataset(files, format="parquet", schema=pa.unify_schemas(schemas))
        names = [n for n in dataset.schema.names if n not in CURVE_COLUMNS]
        table = dataset.to_table(columns=names + (list(CURVE_COLUMNS) if curves else []))
    except (pa.ArrowException, OSError, ValueError) as exc:  # a column the quick check did not decode
        _raise_damaged(store, store.verify(full=True)[1])
        reason = " ".join(str(exc).split())
        raise InputError(f"{store.runs_dir}: the run files do not read as one table: {reason}") from None
    table = table.take(pc.sort_indices(table, [("index", "ascending")]))
    cols: dict[str, np.ndarray] = {}
    for n in names:
        col = table.column(n)
        t = col.type
        if col.null_count == 0 and (pa.types.is_floating(t) or pa.types.is_integer(t) or pa.types.is_boolean(t)):
            cols[n] = col.to_numpy()
        else:
            cols[n] = np.array(col.to_pylist(), dtype=object)
    curve_arrays = None
    if curves:
        curve_arrays = {}
        for n in CURVE_COLUMNS:
            lists = table.column(n).to_pylist()
            width = max((len(x) for x in lists if x is not None), default=0)
            arr = np.full((len(lists), width), np.nan)
            for i, x in enumerate(lists):
                if x is not None:
                    arr[i, : len(x)] = x
            curve_arrays[n] = arr
    return CampaignRuns(cols, curve_arrays)


def _raise_damaged(store: CampaignStore, damaged: Mapping[int, str]) -> None:
    """`InputError` naming the first damaged run file of `store` (and how many), if any."""
    if damaged:
        first = min(damaged)
        more = f" ({len(damaged)} damaged run files in all)" if len(damaged) > 1 else ""
        raise InputError(
            f"{store.run_path(first)}: damaged run file: {damaged[first]}{more}; rerun the campaign command that "
            f"made {store.path} (the same campaign file, --out {store.path}) to run it again"
        )


def run_table(runs: CampaignRuns, source: str = "<campaign>"):
    """The successful `runs` as a `gyrodrift.runs.table.RunTable` (labels: the 72 h truth; optional columns when
    known)."""
    from gyrodrift.runs.table import OPTIONAL_COLUMNS, RunTable

    ok = runs.select(runs.ok)
    base = ("lat_deg", "lat0_deg", "temp_min_c", "temp_max_c", "drift_deg_h")
    num = {k: ok.numbers(k) for k in base + tuple(c for c in OPTIONAL_COLUMNS if c in ok.columns)}
    records = []
    for i, run in enumerate(ok["run"]):
        rec: dict[str, Any] = {"run": str(run)}
        for k, v in num.items():  # a flag (a bool column of the store) stays a bool
            if k in base or math.isfinite(v[i]):
                rec[k] = bool(v[i]) if k in BOOL_COLUMNS else float(v[i])
        records.append(rec)
    return RunTable.from_records(records, source=source)


def write_run_table(
    runs: CampaignRuns, path: str | os.PathLike[str], *, inputs: Iterable[str | os.PathLike[str]] = ()
) -> int:
    """Write the successful `runs` as a run table `gyrodrift fit` reads (``gyrodrift.runs.table``); returns its rows."""
    import csv
    import io

    from gyrodrift.files.atomic import atomic_write
    from gyrodrift.procedure.results import RUN_TABLE_COLUMNS
    from gyrodrift.procedure.writers import RUN_TABLE_RECOGNISER

    ok = runs.select(runs.ok)
    optional = ("drift_std_deg_h", *SMOOTHER_COLUMNS)
    cols = list(RUN_TABLE_COLUMNS) + ["drift_deg_h"]
    cols += [c for c in optional if c not in cols and np.isfinite(ok.numbers(c)).any()]
    values = {c: ok.numbers(c) for c in cols if c != "run"}
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for i, run in enumerate(ok["run"]):
        w.writerow(
            [run if c == "run" else repr(float(values[c][i])) if math.isfinite(values[c][i]) else "" for c in cols]
        )
    with atomic_write(path, inputs=inputs, recognise=RUN_TABLE_RECOGNISER, what="run table") as fh:
        fh.write(buf.getvalue())
    return len(ok)


# --- running ---------------------------------------------------------------------------------------------


def _worker_init(parent_pid: int) -> None:
    """Pool-worker initializer: ignore SIGINT (a Ctrl-C in the terminal reaches the whole process group; the
    client decides: finish the runs in progress, or terminate the workers on a second Ctrl-C), and exit when the
    client that started the pool is gone (kill -9 of the client must not leave workers computing runs nobody will
    commit)."""
    import signal
    import threading

    signal.signal(signal.SIGINT, signal.SIG_IGN)

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="gyrodrift-parent-watch").start()


class _Interrupts:
    """SIGINT during a campaign: the first stops new runs from being submitted (the runs in progress finish and
    are committed; a note on stderr says so), the second raises KeyboardInterrupt (abort at once). Installed only
    on the main thread (signal handlers live there); the previous handler comes back on exit."""

    def __init__(self) -> None:
        self.count = 0
        self.in_progress: Callable[[], int] = lambda: 0
        self.committing = False  # a run is being written: a second Ctrl-C waits for its rename
        self.abort_pending = False
        self._previous: Any = None
        self._installed = False

    @property
    def stopping(self) -> bool:
        return self.count > 0

    def _handle(self, signum, frame) -> None:
        import sys

        self.count += 1
        if self.count > 1:
            if self.committing:
                self.abort_pending = True
                return
            raise KeyboardInterrupt
        n = self.in_progress()
        sys.stderr.write(
            f"\ncampaign: interrupted: no new runs are started; finishing and committing the {n} run(s) in progress "
            "(Ctrl-C again aborts them at once; rerunning the same command resumes)\n"
        )
        sys.stderr.flush()

    def __enter__(self) -> _Interrupts:
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handle)
            self._installed = True
        return self

    def __exit__(self, *exc) -> None:
        import signal

        if self._installed:
            signal.signal(signal.SIGINT, self._previous)


def _abort_note(n: int) -> None:
    import sys

    sys.stderr.write(
        f"\ncampaign: aborted; {n} run(s) in progress were not committed (rerunning the same command resumes)\n"
    )
    sys.stderr.flush()


def _terminate_workers(pool: concurrent.futures.ProcessPoolExecutor) -> None:
    """Stop a pool's worker processes now (they ignore SIGINT). Python 3.14 has ``terminate_workers``; before it,
    the executor's process table."""
    terminate = getattr(pool, "terminate_workers", None)
    if terminate is not None:
        terminate()
        return
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        proc.terminate()


def _pool_round(pool, campaign, queue, workers: int, on_row, interrupts: _Interrupts, finished: set[int]) -> None:
    """Hand out the runs of `queue` to `pool`, at most `workers` at a time, committing each as it finishes
    (into `finished`); returns when all are done or a first Ctrl-C has let the runs in progress finish.
    BrokenProcessPool when a worker died (the runs of the batch that did finish are committed first)."""
    running: dict[concurrent.futures.Future, int] = {}
    interrupts.in_progress = running.__len__

    def refill() -> None:
        while queue and len(running) < workers and not interrupts.stopping:
            i = queue.popleft()
            running[pool.submit(process_run, campaign, i)] = i

    try:
        refill()
        while running:
            done, _ = concurrent.futures.wait(running, return_when=concurrent.futures.FIRST_COMPLETED)
            rows, broken = [], None
            for fut in done:
                i = running.pop(fut)
                try:
                    rows.append((i, fut.result()))
                except concurrent.futures.process.BrokenProcessPool as exc:
                    broken = exc
            if broken is None:
                refill()  # the idle workers start their next runs while the client commits these
            for i, row in rows:
                on_row(row)
                finished.add(i)
            if broken is not None:
                raise broken
    except KeyboardInterrupt:  # a second Ctrl-C
        _abort_note(len(running))
        raise


def _pool_map(campaign, todo, workers, on_row: Callable[[dict], None], interrupts: _Interrupts) -> int:
    """Process `todo` on a local process pool, at most `workers` runs handed out at a time (so a first Ctrl-C
    leaves only the runs in progress to finish). A worker killed mid-run breaks the pool: a new pool takes the
    runs not yet committed (at most 3 times). Returns the number of runs lost to broken pools."""
    from collections import deque

    remaining = list(todo)
    ctx = multiprocessing.get_context("spawn")
    for _attempt in range(4):
        if not remaining or interrupts.stopping:
            return 0
        finished: set[int] = set()
        pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=workers, mp_context=ctx, initializer=_worker_init, initargs=(os.getpid(),)
        )
        try:
            _pool_round(pool, campaign, deque(remaining), workers, on_row, interrupts, finished)
        except concurrent.futures.process.BrokenProcessPool:
            pass
        except BaseException:  # a second Ctrl-C or the client's own failure: the workers stop now
            _terminate_workers(pool)
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        remaining = [i for i in remaining if i not in finished]
        if interrupts.stopping:
            return 0
    return len(remaining)


def _dask_map(campaign, todo, client, on_row: Callable[[dict], None], interrupts: _Interrupts) -> int:
    """Process `todo` on a dask cluster, as many runs handed out at a time as the cluster has threads (so a
    first Ctrl-C leaves only the runs in progress to finish). Returns the runs lost to the infrastructure."""
    from collections import deque

    from dask.distributed import as_completed

    prefix = f"campaign-{campaign.digest()[:8]}"
    queue = deque(todo)
    running: set = set()
    interrupts.in_progress = running.__len__
    flow = as_completed()

    def refill() -> None:
        window = max(1, sum(client.nthreads().values()))
        while queue and len(running) < window and not interrupts.stopping:
            i = queue.popleft()
            fut = client.submit(process_run, campaign, i, pure=False, key=f"{prefix}-{i}")
            running.add(fut)
            flow.add(fut)

    lost = 0
    refill()
    try:
        for fut in flow:
            running.discard(fut)
            refill()  # the idle worker starts its next run while the client commits this one
            try:
                row = fut.result()
            except Exception:  # the infrastructure failed (a worker killed too often): not the run's error
                lost += 1
            else:
                on_row(row)
    except BaseException as exc:
        if isinstance(exc, KeyboardInterrupt):
            _abort_note(len(running))
        client.cancel(list(running))
        raise
    return lost


def run_campaign(
    campaign: Campaign,
    out: str | os.PathLike[str],
    *,
    text: str | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    dask_workers: int | None = None,
    connect_timeout_s: float | None = None,
    quiet: bool = True,
    limit: int | None = None,
) -> CampaignSummary:
    """Process every run of `campaign` not yet committed in `out`, committing each as it finishes.

    Parameters
    ----------
    campaign : Campaign
    out : path-like
        The campaign folder (new, empty, or this campaign's: then finished runs are skipped).
    text : str, optional
        The campaign file's text, copied to ``out/campaign.toml`` (default: re-read from ``campaign.source``).
    workers : int, optional
        Local processes (default: the CPU count); exclusive with `scheduler`/`dask_workers`.
    scheduler : str, optional
        Address of a running dask scheduler (`gyrodrift.fleet.cluster.dask_client`, `connect_timeout_s`).
    dask_workers : int, optional
        A dask LocalCluster with this many workers instead (benchmarks, tests).
    limit : int, optional
        Process at most this many of the pending runs (lowest indices first).
    quiet : bool
        Hide the progress bar (runs done, failures, rate, time left).

    SIGINT (Ctrl-C), when called on the main thread: the first stops new runs (the runs in progress finish and
    are committed; the summary says ``interrupted``), the second aborts at once (KeyboardInterrupt; the runs in
    progress are not committed, a run being written is renamed into place first). A rerun resumes either way.
    """
    from gyrodrift.fleet.cluster import DEFAULT_CONNECT_TIMEOUT_S, dask_client
    from gyrodrift.progress import progress

    if workers is not None and (scheduler is not None or dask_workers is not None):
        raise OptionError("give --workers or --scheduler, not both")
    if workers is not None and workers < 1:
        raise OptionError(f"--workers must be >= 1, got {workers}")
    check_feasible(campaign)
    if text is None:
        text = Path(campaign.source).read_text(encoding="utf-8")
    store = CampaignStore.create_or_open(out, campaign, text)
    schema = _schema(campaign)
    found, broken = store.verify()  # a file numbered past the count is not this campaign's to redo
    good = {i: ok for i, ok in found.items() if i < campaign.count}
    damaged = {i: why for i, why in broken.items() if i < campaign.count}
    _redo_damaged(store, damaged)
    todo = [i for i in range(campaign.count) if i not in good]
    if limit is not None:
        todo = todo[:limit]
    t0 = time.perf_counter()
    counts = {"done": 0, "failed": 0}
    first_error: list[tuple[int, str]] = []
    with _Interrupts() as interrupts, progress(len(todo), f"campaign {campaign.name}", quiet, unit="run") as bar:

        def on_row(row: dict) -> None:
            interrupts.committing = True
            try:
                store.write(row, schema)
            finally:
                interrupts.committing = False
            if interrupts.abort_pending:
                raise KeyboardInterrupt
            counts["done"] += 1
            if row.get("error") is not None:
                counts["failed"] += 1
                first_error[:] = [min(first_error + [(int(row["index"]), f"{row['run']}: {row['error']}")])]
            bar.set_postfix(failed=counts["failed"], refresh=False)
            bar.update(1)

        if not todo:
            lost = 0
        elif scheduler is not None or dask_workers is not None:
            with dask_client(
                workers=dask_workers,
                scheduler=scheduler,
                connect_timeout_s=DEFAULT_CONNECT_TIMEOUT_S if connect_timeout_s is None else connect_timeout_s,
            ) as client:
                lost = _dask_map(campaign, todo, client, on_row, interrupts)
        else:
            lost = _pool_map(campaign, todo, workers or os.cpu_count() or 1, on_row, interrupts)
    return CampaignSummary(
        campaign.count,
        len(good),
        counts["done"],
        counts["failed"],
        lost,
        time.perf_counter() - t0,
        interrupted=interrupts.stopping,
        failed_before=sum(not ok for ok in good.values()),
        redone=damaged,
        first_error=first_error[0][1] if first_error else None,
    )


def _redo_damaged(store: CampaignStore, damaged: Mapping[int, str]) -> None:
    """Before any work: a damaged run file must be one gyrodrift may replace (a regular file with a Parquet head,
    or empty: else `OutputError` naming it, nothing is done); then one line on stderr per file says it is run
    again."""
    import sys

    from gyrodrift.files.atomic import check_output_file

    for i in sorted(damaged):
        path = store.run_path(i)
        if path.is_symlink():  # replacing it would write wherever it points
            raise OutputError(
                f"{path}: damaged ({damaged[i]}) and a symbolic link, not a run file gyrodrift wrote; move it out of "
                f"{store.runs_dir} and rerun"
            )
        check_output_file(path, recognise=_parquet_recogniser, what="campaign run")
    for i in sorted(damaged):
        sys.stderr.write(f"campaign: {store.run_path(i)}: damaged ({damaged[i]}): run {i} is run again\n")
    sys.stderr.flush()
