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
from gyrodrift.files.toml_schema import Choice, Field, Flag, Integer, Number, Scope, fmt_number, show, type_name

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
OPTIONS: dict[str, Field] = {"smoother": Flag(), "verify": Flag(), **dict.fromkeys(TIMELINE_KEYS, Number.positive())}
"""The ``[options]`` keys: the 16 h smoother on (default) or off, the truth verified (off), the time line [h]."""
SECTIONS = ("campaign", "base", "vary", "grades", "options")
MAX_RUNS = 1_000_000
_STD = Number.non_negative()
_LOG_LOW = Number.positive()
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


def _section(root: Scope, data: Mapping[str, Any], name: str) -> Mapping[str, Any]:
    """The ``[name]`` table of `data` ({} when absent), whatever its keys (names of grades, varied paths)."""
    table = data.get(name, {})
    if not isinstance(table, Mapping):
        raise root.fail(None, f"[{name}] must be a table, got {type_name(table)}")
    return table


def _distribution(at: Scope, table: Any) -> Distribution:
    """The distribution of one ``[vary."PATH"]`` table (`at` names it in errors)."""
    if not isinstance(table, Mapping):
        raise at.fail(None, f"expected a table with dist = one of {', '.join(DISTRIBUTIONS)}, got {type_name(table)}")
    kind = Choice(tuple(DISTRIBUTIONS)).read(at, "dist", table.get("dist"))
    names = DISTRIBUTIONS[kind]
    at.keys(table, ("dist", *names), what=f" for dist = {kind!r}")
    at.require(table, names)
    if kind == "choice":
        values = table["values"]
        if not isinstance(values, list) or not values:
            raise at.fail("values", f"expected a non-empty array, got {type_name(values)} {show(values)}")
        return Distribution(kind, (tuple(values),))
    if kind == "normal":
        return Distribution(kind, (Number().read(at, "mean", table["mean"]), _STD.read(at, "std", table["std"])))
    low = (_LOG_LOW if kind == "log_uniform" else Number()).read(at, "low", table["low"])
    high = Number().read(at, "high", table["high"])
    if not low <= high:
        raise at.fail("high", f"must be >= low ({fmt_number(low)}), got {fmt_number(high)}")
    return Distribution(kind, (low, high))


def _check_path(at: Scope, path: str, dist: Distribution, base: dict, defaults: Mapping[str, Any]) -> None:
    """A varied scenario key `path` exists, is not the seed, has an index exactly when it is a vector, and every
    value `dist` can give (its choices, a normal's mean, the bounds) makes a valid scenario from `base`."""
    from gyrodrift.ins.scenario import Scenario

    m = _PATH_RE.match(path)
    if m is None or m["section"] not in defaults or m["key"] not in defaults[m["section"]]:
        raise at.fail(None, "expected a scenario key SECTION.KEY or SECTION.KEY[i] of docs/scenarios.md")
    if m["key"] == "seed":
        raise at.fail(None, "the seed of each run derives from [campaign] seed; it is not varied")
    default = defaults[m["section"]][m["key"]]
    if isinstance(default, list) != (m["index"] is not None):
        raise at.fail(None, "a vector key takes an index [i]" if isinstance(default, list) else "not a vector key")
    if m["index"] is not None and int(m["index"]) >= len(default):
        raise at.fail(None, f"index out of range (the key has {len(default)} elements)")
    for value in dist.args[0] if dist.kind == "choice" else dist.args[:1] if dist.kind == "normal" else dist.args:
        trial = json.loads(json.dumps(base))
        _set_path(trial, path, value, defaults)
        try:
            Scenario.from_dict(trial, source="")
        except InputError as exc:
            raise at.fail(None, f"the value {show(value)} makes no valid run: {str(exc).lstrip(': ')}") from None


def parse_campaign(data: Mapping[str, Any], source: str = "<campaign>") -> Campaign:
    """Validate a TOML-shaped mapping into a `Campaign` (every error names `source` and the key)."""
    from gyrodrift.ins.scenario import Scenario

    root = Scope(source, CampaignError)
    for section in data:
        if section not in SECTIONS:
            raise root.section(section).fail(None, f"unknown section (expected one of: {', '.join(SECTIONS)})")
    head = root.table(data, "campaign", ("name", "count", "seed"))
    at = root.section("campaign")
    at.require(head, ("count",))
    count = Integer(ge=1).read(at, "count", head["count"])
    if count > MAX_RUNS:
        raise at.fail("count", f"at most {MAX_RUNS} runs, got {count}")
    seed = Integer(ge=0).read(at, "seed", head["seed"]) if "seed" in head else 0
    name = head.get("name", Path(source).stem)
    if not isinstance(name, str):
        raise at.fail("name", f"expected a string, got {type_name(name)} {show(name)}")
    base = data.get("base", {})
    if not isinstance(base, dict):
        raise root.section("base").fail(None, f"expected a scenario table (docs/scenarios.md), got {type_name(base)}")
    Scenario.from_dict(base, source=f"{source}: [base]")  # scenario errors name the file and key
    defaults = Scenario().to_toml_dict()
    grades: dict[str, dict[str, float]] = {}
    for gname, g in _section(root, data, "grades").items():
        at = root.section(f"grades.{gname}")
        if not isinstance(g, Mapping) or not g:
            raise at.fail(None, f"expected a table of {', '.join(NOISE_KEYS)}, got {type_name(g)} {show(g)}")
        at.keys(g, NOISE_KEYS)
        grades[gname] = {key: Number().read(at, key, v) for key, v in g.items()}
    vary: dict[str, Distribution] = {}
    for path, table in _section(root, data, "vary").items():
        at = root.section(f'vary."{path}"')
        dist = _distribution(at, table)
        if path == "grade":
            if dist.kind != "choice":
                raise at.fail("dist", "the noise grade takes dist = 'choice' over [grades] names")
            for v in dist.args[0]:
                if not isinstance(v, str) or v not in grades:
                    raise at.fail("values", f"unknown grade {show(v)} (defined: {', '.join(grades) or 'none'})")
        else:
            _check_path(at, path, dist, base, defaults)
        vary[path] = dist
    if grades and "grade" not in vary:
        raise root.section("vary.grade").fail(None, "grades are defined but no [vary.grade] chooses among them")
    options = dict(root.table(data, "options", OPTIONS))  # as given: the campaign's digest hashes them
    at = root.section("options")
    for key, v in options.items():
        value = OPTIONS[key].read(at, key, v)
        if key == "features_h" and not value.is_integer():
            raise at.fail(key, f"expected whole hours, got {fmt_number(value)}")
    campaign = Campaign(name, count, seed, base, vary, grades, source, options)
    try:
        campaign.timeline  # noqa: B018 - the time line's own checks (align_h fits the coarse span, ...)
    except ValueError as exc:
        raise at.fail(None, str(exc)) from None
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
        longest_h, table, key = _largest(campaign.vary["run.duration_h"]), 'vary."run.duration_h"', None
    else:
        longest_h, table = first.duration_h, "base.run"
        key = "duration_h" + ("" if "duration_h" in campaign.base.get("run", {}) else " (its default)")
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
        raise Scope(campaign.source, CampaignError, table).fail(
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
    raise Scope(campaign.source, CampaignError, "base.trajectory").fail(
        "static_h" + ("" if given else " (default)"),
        f"the vehicle drives off at {route.static_h:g} h, before the {need_h:g} h of static base the procedure "
        "needs (align_h + the longer of features_h and truth_h, [options]): a campaign's runs are identified on a "
        f"static base; give static_h >= {need_h:g} h",
    )


def load_campaign(path: str | os.PathLike[str]) -> Campaign:
    """Read and validate a campaign file (TOML); `CampaignError` naming the file and key otherwise."""
    p = Path(path)
    data = read_toml(p, CampaignError, expected="a campaign TOML file")
    return parse_campaign(data, source=str(p))
