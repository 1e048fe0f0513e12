"""The procedure's results: plain frozen dataclasses, in user units, with their JSON form (`to_dict`).

The algorithms (`align`, `passes`, `truth`, `features`, `evaluate`, `identify`) produce them; the writers
(`gyrodrift.procedure.writers`) and the figures (`gyrodrift.procedure.figures`) take them. This module imports
neither, nor matplotlib, nor the file system: the dependency runs one way, algorithms -> results <- outputs.

- `Alignment` (`align_log`): attitude, biases and their 1-sigma at the end of alignment.
- `NavCurve`, `TemperatureStats`, `PassResult` (`navigate_after_alignment`): the error curves of one read.
- `SmootherEstimate` (`smooth_log`): the 16 h smoother's drift, its 1-sigma and history.
- `TrueDrift` (`find_true_drift`), `RunFeatures` (`extract_features`; `RunFeatures.row` is its run-table row),
  `Evaluation` (`evaluate_compensation`), `Identification` (`identify`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from gyrodrift.drift_law import DriftLaw
from gyrodrift.earth import NMI_M
from gyrodrift.ins.compensation import compensation_record
from gyrodrift.learn.fleet_prior import drift_with_coefficient_prior
from gyrodrift.runs.columns import FEATURES_COLUMNS, LABEL_COLUMNS, SMOOTHER_THERMAL_COLUMNS, TRUTH_LAW_COLUMNS
from gyrodrift.site import Site
from gyrodrift.units import DEG, DEG_PER_H, MICRO_G

if TYPE_CHECKING:  # pragma: no cover
    from gyrodrift import _core
    from gyrodrift.procedure.best_law import BestLaw

__all__ = [
    "Alignment",
    "NavCurve",
    "TemperatureStats",
    "PassResult",
    "TrueDrift",
    "RunFeatures",
    "Evaluation",
    "Identification",
    "SmootherEstimate",
]


@dataclass(frozen=True)
class Alignment:
    """The outcome of the alignment, in user units.

    Attributes
    ----------
    run : str
        Name of the log.
    site : Site
        The known static site used [deg, deg, m].
    samples_used : int
        Samples consumed by the alignment; navigation starts with the next one.
    t_s : float
        End of the alignment [s] as the aligner counts it (samples_used / rate_hz).
    pitch_deg, roll_deg, yaw_deg : float
        Attitude at the end of alignment (yaw counter-clockwise about Up).
    coarse_pitch_deg, coarse_roll_deg, coarse_yaw_deg : float
        Attitude from the coarse alignment.
    vel_enu_m_s : tuple of 3 floats
        Velocity estimate at the end (ENU) [m/s].
    gyro_bias_deg_h, gyro_bias_std_deg_h : tuple of 3 floats
        Gyro bias estimates and their 1-sigma, body x y z [deg/h].
    accel_bias_ug, accel_bias_std_ug : tuple of 3 floats
        Accelerometer bias estimates and 1-sigma, body x y z [ug].
    att_std_arcsec : tuple of 3 floats
        Attitude error 1-sigma, E N U [arcsec].
    hist_t_h : ndarray
        Times of the covariance history [h from the start of the log].
    hist_gyro_z_std_deg_h : ndarray
        1-sigma of the z (axial) gyro bias over the alignment [deg/h].
    """

    run: str
    site: Site
    rate_hz: float
    samples_used: int
    t_s: float
    pitch_deg: float
    roll_deg: float
    yaw_deg: float
    coarse_pitch_deg: float
    coarse_roll_deg: float
    coarse_yaw_deg: float
    vel_enu_m_s: tuple[float, float, float]
    gyro_bias_deg_h: tuple[float, float, float]
    gyro_bias_std_deg_h: tuple[float, float, float]
    accel_bias_ug: tuple[float, float, float]
    accel_bias_std_ug: tuple[float, float, float]
    att_std_arcsec: tuple[float, float, float]
    hist_t_h: np.ndarray = field(repr=False)
    hist_gyro_z_std_deg_h: np.ndarray = field(repr=False)

    @property
    def z_drift_deg_h(self) -> float:
        """The alignment's own axial (z) drift estimate [deg/h] (reported, never applied)."""
        return self.gyro_bias_deg_h[2]

    @property
    def z_drift_std_deg_h(self) -> float:
        """Its 1-sigma at the end of alignment [deg/h]."""
        return self.gyro_bias_std_deg_h[2]

    def navigator_config(self, vertical: str = "fixed") -> _core.NavigatorConfig:
        """SI config of `_core.Navigator` starting at the end of alignment (static site, aligned state), with the
        vertical channel `vertical` ("fixed" or "damped")."""
        from gyrodrift import _core

        return _core.NavigatorConfig(
            **self.site.core_position(),
            vel_enu_m_s=[float(v) for v in self.vel_enu_m_s],
            pitch_rad=self.pitch_deg * DEG,
            roll_rad=self.roll_deg * DEG,
            yaw_rad=self.yaw_deg * DEG,
            rate_hz=float(self.rate_hz),
            vertical=vertical,
        )

    def gyro_compensation_rad_s(self, z_drift_deg_h: float) -> list[float]:
        """Gyro biases for `Navigator.set_gyro_bias`: estimated x, y and the given z drift [deg/h] (SI)."""
        return [self.gyro_bias_deg_h[0] * DEG_PER_H, self.gyro_bias_deg_h[1] * DEG_PER_H, z_drift_deg_h * DEG_PER_H]

    def accel_compensation_m_s2(self) -> list[float]:
        """All three accelerometer bias estimates for `Navigator.set_accel_bias` [m/s^2]."""
        return [b * MICRO_G for b in self.accel_bias_ug]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (user units; the history as lists)."""
        d = asdict(self)
        d["site"] = asdict(self.site)
        d["hist_t_h"] = [float(x) for x in self.hist_t_h]
        d["hist_gyro_z_std_deg_h"] = [float(x) for x in self.hist_gyro_z_std_deg_h]
        for k, v in list(d.items()):
            if isinstance(v, tuple):
                d[k] = [float(x) for x in v]
        d["format"] = "gyrodrift-alignment/1"
        return d


@dataclass(frozen=True)
class NavCurve:
    """Position error of one navigation pass over time (computed minus true).

    Attributes
    ----------
    drift_deg_h : float
        z-gyro drift subtracted in this pass [deg/h].
    t_h : ndarray (m,)
        Time since the start of navigation (end of alignment) [h], every ``decimation_s``, and the exact end
        of the pass as the last value (also when it is not a multiple of ``decimation_s``).
    north_m, east_m : ndarray (m,)
        North and east position errors [m].
    lat_err_arcsec, lon_err_arcsec : ndarray (m,)
        Latitude and longitude errors [arcsec].
    hourly_lat_deg, hourly_lat_err_arcsec : ndarray (h + 1,)
        Latitude and its error at whole navigation hours 0, 1, ..., exact (not decimated).
    """

    drift_deg_h: float
    t_h: np.ndarray = field(repr=False)
    north_m: np.ndarray = field(repr=False)
    east_m: np.ndarray = field(repr=False)
    lat_err_arcsec: np.ndarray = field(repr=False)
    lon_err_arcsec: np.ndarray = field(repr=False)
    hourly_lat_deg: np.ndarray = field(repr=False)
    hourly_lat_err_arcsec: np.ndarray = field(repr=False)

    @property
    def pos_err_nmi(self) -> np.ndarray:
        """Horizontal position error [nmi, 1852 m]."""
        return np.hypot(self.north_m, self.east_m) / NMI_M

    @property
    def final_nmi(self) -> float:
        """Position error at the end of the pass [nmi]."""
        return float(self.pos_err_nmi[-1])

    @property
    def max_nmi(self) -> float:
        """Largest position error over the pass [nmi]."""
        return float(np.max(self.pos_err_nmi))


@dataclass(frozen=True)
class TemperatureStats:
    """System temperature over the first ``hours`` of navigation [deg C]: at the first and last sample,
    lowest and highest."""

    hours: float
    start_c: float
    end_c: float
    min_c: float
    max_c: float


@dataclass(frozen=True)
class PassResult:
    """Curves of the navigators of one read (in the order of the drifts asked) and the temperature; the vertical
    channel the navigators used and its reference height's source (as in `Evaluation`)."""

    curves: list[NavCurve]
    temperature: TemperatureStats | None
    hours: float
    vertical: str = "fixed"
    vertical_reference: str | None = None


@dataclass(frozen=True)
class TrueDrift:
    """The true axial drift of a run and the evidence for it.

    Attributes
    ----------
    run : str
    drift_deg_h : float
        The z-gyro drift minimising the criterion [deg/h] (subtract it from the z gyro).
    criterion : str
        ``final``, ``rms`` or ``max``.
    hours : float
        Navigation hours after alignment over which the criterion is taken.
    predicted_nmi : float
        Criterion at ``drift_deg_h`` predicted by the linear model [nmi].
    verify_drift_deg_h : ndarray (3,)
        ``d* - step``, ``d*``, ``d* + step`` [deg/h], navigated in the verification read.
    verify_nmi : ndarray (3,)
        The criterion of those three navigations [nmi].
    verified : bool
        The navigated criterion at ``d*`` is not above either neighbour.
    uncompensated_nmi : float
        Criterion with no z compensation [nmi].
    grid_drift_deg_h, grid_nmi : ndarray
        The criterion curve from the linear model on a grid around ``d*``.
    sensitivity_nmi_per_deg_h : float
        Position error at the end per deg/h of z drift (hypot of the final north/east sensitivities).
    refinements : int
        Verification reads that moved ``d*`` (0 when the first linearisation was exact enough).
    last_step_deg_h : float
        The move the last re-linearisation asked for [deg/h] (below `tolerance_deg_h` unless the
        refinements ran out; NaN without the verification read).
    alignment : Alignment
    base : NavCurve
        The uncompensated navigation (z drift 0), kept for the features.
    optimum : NavCurve or None
        The verification navigation at ``d*`` (None without the verification read).
    trial : NavCurve or None
        The first read's navigation at ``trial_deg_h`` (with ``base``, the first linearisation's secant).
    temperature : TemperatureStats or None
        Temperature over the features window of the first read (when asked).
    drift_std_deg_h : float
        1-sigma of the label from the linear covariance analysis at the log's noise level [deg/h] (NaN when not
        computed); ``max`` takes the ``rms`` value (an approximation).
    flagged : bool
        The 72 h sensitivity is too low to label the run: the label's 1-sigma exceeds the 1 nmi / 72 h budget
        (`gyrodrift.procedure.truth.label_budget_deg_h`); ``flag_reason`` says why.
    flag_reason : str
    noise : dict or None
        The noise model of the covariance analysis (`SensorNoise.to_dict`).
    noise_note : str or None
        The caveat when that noise was measured from the log (`SensorNoise.white_only_note`: white noise only, the
        label's 1-sigma leaves out a bias instability), else None.
    law : BestLaw or None
        The best drift law (`gyrodrift.procedure.truth_law`); None without a temperature or when not asked.
    """

    run: str
    drift_deg_h: float
    criterion: str
    hours: float
    trial_deg_h: float
    predicted_nmi: float
    verify_drift_deg_h: np.ndarray
    verify_nmi: np.ndarray
    verified: bool
    uncompensated_nmi: float
    grid_drift_deg_h: np.ndarray = field(repr=False)
    grid_nmi: np.ndarray = field(repr=False)
    sensitivity_nmi_per_deg_h: float = 0.0
    refinements: int = 0
    last_step_deg_h: float = 0.0
    alignment: Alignment | None = field(default=None, repr=False)
    base: NavCurve | None = field(default=None, repr=False)
    optimum: NavCurve | None = field(default=None, repr=False)
    trial: NavCurve | None = field(default=None, repr=False)
    temperature: Any = field(default=None, repr=False)
    drift_std_deg_h: float = math.nan
    flagged: bool = False
    flag_reason: str = ""
    noise: dict | None = field(default=None, repr=False)
    noise_note: str | None = None
    law: BestLaw | None = field(default=None, repr=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (user units)."""
        return {
            "format": "gyrodrift-true-drift/1",
            "run": self.run,
            "drift_deg_h": self.drift_deg_h,
            "drift_std_deg_h": None if not math.isfinite(self.drift_std_deg_h) else self.drift_std_deg_h,
            "flagged": bool(self.flagged),
            "flag_reason": self.flag_reason,
            "noise": self.noise,
            "noise_note": self.noise_note,
            "criterion": self.criterion,
            "hours": self.hours,
            "trial_deg_h": self.trial_deg_h,
            "predicted_nmi": self.predicted_nmi,
            "uncompensated_nmi": self.uncompensated_nmi,
            "verify": [
                {"drift_deg_h": float(d), "criterion_nmi": float(v)}
                for d, v in zip(self.verify_drift_deg_h, self.verify_nmi, strict=False)
            ],
            "verified": bool(self.verified),
            "sensitivity_nmi_per_deg_h": self.sensitivity_nmi_per_deg_h,
            "refinements": self.refinements,
            "last_step_deg_h": self.last_step_deg_h if math.isfinite(self.last_step_deg_h) else None,
            "alignment_z_drift_deg_h": None if self.alignment is None else self.alignment.z_drift_deg_h,
            "alignment_z_drift_std_deg_h": None if self.alignment is None else self.alignment.z_drift_std_deg_h,
            "grid": {
                "drift_deg_h": [float(x) for x in self.grid_drift_deg_h],
                "criterion_nmi": [float(x) for x in self.grid_nmi],
            },
            "best_law": None if self.law is None else self.law.to_dict(),
        }


SMOOTHER_THERMAL_FIELDS = (
    "thermal_coeff_deg_h_per_c",
    "thermal_coeff_std_deg_h_per_c",
    "end_coeff_cov",
    "thermal_prior_std_deg_h_per_c",
)
"""The `SmootherEstimate` attributes the columns `SMOOTHER_THERMAL_COLUMNS` (`gyrodrift.runs.columns`) hold, in
order."""


@dataclass(frozen=True)
class RunFeatures:
    """The features of one run (one row of a run table) and how they were obtained.

    Attributes
    ----------
    run : str
        The log's name (file stem).
    lat_deg : float
        Navigated latitude at navigation hour `hours` (12) [deg].
    lat0_deg : float
        True site latitude [deg].
    lat_err_curve_arcsec : ndarray (hours + 1,)
        Latitude error at navigation hours 0, 1, ..., 12 [arcsec], computed minus true.
    temp_start_c, temp_end_c, temp_min_c, temp_max_c : float
        Temperature over the 12 h [deg C].
    drift_deg_h : float
        The true drift when asked (`with_truth`), else NaN [deg/h].
    drift_curvefit_deg_h, drift_curvefit_std_deg_h : float
        The drift from the 12 h curve fit of the latitude and longitude error curves and its 1-sigma [deg/h]
        (`gyrodrift.learn.curve_fit`).
    drift_smoother_deg_h, drift_smoother_std_deg_h : float
        The 16 h smoother's drift carried into navigation and its 1-sigma [deg/h]
        (`SmootherEstimate.navigation_drift_deg_h`: the end-of-span drift under its thermal model; NaN when not
        run).
    smoother_coeff_deg_h_per_c, smoother_coeff_std_deg_h_per_c : float
        The smoother's thermal coefficient k_z and its 1-sigma [deg/h/degC] (NaN under its constant model or when
        not run).
    smoother_end_coeff_cov : float
        cov(``drift_smoother_deg_h``, k_z) [(deg/h)^2/degC] (NaN likewise).
    smoother_coeff_prior_std_deg_h_per_c : float
        The smoother's own prior 1-sigma of k_z (mean 0) [deg/h/degC] (NaN likewise).
    drift_std_deg_h : float
        1-sigma of the truth label (NaN without truth) [deg/h].
    label_flagged : bool
        The truth label is beyond the 1 nmi / 72 h budget (``TrueDrift.flagged``).
    hours : float
        Navigation hours of the features (12).
    alignment : Alignment
    truth : TrueDrift or None
    smoother : SmootherEstimate or None
    """

    run: str
    lat_deg: float
    lat0_deg: float
    lat_err_curve_arcsec: np.ndarray = field(repr=False)
    temp_start_c: float = math.nan
    temp_end_c: float = math.nan
    temp_min_c: float = math.nan
    temp_max_c: float = math.nan
    drift_deg_h: float = math.nan
    hours: float = 12.0
    alignment: Alignment | None = field(default=None, repr=False)
    truth: TrueDrift | None = field(default=None, repr=False)
    drift_curvefit_deg_h: float = math.nan
    drift_curvefit_std_deg_h: float = math.nan
    drift_smoother_deg_h: float = math.nan
    drift_smoother_std_deg_h: float = math.nan
    drift_std_deg_h: float = math.nan
    label_flagged: bool = False
    smoother: SmootherEstimate | None = field(default=None, repr=False)
    smoother_coeff_deg_h_per_c: float = math.nan
    smoother_coeff_std_deg_h_per_c: float = math.nan
    smoother_end_coeff_cov: float = math.nan
    smoother_coeff_prior_std_deg_h_per_c: float = math.nan

    @property
    def lat_err_arcsec(self) -> float:
        """Latitude error at the end of the features window [arcsec] (computed minus true)."""
        return (self.lat_deg - self.lat0_deg) * 3600.0

    def row(self) -> dict[str, Any]:
        """The run-table row (`gyrodrift.runs.columns.FEATURES_COLUMNS`, plus the ``LABEL_COLUMNS``
        ``drift_deg_h``, ``drift_std_deg_h``, ``label_flagged`` and the ``TRUTH_LAW_COLUMNS`` when the truth is
        known)."""
        more = LABEL_COLUMNS + TRUTH_LAW_COLUMNS if math.isfinite(self.drift_deg_h) else ()
        return {column: self.column(column) for column in FEATURES_COLUMNS + more}

    def column(self, name: str) -> Any:
        """The value of the run-table column `name`: an attribute, or the truth's best law
        (`gyrodrift.runs.columns.TRUTH_LAW_COLUMNS`, `gyrodrift.procedure.best_law.BestLaw.columns`; NaN without)."""
        if name not in TRUTH_LAW_COLUMNS:
            return getattr(self, name)
        law = None if self.truth is None else self.truth.law
        return math.nan if law is None else law.columns()[name]


@dataclass(frozen=True)
class Evaluation:
    """Position errors over `hours` after alignment, before and after compensating `drift_deg_h`.

    Attributes
    ----------
    run : str
    drift_deg_h : float
        The compensated z drift [deg/h] (a drift law's ``eps_ref_deg_h``).
    hours : float
    before, after : NavCurve
        Error curves (``t_h`` since the end of alignment).
    source : str
        Where the drift came from (``"given"`` or the model file).
    reference : gyrodrift.ins.track.ReferenceTrack or None
        Moving base: the true track the errors are computed against (None: the static site).
    start_s : float
        Log time of the navigation start [s] (the end of the alignment): curve time t_h is log time
        start_s + 3600 t_h.
    vertical, vertical_reference : str, str or None
        The navigators' vertical channel ("fixed" on a static base; "damped" on a moving base or when the log has
        a ``ref_height_m`` column) and what its reference height was (the column, the reference track's height).
    """

    run: str
    drift_deg_h: float
    hours: float
    before: NavCurve = field(repr=False)
    after: NavCurve = field(repr=False)
    alignment: Alignment | None = field(default=None, repr=False)
    source: str = "given"
    reference: Any = field(default=None, repr=False)
    start_s: float = 0.0
    vertical: str = "fixed"
    vertical_reference: str | None = None
    drift_law: DriftLaw | None = None
    """The compensated drift law (`gyrodrift.procedure.evaluate_compensation`: a constant's too); None: the constant
    `drift_deg_h`."""

    @property
    def before_final_nmi(self) -> float:
        return self.before.final_nmi

    @property
    def after_final_nmi(self) -> float:
        return self.after.final_nmi

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: final and max position error [nmi], before and after."""
        return {
            "format": "gyrodrift-evaluation/1",
            "run": self.run,
            "drift_deg_h": self.drift_deg_h,
            **compensation_record(self.drift_law or DriftLaw.constant(self.drift_deg_h)),
            "drift_source": self.source,
            "reference": None if self.reference is None else self.reference.label,
            "vertical": self.vertical,
            "vertical_reference": self.vertical_reference,
            "hours": self.hours,
            "before": {"final_pos_err_nmi": self.before.final_nmi, "max_pos_err_nmi": self.before.max_nmi},
            "after": {"final_pos_err_nmi": self.after.final_nmi, "max_pos_err_nmi": self.after.max_nmi},
        }


@dataclass(frozen=True)
class Identification:
    """The identified axial drift of a run.

    Attributes
    ----------
    run : str
    drift_deg_h : float
        Model prediction [deg/h] (subtract from the z gyro).
    physics_drift_deg_h : float
        Physics inversion of the 12 h latitude error [deg/h].
    alignment_z_drift_deg_h, alignment_z_drift_std_deg_h : float
        The alignment's own z-gyro bias estimate and 1-sigma [deg/h] (not used).
    model_std_deg_h : float or None
        Predictive 1-sigma of the model; None for the LSSVR (it has none).
    interval_deg_h : tuple of float or None
        (low, high) jackknife interval of the identified drift [deg/h] at ``interval_coverage``; None when the
        model carries no leave-one-out residuals.
    interval_coverage : float
    uncertainty_note : str
    training_error_deg_h : float or None
        The model's error on its training runs [deg/h]: the mean absolute closed-form leave-one-out residual
        when the fitted estimator is at hand, else the best fitness of its tuning (model files keep no
        factorisation); None when neither is known.
    training_error_kind : str or None
        ``"loo_mae"``, or the tuning objective (``"loo_mae"``, ``"train_mae"``, ``"kfold_mae"``).
    features : RunFeatures
    curvefit_drift_deg_h, curvefit_drift_std_deg_h : float
        The 12 h curve fit's drift and 1-sigma [deg/h] (`gyrodrift.learn.curve_fit`).
    smoother_drift_deg_h, smoother_drift_std_deg_h : float
        The 16 h smoother's drift carried into navigation and its 1-sigma [deg/h] (`gyrodrift.procedure.smoother`;
        the end-of-span drift under its thermal model, `smoother_model`; NaN when not run).
    outside_training_range : bool
        The run's inputs lie outside the model's training runs' range (per input or jointly): an extrapolation.
    range_warnings : tuple of str
        What lies outside, one line each.
    outside_drift_range : bool
        The identified drift is beyond a navigation-grade RLG or far outside the training labels' range
        (`gyrodrift.runs.table.drift_range_problems`; its line is in ``range_warnings``).
    model_physics_column : str or None
        The physics base of a hybrid model (``DriftModel.physics_column_``, e.g. ``"drift_smoother_fleet_deg_h"``);
        None for a model fitted on the drift itself.
    smoother_fleet_drift_deg_h, smoother_fleet_drift_std_deg_h : float
        With the fleet base: the 16 h smoother's end drift with the training fleet's k_z prior and its 1-sigma
        [deg/h] (`gyrodrift.learn.fleet_prior.drift_with_coefficient_prior`), the base the model adds its learned
        correction to (``drift_deg_h`` minus it is that correction); NaN with any other base.
    coefficient_prior_deg_h_per_c : tuple of 2 floats or None
        With the fleet base: the model's pooled k_z prior (mean, 1-sigma) [deg/h/degC]
        (``DriftModel.coefficient_prior_``); None otherwise.
    mission : dict or None
        What the smoother's drift 1-sigma (with the fleet's k_z prior under the fleet base) means for the 72 h
        mission at the run's latitude (`gyrodrift.procedure.plan.mission_outlook`: predicted error quantiles after
        compensation, ``ready``, ``more_static_h``, ``note``); None when the smoother did not run.
    drift_law : DriftLaw or None
        The identified drift law (`gyrodrift.procedure.identify`, "The drift law"): eps_ref = ``drift_deg_h`` at
        T_ref, the temperature at the end of the features window; the constant when the model has no fleet base or
        the smoother no thermal model. None only for a result not made by ``identify``.
    """

    run: str
    drift_deg_h: float
    physics_drift_deg_h: float
    alignment_z_drift_deg_h: float
    alignment_z_drift_std_deg_h: float
    model_std_deg_h: float | None
    interval_deg_h: tuple[float, float] | None
    interval_coverage: float
    uncertainty_note: str
    training_error_deg_h: float | None
    training_error_kind: str | None
    features: RunFeatures = field(repr=False)
    curvefit_drift_deg_h: float = math.nan
    curvefit_drift_std_deg_h: float = math.nan
    outside_training_range: bool = False
    range_warnings: tuple[str, ...] = ()
    outside_drift_range: bool = False
    smoother_drift_deg_h: float = math.nan
    smoother_drift_std_deg_h: float = math.nan
    model_physics_column: str | None = None
    smoother_fleet_drift_deg_h: float = math.nan
    smoother_fleet_drift_std_deg_h: float = math.nan
    coefficient_prior_deg_h_per_c: tuple[float, float] | None = None
    mission: dict[str, Any] | None = None
    drift_law: DriftLaw | None = None

    @property
    def drift_law_std_deg_h(self) -> float:
        """1-sigma of the drift law at its T_ref [deg/h] (NaN when its covariance is unknown or there is no law)."""
        law = self.drift_law
        return math.nan if law is None else float(law.std_deg_h(law.t_ref_c))

    @property
    def smoother_model(self) -> str | None:
        """The smoother's model (``"thermal"`` or ``"constant"``; None when it did not run)."""
        sm = self.features.smoother
        return None if sm is None else sm.model

    @property
    def smoother_noise_note(self) -> str | None:
        """The caveat on the smoother's 1-sigma when its noise was measured from the log (white noise only,
        `SensorNoise.white_only_note`); None when the noise was given or the smoother did not run."""
        sm = self.features.smoother
        return None if sm is None or sm.noise is None else sm.noise.white_only_note

    def to_dict(self) -> dict[str, Any]:
        f = self.features
        return {
            "format": "gyrodrift-identification/1",
            "run": self.run,
            "drift_deg_h": self.drift_deg_h,
            "physics_drift_deg_h": self.physics_drift_deg_h,
            "curvefit_drift_deg_h": self.curvefit_drift_deg_h,
            "curvefit_drift_std_deg_h": self.curvefit_drift_std_deg_h,
            "smoother_drift_deg_h": self.smoother_drift_deg_h,
            "smoother_drift_std_deg_h": self.smoother_drift_std_deg_h,
            "smoother_model": self.smoother_model,
            "smoother_noise_note": self.smoother_noise_note,
            "model_physics_column": self.model_physics_column,
            "smoother_fleet_drift_deg_h": self.smoother_fleet_drift_deg_h,
            "smoother_fleet_drift_std_deg_h": self.smoother_fleet_drift_std_deg_h,
            "coefficient_prior_deg_h_per_c": (
                None if self.coefficient_prior_deg_h_per_c is None else list(self.coefficient_prior_deg_h_per_c)
            ),
            "outside_training_range": self.outside_training_range,
            "range_warnings": list(self.range_warnings),
            "outside_drift_range": self.outside_drift_range,
            "alignment_z_drift_deg_h": self.alignment_z_drift_deg_h,
            "alignment_z_drift_std_deg_h": self.alignment_z_drift_std_deg_h,
            "model_std_deg_h": self.model_std_deg_h,
            "interval_deg_h": None if self.interval_deg_h is None else list(self.interval_deg_h),
            "interval_coverage": self.interval_coverage,
            "uncertainty_note": self.uncertainty_note,
            "training_error_deg_h": self.training_error_deg_h,
            "training_error_kind": self.training_error_kind,
            "mission": self.mission,
            "drift_law": None if self.drift_law is None else self.drift_law.to_dict(),
            "features": {
                **f.row(),
                "lat_err_arcsec": f.lat_err_arcsec,
                "lat_err_curve_arcsec": [float(x) for x in f.lat_err_curve_arcsec],
            },
        }


@dataclass(frozen=True)
class SmootherEstimate:
    """The 16 h smoother's axial drift (`gyrodrift.procedure.smoother.smooth_log`), in user units.

    Attributes
    ----------
    run : str
    span_h : float
        Hours of the log used, from its first sample.
    drift_deg_h, drift_std_deg_h : float
        The constant-drift model's z-gyro bias (subtract it from the z gyro) and its 1-sigma [deg/h]: the
        Cramer-Rao line of the linear-Gaussian model without a thermal term (with the thermal state: conditioned
        on k_z = 0, exactly that model's posterior).
    drift_end_deg_h, drift_end_std_deg_h : float
        The z-gyro bias at the end of the span carried into navigation under the reported `model` (constant +
        random walk, + k_z (T_end - T_ref) under the thermal model) and its 1-sigma [deg/h]; equal to the constant
        without bias-drift terms under the constant model. A Gauss-Markov bias is left out (its mean over a
        mission of many correlation times is near zero; the history holds the total).
    model : {"thermal", "constant"}
        The model of the reported end drift and history: ``thermal`` when the thermal state ran and the
        temperature spanned at least its ``thermal_min_range_c``.
    drift_ref_deg_h, drift_ref_std_deg_h, thermal_coeff_deg_h_per_c, thermal_coeff_std_deg_h_per_c : float
        The thermal model's eps_z (the z drift at `temp_ref_c`) [deg/h] and k_z [deg/h/degC], with 1-sigma (NaN
        without the thermal state).
    temp_ref_c, temp_end_c, temp_range_c : float
        T_ref, the temperature at the end of the span and its range after the coarse alignment [degC] (NaN
        without the thermal state).
    end_coeff_cov : float
        Covariance of the thermal model's end drift with k_z [(deg/h)^2/degC] (NaN without the thermal state).
    thermal_prior_std_deg_h_per_c : float
        The filter's prior 1-sigma of k_z (mean 0) [deg/h/degC] (NaN without the thermal state).
    gyro_bias_deg_h, gyro_bias_std_deg_h : tuple of 3 floats
        Constant gyro biases, body x y z, and their 1-sigma [deg/h].
    accel_bias_ug, accel_bias_std_ug : tuple of 3 floats
        Accelerometer biases and 1-sigma [ug].
    hist_t_h, hist_drift_deg_h, hist_drift_std_deg_h, hist_filter_std_deg_h : ndarray
        The smoothed total z drift and its 1-sigma over the span [h from the first sample, deg/h], and the forward
        filter's 1-sigma at the same times.
    noise : SensorNoise
        The noise model the filter used (floored).
    max_attitude_correction_arcsec, max_velocity_correction_m_s, max_position_error_m : float
        Linearity check after the first hour: the largest feedback corrections and position error estimate.
    updates : int
        Measurement updates of the forward filter.
    """

    run: str
    span_h: float
    drift_deg_h: float
    drift_std_deg_h: float
    drift_end_deg_h: float
    drift_end_std_deg_h: float
    model: str
    drift_ref_deg_h: float
    drift_ref_std_deg_h: float
    thermal_coeff_deg_h_per_c: float
    thermal_coeff_std_deg_h_per_c: float
    temp_ref_c: float
    temp_end_c: float
    temp_range_c: float
    end_coeff_cov: float
    thermal_prior_std_deg_h_per_c: float
    gyro_bias_deg_h: tuple[float, float, float]
    gyro_bias_std_deg_h: tuple[float, float, float]
    accel_bias_ug: tuple[float, float, float]
    accel_bias_std_ug: tuple[float, float, float]
    hist_t_h: np.ndarray = field(repr=False)
    hist_drift_deg_h: np.ndarray = field(repr=False)
    hist_drift_std_deg_h: np.ndarray = field(repr=False)
    hist_filter_std_deg_h: np.ndarray = field(repr=False)
    noise: Any = None
    max_attitude_correction_arcsec: float = math.nan
    max_velocity_correction_m_s: float = math.nan
    max_position_error_m: float = math.nan
    updates: int = 0

    @property
    def navigation_drift_deg_h(self) -> float:
        """The drift the system carries into navigation [deg/h]: the end-of-span drift under the thermal model,
        the constant under the constant model."""
        return self.drift_end_deg_h if self.model == "thermal" else self.drift_deg_h

    @property
    def navigation_drift_std_deg_h(self) -> float:
        """1-sigma of `navigation_drift_deg_h` [deg/h]."""
        return self.drift_end_std_deg_h if self.model == "thermal" else self.drift_std_deg_h

    def thermal_columns(self) -> dict[str, float]:
        """The run-table columns of the thermal model (`SMOOTHER_THERMAL_COLUMNS`): k_z and its 1-sigma
        [deg/h/degC], cov(end drift, k_z) [(deg/h)^2/degC] and the prior 1-sigma of k_z [deg/h/degC]; all NaN
        under the constant model (the navigation drift is then the constant's, with no k_z behind it)."""
        thermal = self.model == "thermal"
        return {
            column: float(getattr(self, name)) if thermal else math.nan
            for column, name in zip(SMOOTHER_THERMAL_COLUMNS, SMOOTHER_THERMAL_FIELDS, strict=True)
        }

    def end_drift_with_coefficient_prior(self, mean_deg_h_per_c: float, std_deg_h_per_c: float) -> tuple[float, float]:
        """The end-of-span drift and its 1-sigma [deg/h] with another prior on k_z, N(mean, std^2) [deg/h/degC]
        (e.g. a fleet's coefficient, `fleet_coefficient_prior`) in place of the filter's N(0, prior std^2).

        Exact for the linear-Gaussian model: the joint posterior of (end drift d, k_z) is re-weighted by the ratio
        of the two priors. With V_k, c = cov(d, k_z), the new k_z precision is
        ``L = 1/V_k - 1/s0^2 + 1/std^2`` and mean ``k* = (k/V_k + mean/std^2) / L``; then
        ``d* = d + (c/V_k)(k* - k)``, ``var = V_d - c^2/V_k + (c/V_k)^2 / L``. Under the constant model (no
        thermal state, or a temperature that did not vary) the navigation drift is returned unchanged.
        """
        if self.model != "thermal":
            return self.navigation_drift_deg_h, self.navigation_drift_std_deg_h
        return drift_with_coefficient_prior(
            self.drift_end_deg_h,
            self.drift_end_std_deg_h,
            self.thermal_coeff_deg_h_per_c,
            self.thermal_coeff_std_deg_h_per_c,
            self.end_coeff_cov,
            self.thermal_prior_std_deg_h_per_c,
            mean_deg_h_per_c,
            std_deg_h_per_c,
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (user units; the history as lists; NaN as null)."""

        def num(x: float) -> float | None:
            return None if math.isnan(x) else x

        return {
            "format": "gyrodrift-smoother/2",
            "run": self.run,
            "span_h": self.span_h,
            "drift_deg_h": self.drift_deg_h,
            "drift_std_deg_h": self.drift_std_deg_h,
            "drift_end_deg_h": self.drift_end_deg_h,
            "drift_end_std_deg_h": self.drift_end_std_deg_h,
            "model": self.model,
            "navigation_drift_deg_h": self.navigation_drift_deg_h,
            "navigation_drift_std_deg_h": self.navigation_drift_std_deg_h,
            "drift_ref_deg_h": num(self.drift_ref_deg_h),
            "drift_ref_std_deg_h": num(self.drift_ref_std_deg_h),
            "thermal_coeff_deg_h_per_c": num(self.thermal_coeff_deg_h_per_c),
            "thermal_coeff_std_deg_h_per_c": num(self.thermal_coeff_std_deg_h_per_c),
            "temp_ref_c": num(self.temp_ref_c),
            "temp_end_c": num(self.temp_end_c),
            "temp_range_c": num(self.temp_range_c),
            "end_coeff_cov": num(self.end_coeff_cov),
            "gyro_bias_deg_h": list(self.gyro_bias_deg_h),
            "gyro_bias_std_deg_h": list(self.gyro_bias_std_deg_h),
            "accel_bias_ug": list(self.accel_bias_ug),
            "accel_bias_std_ug": list(self.accel_bias_std_ug),
            "noise": None if self.noise is None else self.noise.to_dict(),
            "max_attitude_correction_arcsec": self.max_attitude_correction_arcsec,
            "max_velocity_correction_m_s": self.max_velocity_correction_m_s,
            "max_position_error_m": self.max_position_error_m,
            "updates": self.updates,
            "history": {
                "t_h": [float(x) for x in self.hist_t_h],
                "drift_deg_h": [float(x) for x in self.hist_drift_deg_h],
                "drift_std_deg_h": [float(x) for x in self.hist_drift_std_deg_h],
                "filter_std_deg_h": [float(x) for x in self.hist_filter_std_deg_h],
            },
        }
