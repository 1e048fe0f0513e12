"""A fleet's prior on the thermal coefficient k_z, and a run's end drift re-weighted by it.

One run's 16 h determine its z-gyro thermal coefficient k_z [deg/h/degC] only loosely (the drift's change during
the warm-up is seen through hours of heading-error growth), so the smoother's end-of-span drift carries most of
that uncertainty. Units of one type share their coefficient more or less: pooling the training runs' k_z gives a
prior for one more unit that is far tighter than the filter's own wide N(0, s0^2).

Pure functions on plain numbers or numpy arrays (the procedure's `SmootherEstimate`, the drift model's
``drift_smoother_fleet_deg_h`` physics base and the exported code all use them):

* `pooled_coefficient_prior`: random-effects pooled mean of the runs' k_z (weights 1/sigma_i^2,
  DerSimonian-Laird between-unit variance) and the 1-sigma of a new unit's k_z about it;
* `drift_with_coefficient_prior`: the end drift and its 1-sigma with another prior on k_z, exact for the
  linear-Gaussian model (the joint posterior of (end drift, k_z) re-weighted by the ratio of the two priors);
* `posterior_with_coefficient_prior`: the same re-weighted joint posterior whole, the end drift and k_z with
  their 2 x 2 covariance (what `gyrodrift.procedure.identify`'s drift law carries).

Units: drifts [deg/h], coefficients [deg/h/degC], ``cov`` = cov(end drift, k_z) [deg/h x deg/h/degC].
"""

from __future__ import annotations

import math

import numpy as np

from gyrodrift.errors import InputError

__all__ = [
    "pooled_coefficient_prior",
    "leave_one_out_coefficient_priors",
    "drift_with_coefficient_prior",
    "posterior_with_coefficient_prior",
]


def pooled_coefficient_prior(coeff, coeff_std) -> tuple[float, float]:
    """A prior N(mean, std^2) for one more unit's k_z from the runs' estimates ``coeff`` +- ``coeff_std``.

    The weighted mean with w_i = 1 / sigma_i^2, the between-unit variance
    ``tau^2 = max(0, (Q - (n - 1)) / (sum w - sum w^2 / sum w))`` (Q the weighted squared deviations,
    DerSimonian & Laird 1986), and ``std = sqrt(1 / sum w + tau^2)`` (the pooled mean's own uncertainty plus the
    unit-to-unit spread). Entries with a non-finite value or a non-positive or non-finite sigma are skipped (runs
    without the thermal model); `InputError` with fewer than two usable runs.
    """
    k = np.asarray(coeff, float).ravel()
    s = np.asarray(coeff_std, float).ravel()
    if k.shape != s.shape:
        raise InputError(f"k_z estimates and 1-sigmas differ in length ({k.size} vs {s.size})")
    use = np.isfinite(k) & np.isfinite(s) & (s > 0.0)
    if int(use.sum()) < 2:
        raise InputError(f"a fleet prior of k_z needs at least 2 runs with the thermal model, got {int(use.sum())}")
    k, w = k[use], 1.0 / s[use] ** 2
    mean = float(np.sum(w * k) / np.sum(w))
    q = float(np.sum(w * (k - mean) ** 2))
    tau2 = max(0.0, (q - (k.size - 1)) / float(np.sum(w) - np.sum(w**2) / np.sum(w)))
    return mean, math.sqrt(1.0 / float(np.sum(w)) + tau2)


LOO_CHUNK_ELEMENTS = 1 << 21
"""Largest (rows x runs) block `leave_one_out_coefficient_priors` holds at once (16 MiB per float array)."""


def leave_one_out_coefficient_priors(coeff, coeff_std, rows) -> np.ndarray:
    """``(len(rows), 2)``: for each index ``i`` in ``rows``, `pooled_coefficient_prior` of every entry but ``i``.

    The same floats as calling `pooled_coefficient_prior` on the arrays with entry ``i`` deleted, in O(n) numpy
    calls per block of rows instead of O(n) Python calls per row: each row of an (rows, n - 1) block is a
    contiguous copy of the usable entries but ``i``, summed along the row as `pooled_coefficient_prior` sums its
    1-D array (numpy's pairwise sum of a contiguous row), and the scalar steps are the same IEEE operations
    elementwise. A row with fewer than two usable entries left raises as `pooled_coefficient_prior` does.
    """
    k_all = np.asarray(coeff, float).ravel()
    s_all = np.asarray(coeff_std, float).ravel()
    rows = np.asarray(rows, int).ravel()
    if k_all.shape != s_all.shape:
        raise InputError(f"k_z estimates and 1-sigmas differ in length ({k_all.size} vs {s_all.size})")
    use = np.isfinite(k_all) & np.isfinite(s_all) & (s_all > 0.0)
    m = int(use.sum())
    out = np.empty((rows.size, 2))
    if m - 1 < 2:  # too few usable entries once one is left out: the plain function says why
        for r, i in enumerate(rows):
            others = np.arange(k_all.size) != i
            out[r] = pooled_coefficient_prior(k_all[others], s_all[others])
        return out
    k, w = k_all[use], 1.0 / s_all[use] ** 2
    position = np.cumsum(use) - 1  # index of each usable entry among the usable ones
    unused = ~use[rows]
    if unused.any():  # leaving out an unusable entry changes nothing
        out[unused] = pooled_coefficient_prior(k, s_all[use])
    left = np.flatnonzero(~unused)
    step = max(1, LOO_CHUNK_ELEMENTS // (m - 1))
    cols = np.arange(m - 1)[None, :]
    for start in range(0, left.size, step):
        block = left[start : start + step]
        skip = position[rows[block]][:, None]
        idx = cols + (cols >= skip)
        kb, wb = k[idx], w[idx]
        sw = np.sum(wb, axis=1)
        mean = np.sum(wb * kb, axis=1) / sw
        q = np.sum(wb * (kb - mean[:, None]) ** 2, axis=1)
        denominator = sw - np.sum(wb**2, axis=1) / sw
        with np.errstate(divide="ignore", invalid="ignore"):
            tau2 = (q - (m - 2)) / denominator
        tau2 = np.where(tau2 > 0.0, tau2, 0.0)  # max(0.0, x) of the scalar code (x NaN: 0.0)
        if not np.all(denominator != 0.0):  # the scalar code's ZeroDivisionError, where it would raise
            for r in block[denominator == 0.0]:
                others = np.arange(k_all.size) != rows[r]
                pooled_coefficient_prior(k_all[others], s_all[others])
        out[block, 0] = mean
        out[block, 1] = np.sqrt(1.0 / sw + tau2)
    return out


def posterior_with_coefficient_prior(drift, drift_std, coeff, coeff_std, cov, prior_std, mean, std):
    """The joint posterior of (end drift, k_z) with the prior N(mean, std^2) on k_z in place of N(0, prior_std^2).

    Arguments as `drift_with_coefficient_prior`. The smoother's posterior N((d, k), [[V_d, c], [c, V_k]]) times
    N(k; mean, std^2) / N(k; 0, s0^2): the marginal of k_z gets the precision ``L = 1/V_k - 1/s0^2 + 1/std^2`` and
    the mean ``k* = (k/V_k + mean/std^2) / L``, the drift given k_z is unchanged (slope ``lever = c / V_k``), so
    ``d* = d + lever (k* - k)``, ``var(d*) = V_d - lever c + lever^2 / L``, ``cov(d*, k*) = lever / L`` and
    ``var(k*) = 1 / L``. Returns ``(thermal, d*, k*, var_d, cov_dk, var_k)``: ``thermal`` (bool, elementwise) is
    false where the run has no thermal estimate (``coeff`` or ``cov`` not finite), and there ``d*`` is ``drift``,
    ``var_d`` its square and k*, cov_dk and var_k are NaN. The operations of ``d*`` and ``k*`` are exactly these, in
    this order (the exported code repeats them bit for bit). Numpy arrays (0-d for scalar arguments); ``mean``
    and ``std`` may be arrays too (one prior per run, elementwise: the floats of one call per run).
    """
    means, stds = np.broadcast_arrays(np.asarray(mean, float), np.asarray(std, float))
    bad = np.flatnonzero(~(np.isfinite(means) & np.isfinite(stds) & (stds > 0.0)).ravel())
    if bad.size:
        mean, std = float(means.flat[bad[0]]), float(stds.flat[bad[0]])
        raise InputError(f"a k_z prior needs a finite mean and a positive finite 1-sigma, got {mean!r}, {std!r}")
    d = np.asarray(drift, float)
    vd = np.asarray(drift_std, float) ** 2
    k = np.asarray(coeff, float)
    vk = np.asarray(coeff_std, float) ** 2
    c = np.asarray(cov, float)
    s0 = np.asarray(prior_std, float)
    thermal = np.isfinite(k) & np.isfinite(vk) & (vk > 0.0) & np.isfinite(c) & np.isfinite(s0) & (s0 > 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        lever = c / vk
        precision = 1.0 / vk - 1.0 / (s0 * s0) + 1.0 / (std * std)
        k_new = (k / vk + mean / (std * std)) / precision
        d_new = d + lever * (k_new - k)
        var = vd - lever * c + lever * lever / precision
        cov_dk = lever / precision
        var_k = 1.0 / precision
    nan = np.nan
    return (
        thermal,
        np.where(thermal, d_new, d),
        np.where(thermal, k_new, nan),
        np.where(thermal, var, vd),
        np.where(thermal, cov_dk, nan),
        np.where(thermal, var_k, nan),
    )


def drift_with_coefficient_prior(drift, drift_std, coeff, coeff_std, cov, prior_std, mean, std):
    """The end drift and its 1-sigma [deg/h] with the prior N(mean, std^2) on k_z in place of N(0, prior_std^2).

    ``drift``, ``drift_std``: the smoother's end-of-span drift and 1-sigma; ``coeff``, ``coeff_std``: its k_z and
    1-sigma; ``cov``: cov(end drift, k_z); ``prior_std``: the filter's own k_z prior 1-sigma s0. With
    V_k = coeff_std^2 and lever = cov / V_k, the new k_z precision is ``L = 1/V_k - 1/s0^2 + 1/std^2``, mean
    ``k* = (k/V_k + mean/std^2) / L``; then ``d* = d + lever (k* - k)``, ``var = V_d - lever cov + lever^2 / L``
    (`posterior_with_coefficient_prior`, of which this is the drift's marginal). Elementwise over arrays (numpy
    broadcasting). Where the run has no thermal estimate (``coeff`` or ``cov`` not finite: the constant model),
    ``drift`` and ``drift_std`` are returned unchanged. The operations are exactly these, in this order (the
    exported code repeats them bit for bit).
    """
    _, d_out, _, var, _, _ = posterior_with_coefficient_prior(
        drift, drift_std, coeff, coeff_std, cov, prior_std, mean, std
    )
    std_out = np.sqrt(np.maximum(var, 0.0))
    if d_out.ndim == 0:
        return float(d_out), float(std_out)
    return d_out, std_out
