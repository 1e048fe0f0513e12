"""Scenario files: a TOML description of one simulated static-base run, validated into frozen dataclasses.

Every key carries its user unit in its name (``lat_deg``, ``bias_deg_h``, ``vrw_ug_rthz``).
`Scenario.to_core_config` converts to the typed SI config of the core (`gyrodrift._core.SimulatorConfig`,
docs/ins-binding-contract.md);
`Scenario.to_toml_dict` / `write_scenario_toml` give back the fully resolved scenario (every default
written out, a temperature series inlined) that reloads to an equal object.

Sections and defaults are documented key by key in docs/scenarios.md. Each section's keys are declared once
(`SITE_FIELDS`, `RUN_FIELDS`, ... with the specs of `gyrodrift.files.toml_schema`; the moving base's
``[trajectory]`` in `gyrodrift.ins.route`), with the core's limits. Any unknown section or key, wrong type,
wrong vector length, non-finite number or out-of-range value raises `ScenarioError` whose message starts with
the file and the key, e.g. ``scenario.toml: [gyro] bias_deg_h: expected 3 numbers, got 2``.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gyrodrift import _core
from gyrodrift.errors import CoreError, InputError
from gyrodrift.files.toml_input import read_toml
from gyrodrift.files.toml_schema import Choice, Field, Integer, Number, Numbers, Scope, fmt_number, show, type_name
from gyrodrift.ins.route import Trajectory, read_trajectory
from gyrodrift.site import Site
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, DEG_PER_SQRT_H, HOUR, MICRO_G

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

    Temperature: a warm-up with a daily swing,
    T(t) = end_c + (start_c - end_c) exp(-t / tau_h) + swing_amplitude_c sin(360 t / swing_period_h + swing_phase_deg)
    [deg C, h, deg] (no swing by default), or a measured series (series_t_h [h], series_temp_c [deg C], linearly
    interpolated) which overrides the warm-up and takes no swing.
    Axial drift [deg/h], added to the z gyro:
    k1 (T - t0_c) + k2 (T - t0_c)^2 + k3 dT/dt, with k1 [deg/h/degC], k2 [deg/h/degC^2],
    k3 [deg/h per degC/h] and dT/dt in degC/h.
    """

    start_c: float = 20.0
    end_c: float = 20.0
    tau_h: float = 1.0
    swing_amplitude_c: float = 0.0
    swing_period_h: float = 24.0
    swing_phase_deg: float = 0.0
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


DRIVE_H = 72.0
"""Default length of the drive after the static period [h] (the paper's 1 nmi / 72 h)."""


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
        return _read_scenario(data, source, Path(base_dir) if base_dir is not None else Path("."))

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
                out["trajectory"] = section.to_toml_dict()
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
            temp_swing_amplitude_c=float(t.swing_amplitude_c),
            temp_swing_period_s=t.swing_period_h * HOUR,
            temp_swing_phase_rad=t.swing_phase_deg * DEG,
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
# Validation: each section's keys declared once (`gyrodrift.files.toml_schema`) with the core's limits
# --------------------------------------------------------------------------------------------------

SECTIONS = ("site", "run", "rotation", "gyro", "accel", "temperature", "attitude", "trajectory")
"""The sections of a scenario file, in the order of docs/scenarios.md."""


class _Span:
    """``[rotation] span_deg``: a number > 0 [deg] (checked by `number`) or the string "balanced"."""

    def __init__(self, number: Number):
        self.number = number

    def read(self, scope: Scope, key: str, v: Any) -> float | str:
        if v == BALANCED and isinstance(v, str):
            return v
        if isinstance(v, (str, bool)) or not isinstance(v, (int, float)):
            got = show(v) if isinstance(v, str) else f"{type_name(v)} {show(v)}"
            raise scope.fail(key, f'expected a number > 0 or "{BALANCED}", got {got}')
        return self.number.read(scope, key, v)

    def default(self, v: Any) -> float | str:
        return v if isinstance(v, str) else float(v)


_TEMP_C = Number.in_range(-100.0, 200.0)

SITE_FIELDS: dict[str, Field] = {
    "lat_deg": Number.in_range(-_core.MAX_LAT_DEG, _core.MAX_LAT_DEG),
    "lon_deg": Number.in_range(-_core.MAX_LON_DEG, _core.MAX_LON_DEG),
    "height_m": Number.in_range(_core.MIN_HEIGHT_M, _core.MAX_HEIGHT_M),
}
RUN_FIELDS: dict[str, Field] = {
    "duration_h": Number.positive(_core.MAX_DURATION_S / HOUR, " h"),
    "rate_hz": Number.in_range(_core.MIN_RATE_HZ, _core.MAX_RATE_HZ),
    "seed": Integer(ge=0, lt=2**64, lt_text="2**64"),
}
ROTATION_FIELDS: dict[str, Field] = {  # scheme is read first: the dwell's default depends on it
    "rate_deg_s": Number.positive(_core.MAX_TABLE_RATE_DEG_S, " deg/s"),
    "accel_deg_s2": Number.positive(_core.MAX_TABLE_ACCEL_DEG_S2),
    "span_deg": _Span(Number.positive(_core.MAX_SPAN_DEG, " deg")),
    "positions_deg": Numbers(),
    "dwell_s": Number.non_negative(),
}
GYRO_FIELDS: dict[str, Field] = {
    "bias_deg_h": Numbers(3),
    "arw_deg_rth": Number.non_negative(),
    "bias_instability_deg_h": Number.non_negative(),
    "correlation_s": Number.positive(),
    "rrw_deg_h_rth": Number.non_negative(),
    "scale_ppm": Numbers(3),
    "misalignment_arcsec": Numbers(6),
}
ACCEL_FIELDS: dict[str, Field] = {"bias_ug": Numbers(3), "vrw_ug_rthz": Number.non_negative(), "scale_ppm": Numbers(3)}
TEMPERATURE_FIELDS: dict[str, Field] = {  # the series (inline or series_csv) are read first
    "start_c": _TEMP_C,
    "end_c": _TEMP_C,
    "tau_h": Number.positive(),
    "swing_amplitude_c": Number.non_negative(),
    "swing_period_h": Number.positive(),
    "swing_phase_deg": Number(),
    "t0_c": _TEMP_C,
    "k1_deg_h_per_c": Number(),
    "k2_deg_h_per_c2": Number(),
    "k3_deg_h_per_c_per_h": Number(),
}
ATTITUDE_FIELDS: dict[str, Field] = {
    "pitch_deg": Number.in_range(-_core.MAX_PITCH_DEG, _core.MAX_PITCH_DEG, strictly=True),
    "roll_deg": Number.in_range(-_core.MAX_ROLL_DEG, _core.MAX_ROLL_DEG),
    "yaw_deg": Number.in_range(-_core.MAX_YAW_DEG, _core.MAX_YAW_DEG),
}


def _read_scenario(data: Mapping[str, Any], source: str, base_dir: Path) -> Scenario:
    """Turn a TOML-shaped mapping into a `Scenario`, naming the file and key in every error."""
    root = Scope(source, ScenarioError)
    if not isinstance(data, Mapping):
        raise root.fail(None, f"expected a table of sections, got {type_name(data)}")
    for name in data:
        if name not in SECTIONS:
            raise root.fail(None, f"unknown section [{name}] (expected one of: {', '.join(SECTIONS)})")

    def site() -> Site:
        return Site(**_fields(root, data, "site", Site, SITE_FIELDS))

    def attitude() -> Attitude:
        return Attitude(**_fields(root, data, "attitude", Attitude, ATTITUDE_FIELDS))

    def origin() -> tuple[tuple[float, float, float], float]:
        s = site()
        return (s.lat_deg, s.lon_deg, s.height_m), attitude().yaw_deg

    trajectory = read_trajectory(root, data, origin)
    run = _run(root, data)
    if trajectory is not None and "duration_h" not in data.get("run", {}):
        run = dataclasses.replace(run, duration_h=trajectory.static_h + DRIVE_H)
    scenario = Scenario(
        trajectory=trajectory,
        site=site(),
        run=run,
        rotation=_rotation(root, data),
        gyro=Gyro(**_fields(root, data, "gyro", Gyro, GYRO_FIELDS)),
        accel=Accel(**_fields(root, data, "accel", Accel, ACCEL_FIELDS)),
        temperature=_temperature(root, data, base_dir),
        attitude=attitude(),
    )
    _core_check(root, scenario, data)
    return scenario


def _fields(root: Scope, data: Mapping[str, Any], name: str, cls: type, specs: Mapping[str, Field]) -> dict[str, Any]:
    """The keys of `specs` in section `name` (whose keys are the fields of the dataclass `cls`), absent ones from
    ``cls()``."""
    t = root.table(data, name, [f.name for f in dataclasses.fields(cls)])
    return root.section(name).fields(t, specs, cls())


def _run(root: Scope, data: Mapping[str, Any]) -> Run:
    run = Run(**_fields(root, data, "run", Run, RUN_FIELDS))
    if round(run.duration_h * HOUR * run.rate_hz) < 1:
        raise root.section("run").fail("duration_h", "shorter than one sample")
    return run


def _rotation(root: Scope, data: Mapping[str, Any]) -> Rotation:
    t = root.table(data, "rotation", [f.name for f in dataclasses.fields(Rotation)])
    scope = root.section("rotation")
    scheme = scope.value(t, "scheme", Choice(ROTATION_SCHEMES), Rotation.scheme)
    defaults = Rotation(scheme=scheme, dwell_s=300.0 if scheme == "indexing" else Rotation.dwell_s)
    rot = Rotation(scheme=scheme, **scope.fields(t, ROTATION_FIELDS, defaults))
    if rot.scheme == "reciprocating" and rot.balanced_span:
        try:
            _core.balanced_reciprocating_span_rad(rot.rate_deg_s * DEG, rot.accel_deg_s2 * DEG, rot.dwell_s)
        except ValueError:
            raise scope.fail(
                "span_deg",
                f"no balanced span within half a turn at accel_deg_s2 = {fmt_number(rot.accel_deg_s2)} and "
                f"rate_deg_s = {fmt_number(rot.rate_deg_s)} (the ramps are too slow); raise accel_deg_s2 or give "
                "a number",
            ) from None
    return rot


def _temperature(root: Scope, data: Mapping[str, Any], base_dir: Path) -> Temperature:
    t = root.table(data, "temperature", [f.name for f in dataclasses.fields(Temperature)] + ["series_csv"])
    scope = root.section("temperature")
    series_t = series_c = None
    if "series_csv" in t:
        for other in ("series_t_h", "series_temp_c"):
            if other in t:
                raise scope.fail("series_csv", f"give either series_csv or {other}, not both")
        series_t, series_c = _read_series_csv(scope, t["series_csv"], base_dir)
    elif "series_t_h" in t or "series_temp_c" in t:
        for key, other in (("series_t_h", "series_temp_c"), ("series_temp_c", "series_t_h")):
            if key not in t:
                raise scope.fail(key, f"missing (required together with {other})")
        series_t = scope.value(t, "series_t_h", Numbers(), ())
        series_c = scope.value(t, "series_temp_c", Numbers(), ())
        if len(series_t) != len(series_c):
            raise scope.fail("series_temp_c", f"expected {len(series_t)} numbers (as series_t_h), got {len(series_c)}")
    if series_t is not None:
        key = "series_csv" if "series_csv" in t else "series_t_h"
        if len(series_t) < 2:
            raise scope.fail(key, f"expected at least 2 samples, got {len(series_t)}")
        if any(b <= a for a, b in zip(series_t, series_t[1:], strict=False)):
            raise scope.fail(key, "times must be strictly increasing")
    values = scope.fields(t, TEMPERATURE_FIELDS, Temperature())
    if series_t is not None and values["swing_amplitude_c"] != 0.0:
        raise scope.fail("swing_amplitude_c", "expected 0 with a temperature series (the series carries its swings)")
    return Temperature(series_t_h=series_t, series_temp_c=series_c, **values)


def _read_series_csv(scope: Scope, value: Any, base_dir: Path) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """``[temperature] series_csv``: a CSV file with columns t_h [h] and temp_c [deg C], relative to `base_dir`."""
    key = "series_csv"
    if not isinstance(value, str):
        raise scope.fail(key, f"expected a file name, got {type_name(value)} {show(value)}")
    path = Path(value)
    if not path.is_absolute():
        path = base_dir / path
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows: list[dict[str, str]] = []
            for row in csv.DictReader(fh):
                if len(rows) == MAX_SERIES_ROWS:
                    raise scope.fail(key, f"{path}: more than {MAX_SERIES_ROWS} rows")
                rows.append(row)
    except FileNotFoundError:
        raise scope.fail(key, f"{path}: no such file") from None
    except IsADirectoryError:
        raise scope.fail(key, f"{path}: is a folder, expected a CSV file") from None
    except OSError as exc:
        raise scope.fail(key, f"{path}: cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise scope.fail(key, f"{path}: not UTF-8 text (byte {exc.start} of a block)") from None
    except csv.Error as exc:
        raise scope.fail(key, f"{path}: not a CSV table: {exc}") from None
    if not rows or "t_h" not in rows[0] or "temp_c" not in rows[0]:
        raise scope.fail(key, f"{path}: expected columns t_h, temp_c and at least one row")
    ts, cs = [], []
    for line, row in enumerate(rows, start=2):
        try:
            tv, cv = float(row["t_h"]), float(row["temp_c"])
        except (TypeError, ValueError):
            raise scope.fail(key, f"{path}:{line}: expected numbers in t_h, temp_c") from None
        if not (math.isfinite(tv) and math.isfinite(cv)):
            raise scope.fail(key, f"{path}:{line}: expected finite numbers in t_h, temp_c")
        ts.append(tv)
        cs.append(cv)
    return tuple(ts), tuple(cs)


def _core_check(root: Scope, scenario: Scenario, data: Mapping[str, Any]) -> None:
    """Let the core validate the whole run (its ranges are the one source); name the TOML key it refuses."""
    try:
        scenario.to_core_config()
    except CoreError as exc:
        key = str(getattr(exc, "key", "") or "")
        section, toml_key = _CORE_KEYS.get(key, (None, None))
        if toml_key in ("series_t_h", "series_temp_c") and "series_csv" in data.get("temperature", {}):
            toml_key = "series_csv"
        if toml_key == "segments" and "waypoints" in data.get("trajectory", {}):
            toml_key = "waypoints"  # the segments were made from them
        msg = str(exc)
        if key and msg.startswith(f"{key}: "):
            msg = msg[len(key) + 2 :]
        raise (root if section is None else root.section(section)).fail(toml_key, msg) from None


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
    "temp_swing_amplitude_c": ("temperature", "swing_amplitude_c"),
    "temp_swing_period_s": ("temperature", "swing_period_h"),
    "temp_swing_phase_rad": ("temperature", "swing_phase_deg"),
    "temp_series_t_s": ("temperature", "series_t_h"),
    "temp_series_c": ("temperature", "series_temp_c"),
    "drift_t0_c": ("temperature", "t0_c"),
    "drift_k1_rad_s_per_c": ("temperature", "k1_deg_h_per_c"),
    "drift_k2_rad_s_per_c2": ("temperature", "k2_deg_h_per_c2"),
    "drift_k3_rad_s_per_c_per_s": ("temperature", "k3_deg_h_per_c_per_h"),
    "trajectory": ("trajectory", "segments"),
}
"""The TOML section and key of each keyword of `gyrodrift._core.SimulatorConfig` (for the core's refusals)."""
