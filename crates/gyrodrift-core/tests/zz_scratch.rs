use gyrodrift_core::alignment::{attitude_error, Aligner, AlignerConfig, MICRO_G, DEG_PER_HOUR};
use gyrodrift_core::attitude::Euler;
use gyrodrift_core::imu_error::ImuErrorParams;
use gyrodrift_core::simulator::{ImuChunk, ImuSimulator, ImuSimulatorConfig};
use gyrodrift_core::turntable::RotationScheme;
use std::f64::consts::PI;
const DEG: f64 = PI / 180.0;
#[test]
fn scratch() {
    for zs in [1e-3, 1e-4, 1e-5] {
      for seed in [1u64, 2] {
        let errors = ImuErrorParams { gyro_bias: [0.01 * DEG_PER_HOUR, -0.008 * DEG_PER_HOUR, 0.003 * DEG_PER_HOUR], accel_bias: [50.0 * MICRO_G, -40.0 * MICRO_G, 30.0 * MICRO_G], gyro_arw: 0.001*DEG/60.0, accel_vrw: 10.0*MICRO_G, ..Default::default() };
        let sc = ImuSimulatorConfig { lat: 28.222*DEG, rate_hz: 20.0, duration_s: 14400.0, seed, attitude: Euler{pitch:0.3*DEG, roll:-0.2*DEG, yaw:40.0*DEG}, scheme: RotationScheme::Reciprocating{rate:6.0*DEG, accel:10.0*DEG, span:2.0*PI, dwell:0.0}, errors, ..Default::default() };
        let cfg = AlignerConfig { zupt_sigma: zs, ..AlignerConfig::new(28.222*DEG, 0.0, 0.0, 20.0) };
        let mut sim = ImuSimulator::new(sc).unwrap(); let mut al = Aligner::new(cfg).unwrap(); let mut ch = ImuChunk::default();
        let mut te = None;
        while !al.done() && sim.next_chunk(10000, &mut ch) > 0 { let u = al.process(&ch.dtheta, &ch.dv); if al.done() { te = Some(Euler{pitch: ch.pitch[u-1], roll: ch.roll[u-1], yaw: ch.yaw[u-1]}); } }
        let r = al.result().unwrap();
        let gb = [0.01, -0.008, 0.003]; let ab=[50.0,-40.0,30.0];
        let phi = attitude_error(r.attitude, te.unwrap());
        println!("zupt {zs} seed {seed}: gerr {:.5?} gstd {:.5?} | aerr {:.2?} astd {:.2?} | phi {:.2?} std {:.2?}",
          (0..3).map(|i| r.gyro_bias[i]/DEG_PER_HOUR-gb[i]).collect::<Vec<_>>(), r.gyro_bias_std.map(|x| x/DEG_PER_HOUR),
          (0..2).map(|i| r.accel_bias[i]/MICRO_G-ab[i]).collect::<Vec<_>>(), r.accel_bias_std.map(|x| x/MICRO_G),
          phi.map(|x| x/DEG*3600.0), r.att_std.map(|x| x/DEG*3600.0));
      }
    }
}
