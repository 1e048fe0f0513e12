//! Throughput of the simulator and the navigator, 72 h at 100 Hz, streamed in chunks (constant memory).
//! Run: `cargo run --release -p gyrodrift-core --example throughput [scheme] [level|tilted] [noisy]`.

use gyrodrift_core::attitude::Euler;
use gyrodrift_core::simulator::{ImuChunk, ImuSimulator, ImuSimulatorConfig};
use gyrodrift_core::strapdown::{Navigator, NavigatorConfig, Vertical};
use gyrodrift_core::turntable::RotationScheme;
use gyrodrift_core::units::{DEG, DEG_PER_H, HOUR, SQRT_HOUR};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scheme = match args.get(1).map(String::as_str).unwrap_or("reciprocating") {
        "none" => RotationScheme::None,
        "continuous" => RotationScheme::Continuous {
            rate: 6.0 * DEG,
            accel: 10.0 * DEG,
        },
        "indexing" => RotationScheme::Indexing {
            rate: 6.0 * DEG,
            accel: 10.0 * DEG,
            positions: vec![0.0, 90.0 * DEG, 180.0 * DEG, 270.0 * DEG],
            dwell: 300.0,
        },
        _ => RotationScheme::Reciprocating {
            rate: 6.0 * DEG,
            accel: 10.0 * DEG,
            span: 360.0 * DEG,
            dwell: 0.0,
        },
    };
    let tilted = args.get(2).map(String::as_str) == Some("tilted");
    let attitude = if tilted {
        Euler {
            pitch: 0.01,
            roll: -0.02,
            yaw: 0.5,
        }
    } else {
        Euler {
            pitch: 0.0,
            roll: 0.0,
            yaw: 0.5,
        }
    };
    let mut cfg = ImuSimulatorConfig {
        rate_hz: 100.0,
        duration_s: 72.0 * HOUR,
        attitude,
        scheme,
        ..Default::default()
    };
    if args.get(3).map(String::as_str) == Some("noisy") {
        // The facade benchmark's sensor: every noise channel, a warm-up and a temperature drift.
        let dh = DEG_PER_H;
        cfg.errors.gyro_bias = [0.002 * dh, -0.002 * dh, 0.003 * dh];
        cfg.errors.gyro_arw = 0.0005 * DEG / SQRT_HOUR;
        cfg.errors.gyro_bias_instability = 0.001 * dh;
        cfg.errors.accel_bias = [20e-5, -20e-5, 15e-5];
        cfg.errors.accel_vrw = 5e-5;
        cfg.errors.drift_k1 = 1e-4 * dh;
        cfg.temperature = gyrodrift_core::temperature::TemperatureProfile::WarmUp {
            start_c: 20.0,
            end_c: 35.0,
            tau_s: 7200.0,
            swing: gyrodrift_core::temperature::DailySwing::NONE,
        };
    }
    let nav_cfg = NavigatorConfig {
        lat: cfg.lat,
        lon: cfg.lon,
        height: cfg.height,
        vel: [0.0; 3],
        attitude,
        rate_hz: 100.0,
        vertical: Vertical::Fixed,
    };
    let mut sim = ImuSimulator::new(cfg).unwrap();
    let mut nav = Navigator::new(nav_cfg).unwrap();
    let mut ch = ImuChunk::default();
    let (mut t_sim, mut t_nav) = (0.0, 0.0);
    let mut n_out = 0usize;
    loop {
        let a = Instant::now();
        if sim.next_chunk(1 << 16, &mut ch) == 0 {
            break;
        }
        let b = Instant::now();
        nav.process(&ch.dtheta, &ch.dv, 6000, |_| n_out += 1).unwrap();
        t_sim += (b - a).as_secs_f64();
        t_nav += b.elapsed().as_secs_f64();
    }
    let n = sim.n_samples() as f64;
    println!(
        "samples {n:.0}: simulator {t_sim:.2} s ({:.1} M/s), navigator {t_nav:.2} s ({:.1} M/s), outputs {n_out}",
        n / t_sim / 1e6,
        n / t_nav / 1e6
    );
}
