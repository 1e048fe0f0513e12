//! Initial alignment on a static base with the turntable running: inertial-frame coarse alignment followed by
//! a zero-velocity Kalman fine alignment (closed loop). The boundary with Python is `docs/alignment-contract.md`.
//!
//! Timeline (t counted from the first sample of the log, sample k ends at k / rate_hz):
//! 1. [0, coarse_s]: `coarse_alignment::InertialCoarseAlignment` gives C_b^n at t = coarse_s;
//! 2. (coarse_s, coarse_s + fine_s]: a `strapdown::Navigator` (vertical channel held) starts from the coarse
//!    attitude with zero velocity at the known site and navigates every sample with the current bias estimates
//!    subtracted (measured - estimate). Every `update_s` the 12-state filter of `kalman` is propagated with the
//!    mean C_b^n of the interval and updated with the navigator's velocity (zero-velocity measurement); the
//!    estimate is fed back at once (attitude q <- q(phi) o q, velocity v <- v - dv, gyro and accelerometer bias
//!    estimates += eps, nabla) and the error state reset to zero.
//!
//! The feedback goes through `Navigator::correct`, which keeps the navigator's position, its coning/sculling
//! memory (the previous sample's increments) and its Earth terms. The position is not corrected: the filter
//! has no position states, and on a static base it moves only by the integral of the residual velocity
//! (below 0.4 m over 4 h in the tests, 6e-8 rad of latitude), which changes the Earth rate and gravity the
//! filter and the navigator use by less than 1e-7 relative.

use crate::attitude::{dcm_to_euler, quat_mul, quat_to_dcm, Euler, Mat3, Vec3};
use crate::coarse_alignment::InertialCoarseAlignment;
use crate::earth;
use crate::error::{check, in_range, CoreError, Unit};
use crate::filter_prior::FilterSettings;
use crate::kalman::{self, ErrorModel, ErrorStateFilter, StateMatrix, DV, EPS, NABLA, N_STATES, PHI};
use crate::limits::{check_increments, check_site};
use crate::strapdown::{Navigator, NavigatorConfig, Vertical};
use crate::units::ARCSEC;

/// Default total alignment span, coarse plus fine \[s\] (4 h).
pub const DEFAULT_TOTAL_S: f64 = 14_400.0;

/// Settings of an alignment (SI). Keys of the contract in brackets.
#[derive(Clone, Debug, PartialEq)]
pub struct AlignerConfig {
    /// Known static site: latitude \[rad\] (`lat_rad`), longitude \[rad\] (`lon_rad`), height \[m\] (`height_m`).
    pub lat: f64,
    pub lon: f64,
    pub height: f64,
    /// IMU sample rate \[Hz\] (`rate_hz`).
    pub rate_hz: f64,
    /// Fine alignment span after the coarse one \[s\] (`fine_s`, default 14400 - coarse_s).
    pub fine_s: f64,
    /// The coarse span, the update interval, the prior, the noise, the zero-velocity sigma and the history interval
    /// the smoother shares (default [`FilterSettings::aligner`]: 300 s, 1 s, 0.01 deg/h, 100 ug, 0.001 deg/sqrt(h),
    /// 10 ug/sqrt(Hz), 0.001 m/s, 60 s; `filter_prior` says why they differ from the smoother's).
    pub filter: FilterSettings,
}

impl AlignerConfig {
    /// The defaults of the contract at a site.
    pub fn new(lat: f64, lon: f64, height: f64, rate_hz: f64) -> Self {
        Self::with_filter(lat, lon, height, rate_hz, FilterSettings::aligner())
    }

    /// The given filter settings at a site, with the default fine span after their coarse span.
    pub fn with_filter(lat: f64, lon: f64, height: f64, rate_hz: f64, filter: FilterSettings) -> Self {
        AlignerConfig {
            lat,
            lon,
            height,
            rate_hz,
            fine_s: Self::default_fine_s(filter.coarse_s),
            filter,
        }
    }

    /// The default fine span \[s\] after a coarse span of `coarse_s` \[s\]: the rest of `DEFAULT_TOTAL_S`.
    pub fn default_fine_s(coarse_s: f64) -> f64 {
        (DEFAULT_TOTAL_S - coarse_s).max(0.0)
    }

    /// Range checks; errors name the contract key.
    pub fn validate(&self) -> Result<(), CoreError> {
        check_site(self.lat, self.lon, self.height, self.rate_hz)?;
        self.filter.validate(self.rate_hz)?;
        in_range("fine_s", "fine span", self.fine_s, 0.0, 604_800.0, Unit::Si("s"))
    }

    /// Samples of the coarse span, of the fine span, and per update.
    fn sample_counts(&self) -> (u64, u64, u64) {
        let n = |s: f64| (s * self.rate_hz).round() as u64;
        (n(self.filter.coarse_s), n(self.fine_s), n(self.filter.update_s))
    }
}

/// Default initial attitude 1-sigma after the coarse alignment, E, N, U \[rad\], from its closed-form error
/// budget without the help of the rotation (so conservative): levelling ~ horizontal accelerometer bias / g
/// plus VRW averaged over the span, heading ~ (horizontal gyro bias + ARW averaged over the span)
/// / (w_ie cos lat), each noise term tripled for the two-epoch (not least-squares) solution, with floors of
/// 10 arcsec (level) and 1 arcmin (heading). At latitude `lat` \[rad\] and height `height` \[m\].
pub fn coarse_attitude_sigma(lat: f64, height: f64, filter: &FilterSettings) -> Vec3 {
    let g = earth::normal_gravity(lat, height);
    let span = filter.coarse_s;
    let acc = filter.accel_bias_sigma[0].max(filter.accel_bias_sigma[1]);
    let gyro = filter.gyro_bias_sigma[0].max(filter.gyro_bias_sigma[1]);
    let level = (acc / g)
        .hypot(3.0 * filter.accel_vrw / (g * span.sqrt()))
        .max(10.0 * ARCSEC);
    let heading = (gyro.hypot(3.0 * filter.gyro_arw / span.sqrt()) / (earth::OMEGA_IE * lat.cos())).max(60.0 * ARCSEC);
    [level, level, heading]
}

/// A navigator at rest at the known site (latitude, longitude \[rad\], height \[m\], rate \[Hz\]; vertical channel
/// held) from the coarse attitude `c_bn` at `t_s` \[s\], and that attitude: where the aligner's and the smoother's
/// fine filters start. A `Diverged` error (key `dv_m_s`) when the coarse alignment found no attitude, or one outside
/// the navigator's range (a pitch of +-90 deg: the body y axis vertical; the site was validated with the filter).
pub(crate) fn navigator_at_rest(
    c_bn: &Mat3,
    lat: f64,
    lon: f64,
    height: f64,
    rate_hz: f64,
    t_s: f64,
) -> Result<(Euler, Navigator), CoreError> {
    let diverged = |message: String| CoreError::Diverged {
        key: "dv_m_s",
        t_s,
        message,
    };
    if !c_bn.iter().flatten().all(|x| x.is_finite()) {
        return Err(diverged(
            "the coarse alignment found no attitude: the specific force and the Earth rate give no two independent \
             directions (no gravity in the log?)"
                .to_string(),
        ));
    }
    let attitude = dcm_to_euler(c_bn);
    let nav = Navigator::new(NavigatorConfig {
        lat,
        lon,
        height,
        vel: [0.0; 3],
        attitude,
        rate_hz,
        vertical: Vertical::Fixed,
    })
    .map_err(|e| diverged(format!("the coarse attitude is outside the navigator's range: {e}")))?;
    Ok((attitude, nav))
}

/// Everything the alignment reports (SI; contract `result()`).
#[derive(Clone, Debug, PartialEq)]
pub struct AlignmentResult {
    /// End of the alignment \[s\] from the first sample.
    pub t_s: f64,
    /// Attitude at the end.
    pub attitude: Euler,
    /// Velocity at the end (E, N, U) [m/s] (the navigator's, after the last feedback).
    pub vel: Vec3,
    /// Bias estimates, body x y z [rad/s], [m/s^2]; measured - estimate is the corrected output.
    pub gyro_bias: Vec3,
    pub accel_bias: Vec3,
    /// Their 1-sigma at the end.
    pub gyro_bias_std: Vec3,
    pub accel_bias_std: Vec3,
    /// Attitude error 1-sigma E, N, U \[rad\] at the end.
    pub att_std: Vec3,
    /// Attitude given by the coarse alignment at t = coarse_s.
    pub coarse_attitude: Euler,
    /// Times of the covariance history \[s\] (the start of the fine alignment, then every `history_s`, and the end).
    pub hist_t: Vec<f64>,
    /// 1-sigma of every state (order `kalman::STATE_NAMES`) at those times.
    pub hist_std: Vec<[f64; N_STATES]>,
}

/// The fine-alignment loop state.
#[derive(Clone, Debug)]
struct FineAlignment {
    nav: Navigator,
    model: ErrorModel,
    filter: ErrorStateFilter,
    gyro_bias: Vec3,
    accel_bias: Vec3,
    /// Sum of C_b^n over the samples of the current update interval, and their count.
    c_sum: Mat3,
    n_interval: u64,
    /// Updates done, and updates between history records.
    updates: u64,
    updates_per_history: u64,
}

/// The aligner (see the module docs). Streaming: `process` may be called with chunks of any size.
#[derive(Clone, Debug)]
pub struct Aligner {
    cfg: AlignerConfig,
    n_coarse: u64,
    n_fine: u64,
    n_update: u64,
    /// Samples consumed.
    k: u64,
    coarse: InertialCoarseAlignment,
    coarse_attitude: Option<Euler>,
    fine: Option<FineAlignment>,
    hist_t: Vec<f64>,
    hist_std: Vec<[f64; N_STATES]>,
    /// The error that stopped the alignment (returned again by every later call).
    failed: Option<CoreError>,
}

impl Aligner {
    /// A validated aligner.
    pub fn new(cfg: AlignerConfig) -> Result<Self, CoreError> {
        cfg.validate()?;
        let (n_coarse, n_fine, n_update) = cfg.sample_counts();
        check(n_coarse >= 2, "coarse_s", "gives fewer than 2 samples at this rate")?;
        Ok(Aligner {
            coarse: InertialCoarseAlignment::new(cfg.lat, cfg.height, cfg.rate_hz, n_coarse)?,
            cfg,
            n_coarse,
            n_fine,
            n_update,
            k: 0,
            coarse_attitude: None,
            fine: None,
            hist_t: Vec::new(),
            hist_std: Vec::new(),
            failed: None,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &AlignerConfig {
        &self.cfg
    }

    /// Samples consumed so far.
    pub fn samples_done(&self) -> u64 {
        self.k
    }

    /// Samples of the whole alignment (coarse plus fine).
    pub fn n_samples(&self) -> u64 {
        self.n_coarse + self.n_fine
    }

    /// True when the whole alignment span has been consumed.
    pub fn done(&self) -> bool {
        self.k >= self.n_samples()
    }

    /// The covariance of the fine alignment's error state (None before the fine alignment starts).
    pub fn covariance(&self) -> Option<&StateMatrix> {
        self.fine.as_ref().map(|f| f.filter.covariance())
    }

    /// Consume samples given as flat row-major (n x 3) slices of raw increments (dtheta \[rad\], dv [m/s], body
    /// frame); stops at the end of the alignment span. Returns how many samples were used.
    ///
    /// The samples are checked first (`limits::check_increments`); a refused chunk changes nothing. An
    /// estimate that leaves its physical range ([`CoreError::Diverged`]: the log is not a static base at the
    /// configured site and rate) stops the alignment: this and every later call return that error.
    pub fn process(&mut self, dtheta: &[f64], dv: &[f64]) -> Result<usize, CoreError> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        check_increments(dtheta, dv, 1.0 / self.cfg.rate_hz)?;
        let n = (dtheta.len() / 3).min(usize::try_from(self.n_samples() - self.k).unwrap_or(usize::MAX));
        for (a, b) in dtheta.chunks_exact(3).zip(dv.chunks_exact(3)).take(n) {
            if let Err(e) = self.step([a[0], a[1], a[2]], [b[0], b[1], b[2]]) {
                self.failed = Some(e.clone());
                return Err(e);
            }
        }
        Ok(n)
    }

    /// One sample.
    fn step(&mut self, dtheta: Vec3, dv: Vec3) -> Result<(), CoreError> {
        self.k += 1;
        if self.k <= self.n_coarse {
            self.coarse.step(dtheta, dv);
            if self.k == self.n_coarse {
                self.start_fine()?;
            }
            return Ok(());
        }
        let last = self.k == self.n_samples();
        // Invariant: `start_fine` ran at sample n_coarse (it either set `fine` or failed, which stops `process`).
        let fine = self.fine.as_mut().expect("fine alignment starts after the coarse span");
        fine.nav.step(dtheta, dv);
        let c = quat_to_dcm(fine.nav.quaternion());
        for (sum_row, c_row) in fine.c_sum.iter_mut().zip(c) {
            for (sum, x) in sum_row.iter_mut().zip(c_row) {
                *sum += x;
            }
        }
        fine.n_interval += 1;
        if fine.n_interval == self.n_update || last {
            self.update()?;
        }
        Ok(())
    }

    /// End of the coarse span: start the navigator and the filter.
    fn start_fine(&mut self) -> Result<(), CoreError> {
        let t_s = self.k as f64 / self.cfg.rate_hz;
        // Invariant: called at sample n_coarse, when the coarse span is complete.
        let c_bn = self.coarse.attitude().expect("coarse span complete");
        let cfg = &self.cfg;
        let (attitude, nav) = navigator_at_rest(&c_bn, cfg.lat, cfg.lon, cfg.height, cfg.rate_hz, t_s)?;
        self.coarse_attitude = Some(attitude);
        let f = &cfg.filter;
        let att = f
            .att_sigma
            .unwrap_or_else(|| coarse_attitude_sigma(cfg.lat, cfg.height, f));
        let mut sigma = [0.0; N_STATES];
        sigma[PHI..PHI + 3].copy_from_slice(&att);
        sigma[DV..DV + 3].copy_from_slice(&[f.zupt_sigma; 3]);
        sigma[EPS..EPS + 3].copy_from_slice(&f.gyro_bias_sigma);
        sigma[NABLA..NABLA + 3].copy_from_slice(&f.accel_bias_sigma);
        let update_t = self.n_update as f64 / cfg.rate_hz;
        let fine = FineAlignment {
            nav,
            model: ErrorModel::new(cfg.lat, cfg.height),
            filter: ErrorStateFilter::new(&sigma),
            gyro_bias: [0.0; 3],
            accel_bias: [0.0; 3],
            c_sum: [[0.0; 3]; 3],
            n_interval: 0,
            updates: 0,
            updates_per_history: ((f.history_s / update_t).round() as u64).max(1),
        };
        self.record_history(&fine.filter);
        self.fine = Some(fine);
        Ok(())
    }

    /// Predict over the interval just ended, update with the zero velocity, feed back, reset.
    fn update(&mut self) -> Result<(), CoreError> {
        let at_end = self.k == self.n_samples();
        let t_s = self.k as f64 / self.cfg.rate_hz;
        let cfg = &self.cfg;
        // Invariant: `update` is called from the fine span only, after `start_fine` set `fine`.
        let fine = self.fine.as_mut().expect("fine alignment running");
        let n = fine.n_interval as f64;
        let t = n / cfg.rate_hz;
        let c_mean: Mat3 = std::array::from_fn(|i| std::array::from_fn(|j| fine.c_sum[i][j] / n));
        let phi = fine.model.transition(&c_mean, t);
        let q = kalman::process_noise(&phi, cfg.filter.gyro_arw, cfg.filter.accel_vrw, t);
        fine.filter.predict(&phi, &q);
        let state = fine.nav.state();
        fine.filter
            .update_zero_velocity(state.vel, cfg.filter.zupt_sigma)
            .map_err(|message| CoreError::Diverged {
                key: "dv_m_s",
                t_s,
                message,
            })?;
        fine.feed_back(t_s)?;
        fine.c_sum = [[0.0; 3]; 3];
        fine.n_interval = 0;
        fine.updates += 1;
        let record = fine.updates % fine.updates_per_history == 0 || at_end;
        if record {
            let filter = fine.filter.clone();
            self.record_history(&filter);
        }
        Ok(())
    }

    fn record_history(&mut self, filter: &ErrorStateFilter) {
        let t = self.k as f64 / self.cfg.rate_hz;
        if self.hist_t.last() != Some(&t) {
            self.hist_t.push(t);
            self.hist_std.push(filter.std());
        }
    }

    /// The result: [`CoreError::Incomplete`] until the alignment span is complete, or the error that stopped
    /// the alignment.
    pub fn result(&self) -> Result<AlignmentResult, CoreError> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        if !self.done() {
            return Err(CoreError::Incomplete {
                done: self.k,
                needed: self.n_samples(),
            });
        }
        // Invariants: done means sample n_coarse (>= 2, checked in `new`) was processed without error, so
        // `start_fine` set both the coarse attitude and the fine alignment.
        let coarse_attitude = self.coarse_attitude.expect("coarse span complete");
        let fine = self
            .fine
            .as_ref()
            .expect("the fine alignment starts with the last coarse sample");
        let t_s = self.k as f64 / self.cfg.rate_hz;
        let s = fine.filter.std();
        let state = fine.nav.state();
        Ok(AlignmentResult {
            t_s,
            attitude: state.attitude,
            vel: state.vel,
            gyro_bias: fine.gyro_bias,
            accel_bias: fine.accel_bias,
            gyro_bias_std: [s[EPS], s[EPS + 1], s[EPS + 2]],
            accel_bias_std: [s[NABLA], s[NABLA + 1], s[NABLA + 2]],
            att_std: [s[PHI], s[PHI + 1], s[PHI + 2]],
            coarse_attitude,
            hist_t: self.hist_t.clone(),
            hist_std: self.hist_std.clone(),
        })
    }
}

impl FineAlignment {
    /// Closed-loop feedback of the filter's estimate (module docs), then reset of the error state. An estimate
    /// beyond the navigator's ranges (attitude correction 0.5 rad, velocity 1000 m/s, gyro bias 0.1 rad/s,
    /// accelerometer bias 10 m/s^2) means the log does not fit a static base: [`CoreError::Diverged`] at `t_s`.
    fn feed_back(&mut self, t_s: f64) -> Result<(), CoreError> {
        let x = self.filter.take_correction();
        let phi = [x[PHI], x[PHI + 1], x[PHI + 2]];
        let dv = [x[DV], x[DV + 1], x[DV + 2]];
        for i in 0..3 {
            self.gyro_bias[i] += x[EPS + i];
            self.accel_bias[i] += x[NABLA + i];
        }
        let diverged = |what: &str, e: CoreError| CoreError::Diverged {
            key: e.key(),
            t_s,
            message: format!(
                "the fine alignment's {what} left its range ({e}): the log does not look like a static base at \
                 the given site and sample rate"
            ),
        };
        // C_b^n(true) = (I + [phi x]) C_b^n(computed): q <- q(phi) o q; v <- v - dv.
        self.nav
            .correct(phi, dv)
            .map_err(|e| diverged("attitude or velocity correction", e))?;
        self.nav
            .set_gyro_bias(self.gyro_bias)
            .map_err(|e| diverged("gyro bias estimate", e))?;
        self.nav
            .set_accel_bias(self.accel_bias)
            .map_err(|e| diverged("accelerometer bias estimate", e))
    }
}

/// Attitude error of `estimate` against `truth` as the correction phi of the filter (E, N, U) \[rad\]:
/// C_b^n(truth) = (I + [phi x]) C_b^n(estimate) to first order, computed exactly as a rotation vector.
pub fn attitude_error(estimate: Euler, truth: Euler) -> Vec3 {
    use crate::attitude::{euler_to_quat, quat_conj, quat_to_rotvec};
    quat_to_rotvec(quat_mul(euler_to_quat(truth), quat_conj(euler_to_quat(estimate))))
}
