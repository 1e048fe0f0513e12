"""Scenario files: a TOML description of one simulated static-base run, validated into frozen dataclasses.

Every key carries its user unit in its name (``lat_deg``, ``bias_deg_h``, ``vrw_ug_rthz``).
`Scenario.to_core_config` converts to the typed SI config of the core (`gyrodrift._core.SimulatorConfig`,
docs/ins-binding-contract.md);
`Scenario.to_toml_dict` / `write_scenario_toml` give back the fully resolved scenario (every default
written out, a temperature series inlined) that reloads to an equal object.

Sections and defaults are documented key by key in docs/scenarios.md. Any unknown section or key, wrong
type, wrong vector length, non-finite number or out-of-range value raises `ScenarioError` whose message
starts with the file and the key, e.g. ``scenario.toml: [gyro] bias_deg_h: expected 3 numbers, got 2``.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, cast

from gyrodrift.errors import InputError
from gyrodrift.files.toml_input import read_toml
from gyrodrift.site import Site
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, DEG_PER_SQRT_H, HOUR, MICRO_G

if TYPE_CHECKING:
    from gyrodrift import _core

__all__ = [
    "ScenarioError",
    "Site",
    "Run",
    "Rotation",
    "Gyro",
    "Accel",
    "Temperature",
    "Attitude",
    "Scenario",
    "load_scenario",
    "write_scenario_toml",
    "ROTATION_SCHEMES",
    "BALANCED",
]

ROTATION_SCHEMES = ("none", "continuous", "reciprocating", "indexing")
"""Turntable schemes understood by the core."""

BALANCED = "balanced"
"""The value of ``[rotation] span_deg`` that asks for the balanced reciprocating span."""

MAX_SCENARIO_BYTES = 1 << 20
"""Largest scenario TOML file [bytes] (a full scenario is about 1 kB; an inline series of 10 000 points ~200 kB)."""

MAX_SERIES_ROWS = 1_000_000
"""Most rows of a ``[temperature] series_csv`` (1 s steps for 11 days), checked while reading."""

DEG_PER_H_PER_SQRT_H = DEG_PER_H / math.sqrt(HOUR)
"""One deg/h/sqrt(h) (rate random walk) [rad/s/sqrt(s)]."""


class ScenarioError(InputError):
    """A scenario file (or dict) is invalid; the message names the file and the key."""


# --------------------------------------------------------------------------------------------------
# The typed scenario
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Run:
    """Length of the run [h], IMU sample rate [Hz] and the seed of all its noise."""

    duration_h: float = 16.0
    rate_hz: float = 100.0
    seed: int = 0


@dataclass(frozen=True)
class Rotation:
    """Single-axis turntable about body Up (positive counter-clockwise seen from above).

    scheme : "none", "continuous" (one direction), "reciprocating" (turn `span_deg` one way, dwell
    `dwell_s`, turn back), "indexing" (slew through `positions_deg`, dwelling `dwell_s` at each, cycled).
    rate_deg_s : cruise rate [deg/s]; accel_deg_s2 : acceleration at starts, stops, reversals [deg/s^2].

    The default acceleration, 100 deg/s^2 (ramp to 6 deg/s in 0.12 s), matters: reciprocating rotation
    with a 360 deg span turns round at the same table angle at both ends, leaving a fraction
    T_r / (span/rate + T_r) of the horizontal errors unmodulated (T_r = 2 rate / accel): 0.2 % at
    100 deg/s^2, 2 % at 10 deg/s^2. ``span_deg = "balanced"`` uses instead the span just short of one turn
    at which the reversal ramps leave no residual (`gyrodrift._core.balanced_reciprocating_span_rad`).
    The default indexing order [0, 90, 180, 270, 360, 270, 180, 90] cancels exactly; an order whose slews
    do not mirror each other (e.g. [0, 180, 90, 270], 4 %) does not.
    """

    scheme: str = "reciprocating"
    rate_deg_s: float = 6.0
    accel_deg_s2: float = 100.0
    span_deg: float | str = 360.0
    positions_deg: tuple[float, ...] = (0.0, 90.0, 180.0, 270.0, 360.0, 270.0, 180.0, 90.0)
    dwell_s: float = 0.0

    @property
    def balanced_span(self) -> bool:
        """True if the reciprocating span is the balanced one (``span_deg = "balanced"``)."""
        return self.span_deg == BALANCED


@dataclass(frozen=True)
class Gyro:
    """Gyro errors in user units, body axes x, y, z (x right, y forward, z up = rotation axis).

    bias_deg_h [deg/h]; arw_deg_rth angle random walk [deg/sqrt(h)]; bias_instability_deg_h stationary
    sigma of a first-order Gauss-Markov bias [deg/h] with correlation time correlation_s [s];
    rrw_deg_h_rth rate random walk [deg/h/sqrt(h)]; scale_ppm [ppm]; misalignment_arcsec off-diagonal
    terms xy, xz, yx, yz, zx, zy [arcsec].
    """

    bias_deg_h: tuple[float, float, float] = (0.0, 0.0, 0.0)
    arw_deg_rth: float = 0.0
    bias_instability_deg_h: float = 0.0
    correlation_s: float = 3600.0
    rrw_deg_h_rth: float = 0.0
    scale_ppm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    misalignment_arcsec: tuple[float, float, float, float, float, float] = (0.0,) * 6


@dataclass(frozen=True)
class Accel:
    """Accelerometer errors: bias_ug [ug, 1 ug = 9.80665e-6 m/s^2], vrw_ug_rthz velocity random walk
    [ug/sqrt(Hz)], scale_ppm [ppm], body axes x, y, z."""

    bias_ug: tuple[float, float, float] = (0.0, 0.0, 0.0)
    vrw_ug_rthz: float = 0.0
    scale_ppm: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Temperature:
    """System temperature and the axial (z) gyro drift it causes.

    Temperature: a warm-up T(t) = end_c + (start_c - end_c) exp(-t / tau_h) [deg C, h], or a measured
    series (series_t_h [h], series_temp_c [deg C], linearly interpolated) which overrides the warm-up.
    Axial drift [deg/h], added to the z gyro:
    k1 (T - t0_c) + k2 (T - t0_c)^2 + k3 dT/dt, with k1 [deg/h/degC], k2 [deg/h/degC^2],
    k3 [deg/h per degC/h] and dT/dt in degC/h.
    """

    start_c: float = 20.0
    end_c: float = 20.0
    tau_h: float = 1.0
    series_t_h: tuple[float, ...] | None = None
    series_temp_c: tuple[float, ...] | None = None
    t0_c: float = 20.0
    k1_deg_h_per_c: float = 0.0
    k2_deg_h_per_c2: float = 0.0
    k3_deg_h_per_c_per_h: float = 0.0


@dataclass(frozen=True)
class Attitude:
    """Initial body attitude at table angle 0 [deg]: pitch about x, roll about y, yaw about Up (CCW +)."""

    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    yaw_deg: float = 0.0


SEGMENT_KINDS = ("straight", "turn", "accelerate", "stop")
"""The kinds of route segment of ``[trajectory] segments``."""

WAYPOINT_ROUTE_KEYS = ("waypoints", "turn_rate_deg_s", "accel_m_s2")
"""Keys of ``[trajectory]`` for a route given by waypoints (`gyrodrift.ins.waypoints`) instead of segments."""

DRIVE_H = 72.0
"""Default length of the drive after the static period [h] (the paper's 1 nmi / 72 h)."""


@dataclass(frozen=True)
class Segment:
    """One segment of a land-vehicle route, resolved: ``kind`` (one of `SEGMENT_KINDS`), ``duration_s`` [s],
    longitudinal acceleration ``accel_m_s2`` [m/s^2] (accelerate; negative brakes), turn rate
    ``rate_deg_s`` [deg/s] (turn; positive counter-clockwise about Up, i.e. a left turn) and height change
    ``climb_m`` [m] (any kind but stop; a smooth profile starting and ending with zero vertical speed)."""

    kind: str
    duration_s: float
    accel_m_s2: float = 0.0
    rate_deg_s: float = 0.0
    climb_m: float = 0.0

    def to_toml_dict(self) -> dict[str, Any]:
        """The segment as its TOML table (only the keys its kind takes)."""
        out: dict[str, Any] = {"kind": self.kind, "duration_s": self.duration_s}
        if self.kind == "accelerate":
            out["accel_m_s2"] = self.accel_m_s2
        if self.kind == "turn":
            out["rate_deg_s"] = self.rate_deg_s
        if self.climb_m != 0.0:
            out["climb_m"] = self.climb_m
        return out


@dataclass(frozen=True)
class Trajectory:
    """A moving base: the vehicle stands still for ``static_h`` [h] (alignment and identification), then drives
    ``segments`` in order (cycled to the end of the run with ``repeat``). The route starts at the site's height
    and changes it by the segments' ``climb_m`` (the vehicle body stays level); the vehicle's initial yaw is
    ``[attitude] yaw_deg`` and ``[attitude] pitch_deg``/``roll_deg`` are the IMU's mounting tilt on the vehicle.
    After the last segment (without ``repeat``) the vehicle goes on straight at its last speed."""

    static_h: float = 16.0
    repeat: bool = False
    segments: tuple[Segment, ...] = ()


@dataclass(frozen=True)
class Scenario:
    """One static-base run. Build it with `load_scenario` (file) or `Scenario.from_dict` (mapping)."""

    site: Site = field(default_factory=Site)
    run: Run = field(default_factory=Run)
    rotation: Rotation = field(default_factory=Rotation)
    gyro: Gyro = field(default_factory=Gyro)
    accel: Accel = field(default_factory=Accel)
    temperature: Temperature = field(default_factory=Temperature)
    attitude: Attitude = field(default_factory=Attitude)
    trajectory: Trajectory | None = None

    @property
    def n_samples(self) -> int:
        """Number of IMU samples of the run (duration x rate, rounded)."""
        return int(round(self.run.duration_h * HOUR * self.run.rate_hz))

    @classmethod
    def from_dict(
        cls, data: Mapping[str, Any], source: str = "<scenario>", base_dir: str | os.PathLike[str] | None = None
    ) -> Scenario:
        """Validate a mapping shaped like the TOML file.

        Parameters
        ----------
        data : mapping
            Sections to key/value mappings, user units.
        source : str
            Name used at the start of every error message (normally the file path).
        base_dir : path-like, optional
            Folder against which a relative ``[temperature] series_csv`` is resolved (default: the current
            folder).

        Raises
        ------
        ScenarioError
        """
        return _Validator(source, Path(base_dir) if base_dir is not None else Path(".")).scenario(data)

    def to_toml_dict(self) -> dict[str, dict[str, Any]]:
        """The fully resolved scenario as a TOML-shaped dict (user units, every key written out).

        A temperature series is written inline (``series_t_h``, ``series_temp_c``), so the result is
        self-contained: ``Scenario.from_dict(s.to_toml_dict()) == s``.
        """
        out: dict[str, dict[str, Any]] = {}
        for f in dataclasses.fields(self):
            section = getattr(self, f.name)
            if section is None:
                continue
            if isinstance(section, Trajectory):
                out["trajectory"] = {
                    "static_h": section.static_h,
                    "repeat": section.repeat,
                    "segments": [seg.to_toml_dict() for seg in section.segments],
                }
                continue
            values: dict[str, Any] = {}
            for g in dataclasses.fields(section):
                v = getattr(section, g.name)
                if v is None:
                    continue
                values[g.name] = list(v) if isinstance(v, tuple) else v
            out[f.name] = values
        return out

    def to_core_config(self) -> _core.SimulatorConfig:
        """The validated SI config of `gyrodrift._core.ImuSimulator` (see docs/ins-binding-contract.md).

        Conversions: deg -> rad, deg/h -> rad/s, deg/sqrt(h) -> rad/sqrt(s), deg/h/sqrt(h) -> rad/s/sqrt(s),
        ug -> m/s^2 (1 ug = 9.80665e-6 m/s^2), ug/sqrt(Hz) -> m/s/sqrt(s), ppm -> 1e-6, arcsec -> rad,
        h -> s; k3 [deg/h per degC/h] -> [rad/s per degC/s] (multiply by deg/h and by 3600 s/h).

        Raises
        ------
        gyrodrift.errors.CoreError
            A value the core refuses (`Scenario.from_dict` has already checked them, naming the file and key).
        """
        from gyrodrift import _core

        s, r, rot, g, a, t, att = (
            self.site,
            self.run,
            self.rotation,
            self.gyro,
            self.accel,
            self.temperature,
            self.attitude,
        )
        series_t, series_c = t.series_t_h, t.series_temp_c
        # "balanced": the core replaces the one-turn span by the balanced span near it.
        span_rad = 2.0 * math.pi if isinstance(rot.span_deg, str) else rot.span_deg * DEG
        return _core.SimulatorConfig(
            **s.core_position(),
            rate_hz=float(r.rate_hz),
            duration_s=r.duration_h * HOUR,
            seed=int(r.seed),
            pitch_rad=att.pitch_deg * DEG,
            roll_rad=att.roll_deg * DEG,
            yaw_rad=att.yaw_deg * DEG,
            rotation_scheme=rot.scheme,
            rotation_rate_rad_s=rot.rate_deg_s * DEG,
            rotation_accel_rad_s2=rot.accel_deg_s2 * DEG,
            reciprocating_span_rad=span_rad,
            reciprocating_balanced=rot.balanced_span,
            positions_rad=[p * DEG for p in rot.positions_deg],
            dwell_s=float(rot.dwell_s),
            gyro_bias_rad_s=[b * DEG_PER_H for b in g.bias_deg_h],
            gyro_arw_rad_rts=g.arw_deg_rth * DEG_PER_SQRT_H,
            gyro_bias_instability_rad_s=g.bias_instability_deg_h * DEG_PER_H,
            gyro_correlation_s=float(g.correlation_s),
            gyro_rrw_rad_s_rts=g.rrw_deg_h_rth * DEG_PER_H_PER_SQRT_H,
            gyro_scale=[p * 1e-6 for p in g.scale_ppm],
            gyro_misalignment_rad=[m * ARCSEC for m in g.misalignment_arcsec],
            accel_bias_m_s2=[b * MICRO_G for b in a.bias_ug],
            accel_vrw_m_s_rts=a.vrw_ug_rthz * MICRO_G,
            accel_scale=[p * 1e-6 for p in a.scale_ppm],
            temp_start_c=float(t.start_c),
            temp_end_c=float(t.end_c),
            temp_tau_s=t.tau_h * HOUR,
            temp_series_t_s=None if series_t is None else [x * HOUR for x in series_t],
            temp_series_c=None if series_c is None else [float(x) for x in series_c],
            drift_t0_c=float(t.t0_c),
            drift_k1_rad_s_per_c=t.k1_deg_h_per_c * DEG_PER_H,
            drift_k2_rad_s_per_c2=t.k2_deg_h_per_c2 * DEG_PER_H,
            drift_k3_rad_s_per_c_per_s=t.k3_deg_h_per_c_per_h * DEG_PER_H * HOUR,
            **self._trajectory_keywords(),
        )

    def _trajectory_keywords(self) -> dict[str, Any]:
        """The moving-base keywords of `_core.SimulatorConfig` (none for a static base)."""
        tr = self.trajectory
        if tr is None:
            return {}
        return {
            "trajectory_start_s": tr.static_h * HOUR,
            "trajectory_segments": [(g.duration_s, g.accel_m_s2, g.rate_deg_s * DEG, g.climb_m) for g in tr.segments],
            "trajectory_repeat": tr.repeat,
        }


def write_scenario_toml(scenario: Scenario, path: str | os.PathLike[str], header: str | None = None) -> None:
    """Write the resolved scenario (`Scenario.to_toml_dict`) as TOML, atomically; it reloads to an equal
    `Scenario` with `load_scenario`."""
    from gyrodrift.files.toml_writer import write_toml

    write_toml(scenario.to_toml_dict(), path, header=header)


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """Read and validate a scenario TOML file.

    A relative ``[temperature] series_csv`` is read relative to the TOML file's folder.

    Raises
    ------
    ScenarioError
        Missing or unreadable file, invalid TOML, or any invalid key (the message names the file and key).
    """
    p = Path(path)
    source = str(path)
    data = read_toml(p, ScenarioError, expected="a scenario TOML file", max_bytes=MAX_SCENARIO_BYTES)
    return Scenario.from_dict(data, source=source, base_dir=p.parent)


# --------------------------------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------------------------------


def _type_name(v: Any) -> str:
    if isinstance(v, bool):
        return "boolean"
    if isinstance(v, str):
        return "string"
    if isinstance(v, (list, tuple)):
        return "array"
    if isinstance(v, dict):
        return "table"
    if isinstance(v, (int, float)):
        return "number"
    return type(v).__name__


class _Validator:
    """Turns a TOML-shaped mapping into a `Scenario`, naming the file and key in every error."""

    SECTIONS = ("site", "run", "rotation", "gyro", "accel", "temperature", "attitude", "trajectory")

    def __init__(self, source: str, base_dir: Path):
        self.source = source
        self.base_dir = base_dir

    # -- error helpers -------------------------------------------------------------------------
    def fail(self, section: str | None, key: str | None, msg: str) -> ScenarioError:
        where = self.source
        if section is not None:
            where += f": [{section}]"
        if key is not None:
            where += f" {key}"
        return ScenarioError(f"{where}: {msg}")

    # -- scalar readers --------------------------------------------------------------------------
    def number(self, sec: str, table: Mapping[str, Any], key: str, default: float) -> float:
        if key not in table:
            return float(default)
        v = table[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.fail(sec, key, f"expected a number, got {_type_name(v)} {_show(v)}")
        f = _finite(v)
        if f is None:
            raise self.fail(sec, key, f"expected a finite number, got {_show(v)}")
        return f

    def positive(self, sec, table, key, default) -> float:
        v = self.number(sec, table, key, default)
        if not v > 0:
            raise self.fail(sec, key, f"must be > 0, got {_fmt(v)}")
        return v

    def positive_at_most(self, sec, table, key, default, hi, unit: str = "") -> float:
        v = self.positive(sec, table, key, default)
        if v > hi:
            raise self.fail(sec, key, f"must be at most {hi:.6g}{unit}, got {_fmt(v)}")
        return v

    def non_negative(self, sec, table, key, default) -> float:
        v = self.number(sec, table, key, default)
        if v < 0:
            raise self.fail(sec, key, f"must be >= 0, got {_fmt(v)}")
        return v

    def in_range(self, sec, table, key, default, lo, hi, *, open_interval=False) -> float:
        v = self.number(sec, table, key, default)
        bad = not (lo < v < hi) if open_interval else not (lo <= v <= hi)
        if bad:
            kind = "strictly between" if open_interval else "between"
            raise self.fail(sec, key, f"must be {kind} {_fmt(lo)} and {_fmt(hi)}, got {_fmt(v)}")
        return v

    def integer(self, sec, table, key, default: int) -> int:
        if key not in table:
            return default
        v = table[key]
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.fail(sec, key, f"expected an integer, got {_type_name(v)} {_show(v)}")
        if v < 0:
            raise self.fail(sec, key, f"must be >= 0, got {v}")
        return v

    def vector(self, sec, table, key, default: tuple[float, ...], n: int | None) -> tuple[float, ...]:
        """A list of numbers; exactly `n` long, or non-empty when `n` is None."""
        if key not in table:
            return tuple(float(x) for x in default)
        v = table[key]
        if not isinstance(v, (list, tuple)):
            want = f"{n} numbers" if n is not None else "an array of numbers"
            raise self.fail(sec, key, f"expected {want}, got {_type_name(v)} {_show(v)}")
        if n is not None and len(v) != n:
            raise self.fail(sec, key, f"expected {n} numbers, got {len(v)}")
        if n is None and len(v) == 0:
            raise self.fail(sec, key, "expected at least 1 number, got 0")
        out = []
        for i, x in enumerate(v):
            if isinstance(x, bool) or not isinstance(x, (int, float)):
                raise self.fail(sec, key, f"element {i}: expected a number, got {_type_name(x)} {_show(x)}")
            f = _finite(x)
            if f is None:
                raise self.fail(sec, key, f"element {i}: expected a finite number, got {_show(x)}")
            out.append(f)
        return tuple(out)

    def vector3(self, sec, table, key, default: tuple[float, float, float]) -> tuple[float, float, float]:
        """Three numbers (body x, y, z)."""
        return cast("tuple[float, float, float]", self.vector(sec, table, key, default, 3))

    def section(self, data: Mapping[str, Any], name: str, cls: type) -> Mapping[str, Any]:
        table = data.get(name, {})
        if not isinstance(table, Mapping):
            raise self.fail(None, None, f"[{name}] must be a table, got {_type_name(table)}")
        allowed = [f.name for f in dataclasses.fields(cls)]
        if name == "temperature":
            allowed = allowed + ["series_csv"]
        if name == "trajectory":
            allowed = allowed + list(WAYPOINT_ROUTE_KEYS)
        for key in table:
            if key not in allowed:
                raise self.fail(name, key, f"unknown key (expected one of: {', '.join(allowed)})")
        return table

    # -- sections --------------------------------------------------------------------------------
    def scenario(self, data: Mapping[str, Any]) -> Scenario:
        if not isinstance(data, Mapping):
            raise self.fail(None, None, f"expected a table of sections, got {_type_name(data)}")
        for name in data:
            if name not in self.SECTIONS:
                raise self.fail(None, None, f"unknown section [{name}] (expected one of: {', '.join(self.SECTIONS)})")
        trajectory = self.trajectory(data)
        run = self.run(data)
        if trajectory is not None and "duration_h" not in data.get("run", {}):
            run = dataclasses.replace(run, duration_h=trajectory.static_h + DRIVE_H)
        scenario = Scenario(
            trajectory=trajectory,
            site=self.site(data),
            run=run,
            rotation=self.rotation(data),
            gyro=self.gyro(data),
            accel=self.accel(data),
            temperature=self.temperature(data),
            attitude=self.attitude(data),
        )
        self.core_check(scenario, data)
        return scenario

    def core_check(self, scenario: Scenario, data: Mapping[str, Any]) -> None:
        """Let the core validate the whole run (its ranges are the one source); name the TOML key it refuses."""
        from gyrodrift.errors import CoreError

        try:
            scenario.to_core_config()
        except CoreError as exc:
            key = str(getattr(exc, "key", "") or "")
            where = _CORE_KEYS.get(key)
            section, toml_key = where if where is not None else (None, None)
            if toml_key in ("series_t_h", "series_temp_c") and "series_csv" in data.get("temperature", {}):
                toml_key = "series_csv"
            if toml_key == "segments" and "waypoints" in data.get("trajectory", {}):
                toml_key = "waypoints"  # the segments were made from them
            msg = str(exc)
            if key and msg.startswith(f"{key}: "):
                msg = msg[len(key) + 2 :]
            raise self.fail(section, toml_key, msg) from None

    def site(self, data) -> Site:
        t, d = self.section(data, "site", Site), Site()
        c = _limits()
        return Site(
            lat_deg=self.in_range("site", t, "lat_deg", d.lat_deg, -c.MAX_LAT_DEG, c.MAX_LAT_DEG),
            lon_deg=self.in_range("site", t, "lon_deg", d.lon_deg, -c.MAX_LON_DEG, c.MAX_LON_DEG),
            height_m=self.in_range("site", t, "height_m", d.height_m, c.MIN_HEIGHT_M, c.MAX_HEIGHT_M),
        )

    def run(self, data) -> Run:
        t, d = self.section(data, "run", Run), Run()
        c = _limits()
        max_h = c.MAX_DURATION_S / HOUR
        run = Run(
            duration_h=self.positive_at_most("run", t, "duration_h", d.duration_h, max_h, " h"),
            rate_hz=self.in_range("run", t, "rate_hz", d.rate_hz, c.MIN_RATE_HZ, c.MAX_RATE_HZ),
            seed=self.integer("run", t, "seed", d.seed),
        )
        if run.seed >= 2**64:
            raise self.fail("run", "seed", f"must be < 2**64, got {_show(run.seed)}")
        if round(run.duration_h * HOUR * run.rate_hz) < 1:
            raise self.fail("run", "duration_h", "shorter than one sample")
        return run

    def rotation(self, data) -> Rotation:
        t, d = self.section(data, "rotation", Rotation), Rotation()
        scheme = t.get("scheme", d.scheme)
        if scheme not in ROTATION_SCHEMES:
            opts = ", ".join(repr(s) for s in ROTATION_SCHEMES)
            raise self.fail("rotation", "scheme", f"expected one of {opts}, got {_show(scheme)}")
        dwell_default = 300.0 if scheme == "indexing" else d.dwell_s
        c = _limits()
        rot = Rotation(
            scheme=scheme,
            rate_deg_s=self.positive_at_most(
                "rotation", t, "rate_deg_s", d.rate_deg_s, c.MAX_TABLE_RATE_DEG_S, " deg/s"
            ),
            accel_deg_s2=self.positive_at_most("rotation", t, "accel_deg_s2", d.accel_deg_s2, c.MAX_TABLE_ACCEL_DEG_S2),
            span_deg=self.span(t, d.span_deg),
            positions_deg=self.vector("rotation", t, "positions_deg", d.positions_deg, None),
            dwell_s=self.non_negative("rotation", t, "dwell_s", dwell_default),
        )
        if rot.scheme == "reciprocating" and rot.balanced_span:
            from gyrodrift import _core

            try:
                _core.balanced_reciprocating_span_rad(rot.rate_deg_s * DEG, rot.accel_deg_s2 * DEG, rot.dwell_s)
            except ValueError:
                raise self.fail(
                    "rotation",
                    "span_deg",
                    f"no balanced span within half a turn at accel_deg_s2 = "
                    f"{_fmt(rot.accel_deg_s2)} and rate_deg_s = {_fmt(rot.rate_deg_s)} (the ramps are too "
                    "slow); raise accel_deg_s2 or give a number",
                ) from None
        return rot

    def span(self, table: Mapping[str, Any], default: float | str) -> float | str:
        """``[rotation] span_deg``: a number > 0 [deg] or the string "balanced"."""
        v = table.get("span_deg", default)
        if isinstance(v, str):
            if v != BALANCED:
                raise self.fail("rotation", "span_deg", f'expected a number > 0 or "{BALANCED}", got {_show(v)}')
            return v
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            got = f"{_type_name(v)} {_show(v)}"
            raise self.fail("rotation", "span_deg", f'expected a number > 0 or "{BALANCED}", got {got}')
        return self.positive_at_most("rotation", table, "span_deg", default, _limits().MAX_SPAN_DEG, " deg")

    def gyro(self, data) -> Gyro:
        t, d = self.section(data, "gyro", Gyro), Gyro()
        return Gyro(
            bias_deg_h=self.vector3("gyro", t, "bias_deg_h", d.bias_deg_h),
            arw_deg_rth=self.non_negative("gyro", t, "arw_deg_rth", d.arw_deg_rth),
            bias_instability_deg_h=self.non_negative("gyro", t, "bias_instability_deg_h", d.bias_instability_deg_h),
            correlation_s=self.positive("gyro", t, "correlation_s", d.correlation_s),
            rrw_deg_h_rth=self.non_negative("gyro", t, "rrw_deg_h_rth", d.rrw_deg_h_rth),
            scale_ppm=self.vector3("gyro", t, "scale_ppm", d.scale_ppm),
            misalignment_arcsec=cast(
                "tuple[float, float, float, float, float, float]",
                self.vector("gyro", t, "misalignment_arcsec", d.misalignment_arcsec, 6),
            ),
        )

    def accel(self, data) -> Accel:
        t, d = self.section(data, "accel", Accel), Accel()
        return Accel(
            bias_ug=self.vector3("accel", t, "bias_ug", d.bias_ug),
            vrw_ug_rthz=self.non_negative("accel", t, "vrw_ug_rthz", d.vrw_ug_rthz),
            scale_ppm=self.vector3("accel", t, "scale_ppm", d.scale_ppm),
        )

    def temperature(self, data) -> Temperature:
        sec = "temperature"
        t, d = self.section(data, sec, Temperature), Temperature()
        series_t = series_c = None
        if "series_csv" in t:
            for other in ("series_t_h", "series_temp_c"):
                if other in t:
                    raise self.fail(sec, "series_csv", f"give either series_csv or {other}, not both")
            series_t, series_c = self.read_series_csv(t["series_csv"])
        elif "series_t_h" in t or "series_temp_c" in t:
            for key in ("series_t_h", "series_temp_c"):
                if key not in t:
                    other = "series_temp_c" if key == "series_t_h" else "series_t_h"
                    raise self.fail(sec, key, f"missing (required together with {other})")
            series_t = self.vector(sec, t, "series_t_h", (), None)
            series_c = self.vector(sec, t, "series_temp_c", (), None)
            if len(series_t) != len(series_c):
                raise self.fail(
                    sec, "series_temp_c", f"expected {len(series_t)} numbers (as series_t_h), got {len(series_c)}"
                )
        if series_t is not None:
            key = "series_csv" if "series_csv" in t else "series_t_h"
            if len(series_t) < 2:
                raise self.fail(sec, key, f"expected at least 2 samples, got {len(series_t)}")
            if any(b <= a for a, b in zip(series_t, series_t[1:], strict=False)):
                raise self.fail(sec, key, "times must be strictly increasing")
        return Temperature(
            start_c=self.in_range(sec, t, "start_c", d.start_c, -100.0, 200.0),
            end_c=self.in_range(sec, t, "end_c", d.end_c, -100.0, 200.0),
            tau_h=self.positive(sec, t, "tau_h", d.tau_h),
            series_t_h=series_t,
            series_temp_c=series_c,
            t0_c=self.in_range(sec, t, "t0_c", d.t0_c, -100.0, 200.0),
            k1_deg_h_per_c=self.number(sec, t, "k1_deg_h_per_c", d.k1_deg_h_per_c),
            k2_deg_h_per_c2=self.number(sec, t, "k2_deg_h_per_c2", d.k2_deg_h_per_c2),
            k3_deg_h_per_c_per_h=self.number(sec, t, "k3_deg_h_per_c_per_h", d.k3_deg_h_per_c_per_h),
        )

    def attitude(self, data) -> Attitude:
        t, d = self.section(data, "attitude", Attitude), Attitude()
        c = _limits()
        return Attitude(
            pitch_deg=self.in_range(
                "attitude", t, "pitch_deg", d.pitch_deg, -c.MAX_PITCH_DEG, c.MAX_PITCH_DEG, open_interval=True
            ),
            roll_deg=self.in_range("attitude", t, "roll_deg", d.roll_deg, -c.MAX_ROLL_DEG, c.MAX_ROLL_DEG),
            yaw_deg=self.in_range("attitude", t, "yaw_deg", d.yaw_deg, -c.MAX_YAW_DEG, c.MAX_YAW_DEG),
        )

    def trajectory(self, data) -> Trajectory | None:
        """The ``[trajectory]`` section: static_h, repeat, segments (a list of tables with a ``kind``)."""
        if "trajectory" not in data:
            return None
        t, d = self.section(data, "trajectory", Trajectory), Trajectory()
        static_h = self.non_negative("trajectory", t, "static_h", d.static_h)
        repeat = t.get("repeat", d.repeat)
        if not isinstance(repeat, bool):
            raise self.fail("trajectory", "repeat", f"expected true or false, got {_type_name(repeat)} {_show(repeat)}")
        if "waypoints" in t:
            if "segments" in t:
                raise self.fail("trajectory", "waypoints", "give segments or waypoints, not both")
            raw = self.waypoint_segments(data, t, repeat)
        else:
            for k in WAYPOINT_ROUTE_KEYS[1:]:
                if k in t:
                    raise self.fail("trajectory", k, "only with waypoints")
            raw = t.get("segments", [])
        if not isinstance(raw, (list, tuple)):
            raise self.fail("trajectory", "segments", f"expected an array of tables, got {_type_name(raw)}")
        segments: list[Segment] = []
        speed = 0.0
        for i, g in enumerate(raw):
            seg = self.segment(f"segments[{i}]", g, speed)
            speed = max(0.0, speed + seg.accel_m_s2 * seg.duration_s)
            if speed < 1e-9:
                speed = 0.0
            segments.append(seg)
        return Trajectory(static_h=static_h, repeat=repeat, segments=tuple(segments))

    def waypoint_segments(self, data: Mapping[str, Any], t: Mapping[str, Any], repeat: bool) -> list[dict[str, Any]]:
        """The segments of a ``waypoints`` route (`gyrodrift.ins.waypoints`), from the site and initial yaw."""
        from gyrodrift.ins.waypoints import Waypoint, WaypointError, waypoint_route

        sec, c = "trajectory", _limits()
        raw = t["waypoints"]
        if not isinstance(raw, (list, tuple)) or not raw:
            raise self.fail(sec, "waypoints", f"expected a non-empty array of tables, got {_show(raw)}")
        rate = self.positive_at_most(sec, t, "turn_rate_deg_s", 3.0, c.MAX_VEHICLE_YAW_RATE_DEG_S, " deg/s")
        accel = self.positive_at_most(sec, t, "accel_m_s2", 2.0, c.MAX_VEHICLE_ACCEL_M_S2, " m/s^2")
        points = []
        keys = ("lat_deg", "lon_deg", "height_m", "speed_m_s", "leg_s")
        for i, w in enumerate(raw):
            name = f"waypoints[{i}]"
            if not isinstance(w, Mapping):
                raise self.fail(sec, name, f"expected a table, got {_type_name(w)} {_show(w)}")
            for k in w:
                if k not in keys:
                    raise self.fail(sec, f"{name}.{k}", f"unknown key (expected: {', '.join(keys)})")
            for k in ("lat_deg", "lon_deg"):
                if k not in w:
                    raise self.fail(sec, name, f"missing {k}")
            if ("speed_m_s" in w) == ("leg_s" in w):
                raise self.fail(sec, name, "give exactly one of speed_m_s and leg_s")
            named = {f"{name}.{k}": v for k, v in w.items()}

            def value(k: str, lo: float, hi: float, named=named, name=name) -> float:
                return self.in_range(sec, named, f"{name}.{k}", math.nan, lo, hi)

            lim = (c.MAX_LAT_DEG - 0.01, c.MAX_LON_DEG)
            points.append(
                Waypoint(
                    lat_deg=value("lat_deg", -lim[0], lim[0]),
                    lon_deg=value("lon_deg", -lim[1], lim[1]),
                    height_m=value("height_m", c.MIN_HEIGHT_M, c.MAX_HEIGHT_M) if "height_m" in w else None,
                    speed_m_s=value("speed_m_s", 0.0, c.MAX_VEHICLE_SPEED_M_S) if "speed_m_s" in w else None,
                    leg_s=value("leg_s", 0.0, c.MAX_DURATION_S) if "leg_s" in w else None,
                )
            )
            p = points[-1]
            if (p.speed_m_s is not None and p.speed_m_s <= 0) or (p.leg_s is not None and p.leg_s <= 0):
                raise self.fail(sec, name, "the speed (or leg time) must be > 0")
        site, yaw0 = self.site(data), self.attitude(data).yaw_deg
        try:
            return waypoint_route(
                (site.lat_deg, site.lon_deg, site.height_m),
                yaw0,
                points,
                turn_rate_deg_s=rate,
                accel_m_s2=accel,
                repeat=repeat,
            )
        except WaypointError as exc:
            key = "waypoints" if exc.index is None else f"waypoints[{exc.index}]"
            raise self.fail(sec, key if exc.key is None else f"{key}.{exc.key}", str(exc)) from None

    _SEGMENT_KEYS: ClassVar[dict[str, tuple[str, ...]]] = {
        "straight": ("duration_s", "climb_m"),
        "turn": ("rate_deg_s", "duration_s", "angle_deg", "climb_m"),
        "accelerate": ("accel_m_s2", "duration_s", "to_speed_m_s", "climb_m"),
        "stop": ("duration_s",),
    }

    def segment(self, key: str, g: Any, speed: float) -> Segment:
        """One route segment (``key`` names it in messages), entered at `speed` [m/s]."""
        sec, c = "trajectory", _limits()
        if not isinstance(g, Mapping):
            raise self.fail(sec, key, f"expected a table, got {_type_name(g)} {_show(g)}")
        kind = g.get("kind")
        if kind not in self._SEGMENT_KEYS:
            kinds = ", ".join(map(repr, SEGMENT_KINDS))
            raise self.fail(sec, f"{key}.kind", f"expected one of {kinds}, got {_show(kind)}")
        allowed = self._SEGMENT_KEYS[kind]
        for k in g:
            if k != "kind" and k not in allowed:
                raise self.fail(sec, f"{key}.{k}", f"unknown key for a {kind} segment (expected: {', '.join(allowed)})")

        def one_of(a: str, b: str, what: str) -> None:
            if (a in g) == (b in g):
                raise self.fail(sec, key, f"{what} takes exactly one of {a} and {b}")

        duration = self.number(sec, g, "duration_s", math.nan)
        accel = rate = 0.0
        max_speed = c.MAX_VEHICLE_SPEED_M_S
        if kind == "turn":
            max_rate = c.MAX_VEHICLE_YAW_RATE_DEG_S
            rate = self.number(sec, g, "rate_deg_s", math.nan)
            if not (0 < abs(rate) <= max_rate):
                got = _show(g.get("rate_deg_s"))
                raise self.fail(
                    sec, f"{key}.rate_deg_s", f"expected a turn rate with 0 < |rate| <= {max_rate:.6g} deg/s, got {got}"
                )
            one_of("duration_s", "angle_deg", "a turn")
            if "angle_deg" in g:
                angle = self.number(sec, g, "angle_deg", math.nan)
                if angle == 0 or (angle > 0) != (rate > 0):
                    got = _show(g["angle_deg"])
                    raise self.fail(sec, f"{key}.angle_deg", f"must be non-zero with the sign of rate_deg_s, got {got}")
                duration = angle / rate
        elif kind == "accelerate":
            max_accel = c.MAX_VEHICLE_ACCEL_M_S2
            accel = self.number(sec, g, "accel_m_s2", math.nan)
            if not (0 < abs(accel) <= max_accel):
                got = _show(g.get("accel_m_s2"))
                raise self.fail(sec, f"{key}.accel_m_s2", f"expected 0 < |accel| <= {max_accel:.6g} m/s^2, got {got}")
            one_of("duration_s", "to_speed_m_s", "an accelerate segment")
            if "to_speed_m_s" in g:
                target = self.number(sec, g, "to_speed_m_s", math.nan)
                if not (0 <= target <= max_speed) or (target - speed) * accel <= 0:
                    raise self.fail(
                        sec,
                        f"{key}.to_speed_m_s",
                        f"cannot reach {_show(g['to_speed_m_s'])} m/s from {speed:.6g} m/s at {accel:.6g} m/s^2 "
                        f"(speeds within [0, {max_speed:.6g}] m/s)",
                    )
                duration = (target - speed) / accel
        if not (duration > 0 and math.isfinite(duration)):
            raise self.fail(sec, f"{key}.duration_s", f"expected a duration > 0 s, got {_show(g.get('duration_s'))}")
        if kind == "stop" and speed != 0.0:
            raise self.fail(
                sec,
                key,
                f"a stop needs the vehicle at rest, it moves at {speed:.6g} m/s "
                "(brake first: an accelerate segment with to_speed_m_s = 0)",
            )
        end = speed + accel * duration
        if not (-1e-9 <= end <= max_speed):
            raise self.fail(
                sec, key, f"the speed after this segment, {end:.6g} m/s, is outside [0, {max_speed:.6g}] m/s"
            )
        climb = self.number(sec, g, "climb_m", 0.0)
        # Peak vertical speed and acceleration of the smooth climb profile (gyrodrift-core `trajectory`).
        w, a = abs(climb) * math.pi / (2 * duration), abs(climb) * math.pi**2 / (2 * duration**2)
        if w > c.MAX_VEHICLE_CLIMB_RATE_M_S or a > c.MAX_VEHICLE_ACCEL_M_S2:
            raise self.fail(
                sec,
                f"{key}.climb_m",
                f"a climb of {climb:.6g} m in {duration:.6g} s needs a vertical speed of {w:.3g} m/s and "
                f"acceleration {a:.3g} m/s^2 (at most {c.MAX_VEHICLE_CLIMB_RATE_M_S:.6g} m/s and "
                f"{c.MAX_VEHICLE_ACCEL_M_S2:.6g} m/s^2: a longer segment or a smaller climb)",
            )
        return Segment(kind=kind, duration_s=duration, accel_m_s2=accel, rate_deg_s=rate, climb_m=climb)

    def read_series_csv(self, value: Any) -> tuple[tuple[float, ...], tuple[float, ...]]:
        sec, key = "temperature", "series_csv"
        if not isinstance(value, str):
            raise self.fail(sec, key, f"expected a file name, got {_type_name(value)} {_show(value)}")
        path = Path(value)
        if not path.is_absolute():
            path = self.base_dir / path
        try:
            with open(path, newline="", encoding="utf-8") as fh:
                rows: list[dict[str, str]] = []
                for row in csv.DictReader(fh):
                    if len(rows) == MAX_SERIES_ROWS:
                        raise self.fail(sec, key, f"{path}: more than {MAX_SERIES_ROWS} rows")
                    rows.append(row)
        except FileNotFoundError:
            raise self.fail(sec, key, f"{path}: no such file") from None
        except IsADirectoryError:
            raise self.fail(sec, key, f"{path}: is a folder, expected a CSV file") from None
        except OSError as exc:
            raise self.fail(sec, key, f"{path}: cannot read: {exc.strerror or exc}") from None
        except UnicodeDecodeError as exc:
            raise self.fail(sec, key, f"{path}: not UTF-8 text (byte {exc.start} of a block)") from None
        except csv.Error as exc:
            raise self.fail(sec, key, f"{path}: not a CSV table: {exc}") from None
        if not rows or "t_h" not in rows[0] or "temp_c" not in rows[0]:
            raise self.fail(sec, key, f"{path}: expected columns t_h, temp_c and at least one row")
        ts, cs = [], []
        for line, row in enumerate(rows, start=2):
            try:
                tv, cv = float(row["t_h"]), float(row["temp_c"])
            except (TypeError, ValueError):
                raise self.fail(sec, key, f"{path}:{line}: expected numbers in t_h, temp_c") from None
            if not (math.isfinite(tv) and math.isfinite(cv)):
                raise self.fail(sec, key, f"{path}:{line}: expected finite numbers in t_h, temp_c")
            ts.append(tv)
            cs.append(cv)
        return tuple(ts), tuple(cs)


def _finite(v: int | float) -> float | None:
    """`v` as a finite float, or None (NaN, infinity, or an integer beyond the float range)."""
    try:
        f = float(v)
    except OverflowError:
        return None
    return f if math.isfinite(f) else None


def _show(v: Any) -> str:
    """`v` for a message: its repr, cut to 60 characters (an integer of thousands of digits is described)."""
    if isinstance(v, int) and not isinstance(v, bool) and v.bit_length() > 200:
        return f"an integer of about {int(v.bit_length() * 0.30103) + 1} digits"
    try:
        r = repr(v)
    except (ValueError, RecursionError):
        return f"a {_type_name(v)}"
    return r if len(r) <= 60 else r[:57] + "..."


def _limits():
    """The core's limits (`gyrodrift._core`, gyrodrift-core `limits`), imported when a scenario is validated."""
    from gyrodrift import _core

    return _core


_CORE_KEYS = {
    "lat_rad": ("site", "lat_deg"),
    "lon_rad": ("site", "lon_deg"),
    "height_m": ("site", "height_m"),
    "rate_hz": ("run", "rate_hz"),
    "duration_s": ("run", "duration_h"),
    "seed": ("run", "seed"),
    "pitch_rad": ("attitude", "pitch_deg"),
    "roll_rad": ("attitude", "roll_deg"),
    "yaw_rad": ("attitude", "yaw_deg"),
    "rotation_scheme": ("rotation", "scheme"),
    "rotation_rate_rad_s": ("rotation", "rate_deg_s"),
    "rotation_accel_rad_s2": ("rotation", "accel_deg_s2"),
    "reciprocating_span_rad": ("rotation", "span_deg"),
    "positions_rad": ("rotation", "positions_deg"),
    "dwell_s": ("rotation", "dwell_s"),
    "gyro_bias_rad_s": ("gyro", "bias_deg_h"),
    "gyro_arw_rad_rts": ("gyro", "arw_deg_rth"),
    "gyro_bias_instability_rad_s": ("gyro", "bias_instability_deg_h"),
    "gyro_correlation_s": ("gyro", "correlation_s"),
    "gyro_rrw_rad_s_rts": ("gyro", "rrw_deg_h_rth"),
    "gyro_scale": ("gyro", "scale_ppm"),
    "gyro_misalignment_rad": ("gyro", "misalignment_arcsec"),
    "accel_bias_m_s2": ("accel", "bias_ug"),
    "accel_vrw_m_s_rts": ("accel", "vrw_ug_rthz"),
    "accel_scale": ("accel", "scale_ppm"),
    "temp_start_c": ("temperature", "start_c"),
    "temp_end_c": ("temperature", "end_c"),
    "temp_tau_s": ("temperature", "tau_h"),
    "temp_series_t_s": ("temperature", "series_t_h"),
    "temp_series_c": ("temperature", "series_temp_c"),
    "drift_t0_c": ("temperature", "t0_c"),
    "drift_k1_rad_s_per_c": ("temperature", "k1_deg_h_per_c"),
    "drift_k2_rad_s_per_c2": ("temperature", "k2_deg_h_per_c2"),
    "drift_k3_rad_s_per_c_per_s": ("temperature", "k3_deg_h_per_c_per_h"),
    "trajectory": ("trajectory", "segments"),
}
"""The TOML section and key of each keyword of `gyrodrift._core.SimulatorConfig` (for the core's refusals)."""


def _fmt(v: float) -> str:
    """Print 90.0 as 90 and 0.5 as 0.5 in messages."""
    return str(int(v)) if float(v).is_integer() and abs(v) < 1e15 else repr(float(v))
