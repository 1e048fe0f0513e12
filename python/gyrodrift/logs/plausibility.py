"""The plausibility check of every IMU log: its first minutes must show a static base (`StaticMeans`).

The mean specific force magnitude is normal gravity at the site, it points along body up, the horizontal gyros
de-rotated by the table angle see the Earth rate's horizontal component and, with the table still, the axial gyro
its vertical one (docs/procedure.md, "A log is physically plausible"). A unit, scale, sign or axis slip fails one
of them: `ImplausibleLogError` names the check, the measured and expected values and the columns to look at.
`gyrodrift.logs.log.ImuLog.check_static_base` feeds the sums.
"""

from __future__ import annotations

import math

import numpy as np

from gyrodrift import _core
from gyrodrift.earth import OMEGA_IE_RAD_S, normal_gravity
from gyrodrift.logs.rows import G0, HEIGHT_LIMITS_M
from gyrodrift.logs.source import LogError, LogSource
from gyrodrift.site import Site
from gyrodrift.units import DEG_PER_H

__all__ = [
    "ImplausibleLogError",
    "StaticMeans",
    "STATIC_CHECK_SPAN_S",
    "MIN_STATIC_CHECK_SPAN_S",
    "SPECIFIC_FORCE_TOLERANCE_G",
    "EARTH_RATE_TOLERANCE_DEG_H",
    "MAX_UNDECLARED_TILT_DEG",
    "DECLARED_TILT_TOLERANCE_DEG",
    "TABLE_STILL_DEG",
]

STATIC_CHECK_SPAN_S = 300.0
"""Span at the start of every log whose means are checked against a static base [s] (`ImplausibleLogError`): the
default coarse alignment (`gyrodrift.procedure.Timeline.coarse_s`), which every procedure needs static; a
simulated moving-base log's static part (``[trajectory] static_h``) when that is shorter."""
MIN_STATIC_CHECK_SPAN_S = 60.0
"""A log (or a known static part) shorter than this [s] is not checked: too short to tell the Earth rate of a
noisy gyro (a 0.05 deg/sqrt(h) ARW averages to 0.4 deg/h over 60 s)."""
SPECIFIC_FORCE_TOLERANCE_G = 0.01
"""Largest accepted difference [g] between the mean specific force magnitude and normal gravity at the site:
10 mg is 100 times a navigation-grade accelerometer bias (<= 0.1 mg) and covers a tactical one, a site height
off by kilometres (0.3 mg/km) and any gravity anomaly (< 0.5 mg); a unit slip is off by a factor 9.8 (g
declared m/s^2), 1000 (mg, ug) or more."""
EARTH_RATE_TOLERANCE_DEG_H = 1.0
"""Additive tolerance [deg/h] of the gyro checks (a measured Earth-rate component is also accepted within a
factor 2 of its expected range): 1 deg/h is 100 times a navigation-grade RLG bias (<= 0.01 deg/h) and covers
the noise of a 60 s mean; a unit slip is off by a factor 57 (deg vs rad), 60, 1000 or 3600 (deg/s vs deg/h)."""
MAX_UNDECLARED_TILT_DEG = 30.0
"""Largest accepted angle [deg] between body up (the turntable axis) and the mean specific force, for a log that
does not declare its mounting attitude: a single-axis rotation INS stands with its table axis near the vertical;
an upside-down axis mapping gives 180 deg, a swapped up axis 90 deg."""
DECLARED_TILT_TOLERANCE_DEG = 5.0
"""Largest accepted difference [deg] between that angle and the one a log's declared attitude gives
(``gyrodrift.scenario`` metadata: acos(cos pitch cos roll))."""
TABLE_STILL_DEG = 10.0
"""The table counts as still over the checked span when its angle (the axial gyro integrated, minus the Earth
rate's vertical component) stays within this range [deg]; only then is the axial gyro's mean checked."""


class ImplausibleLogError(LogError):
    """A log whose first minutes are not what a static base must show (gravity, up, the Earth rate): a unit,
    scale, sign or axis slip; the message names the check, the measured and expected values and the columns (or
    the log format's keys) to look at."""


class StaticMeans:
    """Running sums over the start of a log for `gyrodrift.logs.log.ImuLog.check_static_base` (a few numbers).

    The table turns about body up, so body up keeps its direction on a static base: the mean up specific force is
    g cos(tilt) whatever the table does, and the horizontal gyros see the Earth rate's horizontal component
    turning against the table. Rotating each sample's x/y angle increment by the table angle phi (the axial gyro
    integrated, minus the Earth rate's vertical component w_ie sin L) brings them back to one frame fixed on the
    ground, where their mean is that component (the x/y biases average out as the table turns); a wrong axial
    gyro (unit, sign) smears it away.
    """

    def __init__(self, source: LogSource, site: Site | None):
        self.source = source
        self.site = site  # the log's true static site (the source's, or the one its caller gave)
        self.dt = 1.0 / source.rate.hz
        lat = None if site is None else site.lat_rad
        self.w_up = 0.0 if lat is None else OMEGA_IE_RAD_S * math.sin(lat)  # [rad/s]
        self.n = 0
        self.phi = 0.0  # table angle [rad]
        self.phi_low = self.phi_high = 0.0
        self.h = np.zeros(2)  # de-rotated horizontal angle increments [rad]
        self.z = 0.0  # axial angle [rad]
        self.f_up = 0.0  # up velocity increments [m/s]
        self.f_abs = 0.0  # sum of |dv| [m/s]

    def add(self, dth: np.ndarray, dv: np.ndarray) -> None:
        """Add checked angle [rad] and velocity [m/s] increments, (n, 3) each, body frame."""
        dphi = dth[:, 2] - self.w_up * self.dt
        phi = self.phi + np.cumsum(dphi)
        mid = phi - 0.5 * dphi  # the table angle in the middle of each sample
        c, s = np.cos(mid), np.sin(mid)
        self.h += (float(np.sum(c * dth[:, 0] - s * dth[:, 1])), float(np.sum(s * dth[:, 0] + c * dth[:, 1])))
        if len(phi):
            self.phi = float(phi[-1])
            self.phi_low = min(self.phi_low, float(phi.min()))
            self.phi_high = max(self.phi_high, float(phi.max()))
        self.z += float(np.sum(dth[:, 2]))
        self.f_up += float(np.sum(dv[:, 2]))
        self.f_abs += float(np.sum(np.sqrt(np.einsum("ij,ij->i", dv, dv))))
        self.n += len(dth)

    def verdict(self) -> None:
        """Raise `ImplausibleLogError` at the first check the sums fail (the order of docs/procedure.md)."""
        source = self.source
        truth = source.provenance.truth
        span = self.n * self.dt
        site = self.site
        g0 = G0
        f_abs = self.f_abs / span  # [m/s^2]
        f_up = self.f_up / span
        tol = SPECIFIC_FORCE_TOLERANCE_G * g0
        if site is not None:
            g_lo = g_hi = float(normal_gravity(site.lat_rad, site.height_m))
            where = f"normal gravity at {site.lat_deg:g} deg, {site.height_m:g} m"
        else:
            g_lo = float(normal_gravity(0.0, HEIGHT_LIMITS_M[1]))
            g_hi = float(normal_gravity(math.radians(float(_core.MAX_LAT_DEG)), HEIGHT_LIMITS_M[0]))
            where = "normal gravity anywhere (the log has no site)"
        head = f"{source.label}: not a static base over its first {span:g} s"
        if not g_lo - tol <= f_abs <= g_hi + tol:
            want = f"{g_lo:.4f}" if g_lo == g_hi else f"{g_lo:.4f} to {g_hi:.4f}"
            raise ImplausibleLogError(
                f"{head} (specific force magnitude): measured {f_abs:.6g} m/s^2 ({f_abs / g0:.6g} g), expected "
                f"{want} m/s^2 ({where}) +- {SPECIFIC_FORCE_TOLERANCE_G * 1e3:g} mg (any accelerometer bias); "
                f"a unit or scale slip: check {source.channels('accel', (0, 1, 2))}"
            )
        tilt = math.degrees(math.acos(max(-1.0, min(1.0, f_up / f_abs))))
        if truth is not None:
            p, r = math.radians(truth.pitch_deg), math.radians(truth.roll_deg)
            declared = math.degrees(math.acos(max(-1.0, min(1.0, math.cos(p) * math.cos(r)))))
            ok = abs(tilt - declared) <= DECLARED_TILT_TOLERANCE_DEG
            want = (
                f"{declared:.4g} deg +- {DECLARED_TILT_TOLERANCE_DEG:g} deg (the declared pitch "
                f"{truth.pitch_deg:g} deg, roll {truth.roll_deg:g} deg)"
            )
        else:
            ok = tilt <= MAX_UNDECLARED_TILT_DEG
            want = f"at most {MAX_UNDECLARED_TILT_DEG:g} deg (the table axis near the vertical)"
        if not ok:
            raise ImplausibleLogError(
                f"{head} (specific force points up): body up is {tilt:.4g} deg from the measured vertical (mean up "
                f"specific force {f_up:.6g} m/s^2 of {f_abs:.6g}), expected {want}; a sign or axis slip: check "
                f"{source.channels('accel', (2,), axes=True)}"
            )
        # The Earth rate's direction makes an angle alpha with body up: 90 deg - latitude, +- the tilt (and 1 deg
        # for the tilt's own error); the horizontal gyros see w_ie sin(alpha), the axial one w_ie cos(alpha).
        w = OMEGA_IE_RAD_S / DEG_PER_H
        t = min(180.0, tilt + 1.0)
        if site is not None:
            c = 90.0 - site.lat_deg
            a_lo, a_hi = abs(c - t), min(c + t, 360.0 - c - t)
            h_lo = w * min(math.sin(math.radians(a_lo)), math.sin(math.radians(a_hi)))
            h_hi = w if a_lo <= 90.0 <= a_hi else w * max(math.sin(math.radians(a_lo)), math.sin(math.radians(a_hi)))
            z_lo, z_hi = w * math.cos(math.radians(a_hi)), w * math.cos(math.radians(a_lo))
            at = f"at {site.lat_deg:g} deg, the site's latitude"
        else:
            h_lo, h_hi, z_lo, z_hi = 0.0, w, -w, w
            at = "(the log has no site: anywhere)"
        horizontal = float(np.hypot(*self.h)) / span / DEG_PER_H
        axial = self.z / span / DEG_PER_H
        still = math.degrees(self.phi_high - self.phi_low) <= TABLE_STILL_DEG
        table = (
            "the table standing still by the axial gyro"
            if still
            else f"de-rotated by the table angle of the axial gyro ({math.degrees(self.phi):.6g} deg at the end)"
        )
        if not _plausible(horizontal, h_lo, h_hi):
            raise ImplausibleLogError(
                f"{head} (horizontal Earth rate): the mean horizontal rate ({table}) is {horizontal:.6g} deg/h, "
                f"expected {_shown_range(h_lo, h_hi)} deg/h (w_ie cos(latitude) {at}, tilt {tilt:.3g} deg) "
                f"+- {EARTH_RATE_TOLERANCE_DEG_H:g} deg/h or within a factor 2; a unit, scale or sign slip: check "
                f"{source.channels('gyro', (0, 1, 2), up_note='the table angle')}"
            )
        if still:
            if site is None:  # the whole Earth rate is w_ie anywhere
                total = math.hypot(horizontal, axial)
                ok, shown, want = _plausible(total, w, w), f"the Earth rate magnitude {total:.6g}", f"{w:.6g}"
            else:
                ok, shown, want = (
                    _plausible(axial, z_lo, z_hi),
                    f"the mean axial rate {axial:.6g}",
                    _shown_range(z_lo, z_hi),
                )
            if not ok:
                raise ImplausibleLogError(
                    f"{head} (axial Earth rate): the table stands still and {shown} deg/h, expected {want} deg/h "
                    f"(w_ie sin(latitude) {at}, tilt {tilt:.3g} deg) +- {EARTH_RATE_TOLERANCE_DEG_H:g} deg/h or "
                    f"within a factor 2; a unit, scale or sign slip: check {source.channels('gyro', (2,))}"
                )


def _plausible(x: float, lo: float, hi: float) -> bool:
    """Whether a measured Earth-rate component `x` [deg/h] can be one expected in [lo, hi]: within
    `EARTH_RATE_TOLERANCE_DEG_H` of the range, or (a range of one sign) within a factor 2 of it."""
    tol = EARTH_RATE_TOLERANCE_DEG_H
    if lo - tol <= x <= hi + tol:
        return True
    if lo > 0.0:
        return 0.5 * lo <= x <= 2.0 * hi
    if hi < 0.0:
        return 2.0 * lo <= x <= 0.5 * hi
    return False


def _shown_range(lo: float, hi: float) -> str:
    return f"{lo:.4g}" if abs(hi - lo) < 5e-4 else f"{lo:.4g} to {hi:.4g}"
