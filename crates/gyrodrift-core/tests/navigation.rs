//! Static-base navigation with the simulator and the navigator against closed forms (method.md).

use gyrodrift_core::attitude::Euler;
use gyrodrift_core::earth::{self, NMI};
use gyrodrift_core::simulator::{ImuChunk, ImuSimulator, ImuSimulatorConfig};
use gyrodrift_core::strapdown::{NavState, Navigator, NavigatorConfig, Vertical};
use gyrodrift_core::turntable::RotationScheme;
use std::f64::consts::PI;

const DEG: f64 = PI / 180.0;
const DEG_H: f64 = PI / 180.0 / 3600.0;
const UG: f64 = 9.806_65e-6;
const HOUR: f64 = 3600.0;

fn lat0() -> f64 {
    28.222 * DEG
}

fn continuous() -> RotationScheme {
    RotationScheme::Continuous { rate: 6.0 * DEG, accel: 1.0 * DEG }
}
fn reciprocating() -> RotationScheme {
    RotationScheme::Reciprocating { rate: 6.0 * DEG, accel: 1.0 * DEG, span: 2.0 * PI, dwell: 0.0 }
}
fn indexing() -> RotationScheme {
    RotationScheme::Indexing { rate: 6.0 * DEG, accel: 1.0 * DEG, positions: vec![0.0, 90.0 * DEG, 180.0 * DEG, 270.0 * DEG], dwell: 300.0 }
}

/// Simulate and navigate; returns the navigation states every `every_s` seconds.
fn run(cfg: ImuSimulatorConfig, every_s: f64) -> Vec<NavState> {
    let nav_cfg = NavigatorConfig {
        lat: cfg.lat,
        lon: cfg.lon,
        height: cfg.height,
        vel: [0.0; 3],
        attitude: cfg.attitude,
        rate_hz: cfg.rate_hz,
        vertical: Vertical::Fixed,
    };
    let dec = (every_s * cfg.rate_hz).round() as u64;
    let mut sim = ImuSimulator::new(cfg).unwrap();
    let mut nav = Navigator::new(nav_cfg).unwrap();
    let mut ch = ImuChunk::default();
    let mut out = Vec::new();
    while sim.next_chunk(65_536, &mut ch) > 0 {
        nav.process(&ch.dtheta, &ch.dv, dec, |s| out.push(*s));
    }
    out
}

/// Horizontal position error [m] of a state against the true static site (computed minus true).
fn pos_err_m(s: &NavState, lat: f64, lon: f64) -> f64 {
    let dn = (s.lat - lat) * earth::meridian_radius(lat);
    let de = (s.lon - lon) * earth::transverse_radius(lat) * lat.cos();
    (dn * dn + de * de).sqrt()
}

fn base(scheme: RotationScheme, rate_hz: f64, hours: f64) -> ImuSimulatorConfig {
    ImuSimulatorConfig {
        lat: lat0(),
        lon: 111.0 * DEG,
        height: 50.0,
        rate_hz,
        duration_s: hours * HOUR,
        seed: 1,
        attitude: Euler { pitch: 0.0, roll: 0.0, yaw: 30.0 * DEG },
        scheme,
        ..Default::default()
    }
}

#[test]
fn error_free_imu_navigates_72_h_within_0_01_nmi_with_every_scheme() {
    for (name, scheme) in [("none", RotationScheme::None), ("continuous", continuous()), ("reciprocating", reciprocating()), ("indexing", indexing())] {
        let mut cfg = base(scheme, 100.0, 72.0);
        // A tilted base exercises the full truth model.
        cfg.attitude = Euler { pitch: 0.5 * DEG, roll: -0.3 * DEG, yaw: 30.0 * DEG };
        let (lat, lon) = (cfg.lat, cfg.lon);
        let out = run(cfg, 600.0);
        let worst = out.iter().map(|s| pos_err_m(s, lat, lon)).fold(0.0, f64::max);
        eprintln!("error-free {name}: max position error over 72 h = {:.3e} nmi ({:.3} m)", worst / NMI, worst);
        assert!(worst < 0.01 * NMI, "{name}: {worst} m");
    }
}
