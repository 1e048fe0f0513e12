//! The smoother on a gyro with a Gauss-Markov bias instability (the README tour's kind of INS): the drift it carries
//! into navigation leaves the Gauss-Markov state out, and its 1-sigma covers the error against the simulated
//! constant + thermal drift when the filter is told of the instability, not when it is not; the smoothed total at
//! the end of the span covers the simulated total, the Gauss-Markov state included (read from a replica of the
//! simulator's error model: same parameters, rate and seed, so the same draws).

use gyrodrift_core::attitude::Euler;
use gyrodrift_core::imu_error::{ImuErrorModel, ImuErrorParams};
use gyrodrift_core::simulator::{ImuChunk, ImuSimulator, ImuSimulatorConfig};
use gyrodrift_core::smoother::{Smoother, SmootherConfig, SmootherResult};
use gyrodrift_core::temperature::{DailySwing, TemperatureProfile};
use gyrodrift_core::turntable::RotationScheme;
use gyrodrift_core::units::{DEG, DEG_PER_H, HOUR, MICRO_G, SQRT_HOUR};

const RATE_HZ: f64 = 5.0;
const SPAN_S: f64 = 10.0 * HOUR;
const ARW: f64 = 0.0005 * DEG / SQRT_HOUR;
const VRW: f64 = 5.0 * MICRO_G;
/// The tour's bias instability: 0.001 deg/h, 1 h correlation time.
const GM_SIGMA: f64 = 0.001 * DEG_PER_H;
const GM_TAU_S: f64 = 3600.0;
const DRIFT: f64 = 0.003 * DEG_PER_H;
const K1: f64 = 0.0002 * DEG_PER_H;
const T0_C: f64 = 25.0;
const TAU_WARM_S: f64 = 2.0 * HOUR;

/// A warm-up from 20 to 35 degC with the axial drift DRIFT + K1 (T - T0_C) and the tour's noise.
fn sim(seed: u64) -> ImuSimulatorConfig {
    ImuSimulatorConfig {
        lat: 28.222 * DEG,
        rate_hz: RATE_HZ,
        duration_s: SPAN_S,
        seed,
        attitude: Euler {
            pitch: 0.0,
            roll: 0.0,
            yaw: 30.0 * DEG,
        },
        scheme: RotationScheme::Reciprocating {
            rate: 6.0 * DEG,
            accel: 10.0 * DEG,
            span: 360.0 * DEG,
            dwell: 0.0,
        },
        errors: ImuErrorParams {
            gyro_bias: [0.002 * DEG_PER_H, -0.002 * DEG_PER_H, DRIFT],
            accel_bias: [20.0 * MICRO_G, -20.0 * MICRO_G, 15.0 * MICRO_G],
            gyro_arw: ARW,
            accel_vrw: VRW,
            gyro_bias_instability: GM_SIGMA,
            gyro_correlation: GM_TAU_S,
            drift_t0_c: T0_C,
            drift_k1: K1,
            ..Default::default()
        },
        temperature: TemperatureProfile::WarmUp {
            start_c: 20.0,
            end_c: 35.0,
            tau_s: TAU_WARM_S,
            swing: DailySwing::NONE,
        },
        ..Default::default()
    }
}

/// The simulated constant + thermal z drift at the end of the span [rad/s] (the temperature at the middle of the
/// last sample, as the simulator evaluates it).
fn law_at_end() -> f64 {
    let t = SPAN_S - 0.5 / RATE_HZ;
    let temp = 35.0 + (20.0 - 35.0) * (-t / TAU_WARM_S).exp();
    DRIFT + K1 * (temp - T0_C)
}

/// The simulator's z Gauss-Markov bias held over sample `k` (0-based) [rad/s]: its error model replayed on the
/// zero increments of the samples before it.
fn gm_held(cfg: &ImuSimulatorConfig, k: usize) -> f64 {
    let mut model = ImuErrorModel::new(cfg.errors.clone(), 1.0 / cfg.rate_hz, cfg.seed).unwrap();
    let (mut dth, mut dv) = (vec![0.0; 3 * k], vec![0.0; 3 * k]);
    model.add_noise(&mut dth, &mut dv);
    model.gauss_markov_state()[2]
}

/// Smooth the simulated log with the thermal state, told of the bias instability or not.
fn smooth(sim_cfg: &ImuSimulatorConfig, told: bool) -> SmootherResult {
    let mut cfg = SmootherConfig::new(sim_cfg.lat, sim_cfg.lon, sim_cfg.height, sim_cfg.rate_hz);
    cfg.span_s = SPAN_S;
    cfg.thermal = true;
    cfg.gyro_arw = ARW;
    cfg.accel_vrw = VRW;
    if told {
        cfg.gyro_bias_instability = GM_SIGMA;
        cfg.gyro_correlation = GM_TAU_S;
    }
    let mut s = ImuSimulator::new(sim_cfg.clone()).unwrap();
    let mut sm = Smoother::new(cfg).unwrap();
    let mut ch = ImuChunk::default();
    while !sm.done() && s.next_chunk(50_000, &mut ch) > 0 {
        sm.process(&ch.dtheta, &ch.dv, Some(&ch.temp_c)).unwrap();
    }
    sm.result().unwrap()
}

fn rms(z: &[f64]) -> f64 {
    (z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64).sqrt()
}

#[test]
fn the_replayed_error_model_gives_the_simulators_gauss_markov_state() {
    // A twin with the same seed and white noise of 1e-20 of the tour's draws the same normals in the same order
    // (a term draws whenever it is on), so its z increments minus the noise-free twin's are the held Gauss-Markov
    // bias alone: the replica's state must be it, to rounding.
    let cfg = sim(3);
    let n = (SPAN_S * RATE_HZ).round() as usize;
    let read = |c: ImuSimulatorConfig| {
        let mut s = ImuSimulator::new(c).unwrap();
        let mut ch = ImuChunk::default();
        assert_eq!(s.next_chunk(n, &mut ch), n);
        ch.dtheta
    };
    let mut twin = cfg.clone();
    (twin.errors.gyro_arw, twin.errors.accel_vrw) = (1e-20 * ARW, 1e-20 * VRW);
    let mut quiet = cfg.clone();
    (
        quiet.errors.gyro_arw,
        quiet.errors.accel_vrw,
        quiet.errors.gyro_bias_instability,
    ) = (0.0, 0.0, 0.0);
    let (twin, free) = (read(twin), read(quiet));
    for k in [n / 3, n - 1] {
        let held = (twin[3 * k + 2] - free[3 * k + 2]) * RATE_HZ;
        let gm = gm_held(&cfg, k);
        assert!(gm.abs() > 1e-3 * GM_SIGMA, "{gm}");
        assert!((held - gm).abs() < 1e-6 * GM_SIGMA, "sample {k}: {held} vs {gm}");
    }
}

#[test]
fn the_carried_drift_is_calibrated_when_the_filter_is_told_of_the_bias_instability() {
    let n = 12;
    let (mut z_told, mut z_not, mut z_total) = (Vec::new(), Vec::new(), Vec::new());
    let law = law_at_end();
    for seed in 0..n {
        let cfg = sim(300 + seed);
        let told = smooth(&cfg, true);
        let not = smooth(&cfg, false);
        assert!(told.thermal && not.thermal);
        z_told.push((told.drift_end - law) / told.drift_end_std);
        z_not.push((not.drift_end - law) / not.drift_end_std);
        // The history's last point is the total, the Gauss-Markov state included.
        let (total, total_std) = (told.hist_drift.last().unwrap(), told.hist_drift_std.last().unwrap());
        z_total.push((total - law - gm_held(&cfg, (SPAN_S * RATE_HZ).round() as usize - 1)) / total_std);
        // The carried sigma lies between the told total's and the untold one's.
        assert!(not.drift_end_std < told.drift_end_std && told.drift_end_std < *total_std);
    }
    let (told, not, total) = (rms(&z_told), rms(&z_not), rms(&z_total));
    println!("z rms over {n} seeds: carried, told {told:.2}; carried, not told {not:.2}; total, told {total:.2}");
    // 12 seeds: the rms of 12 unit normals lies in [0.6, 1.4] with about 98 % probability.
    assert!((0.5..1.5).contains(&told), "{told}");
    assert!((0.5..1.5).contains(&total), "{total}");
    assert!(not > 1.4, "{not}");
}
