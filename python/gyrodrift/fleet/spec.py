"""A campaign file (TOML, docs/campaigns.md) -> a validated `Campaign`: what defines every run of a simulated fleet.

A campaign file holds

- ``[campaign]``: ``name``, ``count`` (runs), ``seed`` (integer >= 0);
- ``[base]``: a scenario (the sections and keys of docs/scenarios.md) every run starts from;
- ``[grades.NAME]``: optional noise grades, each a table of noise keys (``arw_deg_rth``, ``vrw_ug_rthz``,
  ``bias_instability_deg_h``, ``correlation_s``, ``rrw_deg_h_rth``) set on the run's gyro/accel;
- ``[vary."SECTION.KEY"]`` or ``[vary."SECTION.KEY[i]"]`` (one element of a vector key) and ``[vary.grade]``:
  a distribution, ``dist`` = ``uniform`` (``low``, ``high``), ``normal`` (``mean``, ``std``), ``log_uniform``
  (``low`` > 0, ``high``) or ``choice`` (``values``, a list);
- ``[options]``: ``smoother``, ``verify`` and the time line's ``align_h``, ``features_h``, ``truth_h`` [h].

Run ``i`` (0-based) draws its parameters and its simulator seed from ``numpy.random.SeedSequence(seed,
spawn_key=(i,))`` (the i-th child of ``SeedSequence(seed).spawn``): any run is regenerated alone, whatever the
count, the order of completion or the workers (`Campaign.scenario`). A campaign whose every run is too short,
or whose vehicle drives off before the procedure's time line ends, is refused before anything is simulated
(`check_feasible`).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gyrodrift.errors import InputError, OptionError
from gyrodrift.files.toml_input import read_toml

__all__ = [
    "CAMPAIGN_FORMAT",
    "Campaign",
    "CampaignError",
    "Distribution",
    "NOISE_KEYS",
    "RunSpec",
    "check_feasible",
    "load_campaign",
    "parse_campaign",
    "run_id",
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
TIMELINE_KEYS = ("align_h", "features_h", "truth_h")
"""`[options]` keys shortening the procedure's time line (tests and quick looks; default 4 h, 12 h, 72 h)."""
_PATH_RE = re.compile(r"^(?P<section>[a-z_]+)\.(?P<key>[a-z0-9_]+)(?:\[(?P<index>[0-9]+)\])?$")


class CampaignError(InputError):
    """A campaign file or folder that cannot be used (the message names the file and key)."""


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

    @property
    def timeline(self):
        """The procedure's `gyrodrift.procedure.timeline.Timeline` for every run: the default one with the
        ``[options]`` align_h, features_h and truth_h [h] given."""
        from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline

        d = DEFAULT_TIMELINE
        return Timeline(
            align_h=float(self.options.get("align_h", d.align_h)),
            features_h=float(self.options.get("features_h", d.features_h)),
            truth_h=float(self.options.get("truth_h", d.truth_h)),
            coarse_s=d.coarse_s,
        )

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
    campaign = Campaign(name, count, seed, base, vary, grades, source, options)
    try:
        campaign.timeline  # noqa: B018 - the time line's own checks (align_h fits the coarse span, ...)
    except ValueError as exc:
        raise _fail(source, "[options]", str(exc)) from None
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
    timeline = campaign.timeline
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
