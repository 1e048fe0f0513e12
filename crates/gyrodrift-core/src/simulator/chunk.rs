//! The output of the simulator: owned, reusable chunk buffers ([`ImuChunk`]) or caller-provided slices
//! ([`ImuChunkSlices`]).

/// Most samples of one chunk handed to a caller (2^24: 1.5 GiB of output arrays).
pub const MAX_CHUNK_SAMPLES: u64 = 1 << 24;

/// A chunk of simulated samples (flat buffers, reused between calls).
#[derive(Clone, Debug, Default)]
pub struct ImuChunk {
    /// End time of each sample \[s\].
    pub t_s: Vec<f64>,
    /// Angle increments \[rad\], body x y z, flattened row-major (n x 3).
    pub dtheta: Vec<f64>,
    /// Velocity increments [m/s], body x y z, flattened row-major (n x 3).
    pub dv: Vec<f64>,
    /// Temperature at the end of each sample [deg C].
    pub temp_c: Vec<f64>,
    /// Table angle at the end of each sample \[rad\] (unwrapped, CCW about body Up).
    pub table_angle: Vec<f64>,
    /// True attitude at the end of each sample \[rad\].
    pub pitch: Vec<f64>,
    pub roll: Vec<f64>,
    pub yaw: Vec<f64>,
    /// Moving base only (empty for a static base): true position at the end of each sample (lat, lon \[rad\],
    /// height \[m\]) and true velocity [m/s], ENU, flattened row-major (n x 3).
    pub lat: Vec<f64>,
    pub lon: Vec<f64>,
    pub height: Vec<f64>,
    pub vel: Vec<f64>,
}

impl ImuChunk {
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Set every buffer to n samples (contents are overwritten by the simulator).
    pub(super) fn resize(&mut self, n: usize) {
        for v in [
            &mut self.t_s,
            &mut self.temp_c,
            &mut self.table_angle,
            &mut self.pitch,
            &mut self.roll,
            &mut self.yaw,
        ] {
            v.resize(n, 0.0);
        }
        self.dtheta.resize(3 * n, 0.0);
        self.dv.resize(3 * n, 0.0);
    }

    /// Size the moving-base truth buffers to n samples (0 for a static base).
    pub(super) fn resize_truth(&mut self, n: usize) {
        for v in [&mut self.lat, &mut self.lon, &mut self.height] {
            v.resize(n, 0.0);
        }
        self.vel.resize(3 * n, 0.0);
    }
}

/// Caller-provided moving-base truth buffers (same meaning as the fields of [`ImuChunk`]).
#[derive(Debug)]
pub struct TruthSlices<'a> {
    pub lat: &'a mut [f64],
    pub lon: &'a mut [f64],
    pub height: &'a mut [f64],
    pub vel: &'a mut [f64],
}

/// Caller-provided output buffers for [`super::ImuSimulator::fill`] (same meaning as the fields of [`ImuChunk`]).
#[derive(Debug)]
pub struct ImuChunkSlices<'a> {
    pub t_s: &'a mut [f64],
    pub dtheta: &'a mut [f64],
    pub dv: &'a mut [f64],
    pub temp_c: &'a mut [f64],
    pub table_angle: &'a mut [f64],
    pub pitch: &'a mut [f64],
    pub roll: &'a mut [f64],
    pub yaw: &'a mut [f64],
    /// Moving base: where to write the true position and velocity (None: not wanted).
    pub truth: Option<TruthSlices<'a>>,
}
