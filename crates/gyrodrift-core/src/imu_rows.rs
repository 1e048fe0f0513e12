//! The fast pass of the log reader's row checks (Python `gyrodrift.logs.rows`): whether a block of IMU log rows
//! is clean, and its sensor axes as the (n, 3) row-major arrays the navigator takes. One pass over the block per
//! quantity, no allocation but the outputs; the reader explains a block that is not clean itself (the row, the
//! column and what was expected), so nothing here names a cell.
//!
//! A block is clean when every time stamp is finite and one nominal step after the one before it (within the
//! tolerance; the block's first after the previous block's last), every stored gyro and accelerometer value is
//! within its magnitude limit (a NaN is not), every temperature and reference height lies within its closed
//! range, and every truth cell is finite: the reader's vectorised checks, comparison for comparison.

use crate::error::{check_shape_with as shape, CoreError};

/// The three axes of one sensor in a block: three columns of n values, or n rows of three (row-major, 3 n).
#[derive(Clone, Copy, Debug)]
pub enum Axes<'a> {
    Columns([&'a [f64]; 3]),
    Rows(&'a [f64]),
}

impl Axes<'_> {
    /// Samples in the block (rows of three values).
    pub fn len(&self) -> usize {
        match self {
            Axes::Columns(c) => c[0].len(),
            Axes::Rows(r) => r.len() / 3,
        }
    }

    /// Whether the block has no sample.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether every stored value has |x| <= `limit` (false at a NaN).
    fn within(&self, limit: f64) -> bool {
        match self {
            Axes::Columns(c) => c.iter().all(|col| col.iter().all(|x| x.abs() <= limit)),
            Axes::Rows(r) => r.iter().all(|x| x.abs() <= limit),
        }
    }

    /// The values as n rows of three (row-major), each times `scale`.
    pub fn rows_scaled(&self, scale: f64) -> Vec<f64> {
        match self {
            Axes::Columns([x, y, z]) => {
                let mut out = Vec::with_capacity(3 * x.len());
                for ((a, b), c) in x.iter().zip(y.iter()).zip(z.iter()) {
                    out.extend_from_slice(&[a * scale, b * scale, c * scale]);
                }
                out
            }
            Axes::Rows(r) => r.iter().map(|x| x * scale).collect(),
        }
    }

    /// An error unless the axes hold `n` samples (three equal columns, or 3 n row-major values).
    fn check_len(&self, n: usize, key: &'static str) -> Result<(), CoreError> {
        let ok = match self {
            Axes::Columns(c) => c.iter().all(|col| col.len() == n),
            Axes::Rows(r) => r.len() == 3 * n,
        };
        shape(ok, key, || {
            format!("expected {n} samples of three axes, one per time stamp")
        })
    }
}

/// One block of log rows: time stamps \[s\], the stored gyro and accelerometer values (increments or rates, as the
/// log holds them), and the optional columns.
#[derive(Clone, Debug)]
pub struct RowBlock<'a> {
    pub t: &'a [f64],
    pub gyro: Axes<'a>,
    pub accel: Axes<'a>,
    pub temperature: Option<&'a [f64]>,
    pub truth: Vec<&'a [f64]>,
    pub ref_height: Option<&'a [f64]>,
}

/// The limits of a clean block, in the units the log stores (the reader scales the rate limits by the step for
/// an increments log).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowLimits {
    /// Nominal time step 1 / rate \[s\] and the largest deviation of a step from it \[s\].
    pub step_s: f64,
    pub step_tolerance_s: f64,
    /// Largest |stored value| of a gyro and of an accelerometer axis.
    pub max_gyro: f64,
    pub max_accel: f64,
    /// Closed ranges of the temperature \[deg C\] and of the reference height \[m\].
    pub temperature_c: (f64, f64),
    pub height_m: (f64, f64),
}

impl RowBlock<'_> {
    /// An error unless every column has one value per time stamp.
    pub fn check_lengths(&self) -> Result<(), CoreError> {
        let n = self.t.len();
        self.gyro.check_len(n, "gyro")?;
        self.accel.check_len(n, "accel")?;
        let optional = [("temperature", self.temperature), ("ref_height", self.ref_height)];
        for (key, column) in optional
            .into_iter()
            .chain(self.truth.iter().map(|c| ("truth", Some(*c))))
        {
            if let Some(c) = column {
                shape(c.len() == n, key, || {
                    format!("expected {n} values, one per time stamp, got {}", c.len())
                })?;
            }
        }
        Ok(())
    }

    /// Whether the block is clean (module docs), its first step taken from `previous_t` \[s\], the last time stamp
    /// of the block before it (None: the log's first block).
    pub fn is_clean(&self, previous_t: Option<f64>, limits: &RowLimits) -> bool {
        let in_range = |c: &[f64], (low, high): (f64, f64)| c.iter().all(|&x| x >= low && x <= high);
        self.t.iter().all(|x| x.is_finite())
            && steps_ok(self.t, previous_t, limits)
            && self.gyro.within(limits.max_gyro)
            && self.accel.within(limits.max_accel)
            && self.temperature.is_none_or(|c| in_range(c, limits.temperature_c))
            && self.truth.iter().all(|c| c.iter().all(|x| x.is_finite()))
            && self.ref_height.is_none_or(|c| in_range(c, limits.height_m))
    }
}

/// Every step |t_k - t_(k-1) - step| <= tolerance, from `previous_t` to the first stamp too.
fn steps_ok(t: &[f64], previous_t: Option<f64>, limits: &RowLimits) -> bool {
    let ok = |a: f64, b: f64| ((b - a) - limits.step_s).abs() <= limits.step_tolerance_s;
    let first = match (previous_t, t.first()) {
        (Some(p), Some(&t0)) => ok(p, t0),
        _ => true,
    };
    first && t.windows(2).all(|w| ok(w[0], w[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: RowLimits = RowLimits {
        step_s: 0.1,
        step_tolerance_s: 0.001,
        max_gyro: 1.0,
        max_accel: 2.0,
        temperature_c: (-60.0, 150.0),
        height_m: (-1000.0, 20_000.0),
    };

    /// Time stamps 10.0, 10.1, ... and small sensor values: a clean block of `n` rows.
    fn columns(n: usize) -> (Vec<f64>, [Vec<f64>; 6], Vec<f64>) {
        let t = (0..n).map(|i| 10.0 + 0.1 * i as f64).collect();
        let sensors = std::array::from_fn(|k| (0..n).map(|i| 0.01 * (k + i) as f64 / n as f64).collect());
        (t, sensors, vec![25.0; n])
    }

    fn block<'a>(t: &'a [f64], s: &'a [Vec<f64>; 6], temp: &'a [f64]) -> RowBlock<'a> {
        RowBlock {
            t,
            gyro: Axes::Columns([&s[0], &s[1], &s[2]]),
            accel: Axes::Columns([&s[3], &s[4], &s[5]]),
            temperature: Some(temp),
            truth: vec![],
            ref_height: None,
        }
    }

    #[test]
    fn a_clean_block_and_each_kind_of_fault() {
        let (t, s, temp) = columns(50);
        assert!(block(&t, &s, &temp).is_clean(Some(9.9), &LIMITS));
        assert!(block(&t, &s, &temp).is_clean(None, &LIMITS));
        assert!(
            !block(&t, &s, &temp).is_clean(Some(9.8), &LIMITS),
            "a gap before the block"
        );
        type Fault = Box<dyn Fn(&mut Vec<f64>, &mut [Vec<f64>; 6], &mut Vec<f64>)>;
        let faults: Vec<Fault> = vec![
            Box::new(|t, _, _| t[7] = f64::NAN),
            Box::new(|t, _, _| t[30] += 0.05),
            Box::new(|_, s, _| s[1][3] = 1.5),
            Box::new(|_, s, _| s[2][3] = f64::NAN),
            Box::new(|_, s, _| s[5][49] = -2.5),
            Box::new(|_, _, temp| temp[0] = 300.0),
            Box::new(|_, _, temp| temp[9] = f64::NAN),
        ];
        for (k, fault) in faults.iter().enumerate() {
            let (mut t, mut s, mut temp) = columns(50);
            fault(&mut t, &mut s, &mut temp);
            assert!(!block(&t, &s, &temp).is_clean(Some(9.9), &LIMITS), "fault {k} passed");
        }
    }

    #[test]
    fn limits_are_inclusive_and_rows_equal_columns() {
        let (t, mut s, temp) = columns(8);
        s[0][2] = -1.0; // exactly the limit
        let b = block(&t, &s, &temp);
        assert!(b.is_clean(None, &LIMITS));
        let rows = b.gyro.rows_scaled(1.0);
        let as_rows = RowBlock {
            gyro: Axes::Rows(&rows),
            ..b.clone()
        };
        assert!(as_rows.is_clean(None, &LIMITS));
        assert_eq!(rows[3 * 2], -1.0);
        let scaled = as_rows.gyro.rows_scaled(0.5);
        for (i, row) in scaled.chunks(3).enumerate() {
            for (k, x) in row.iter().enumerate() {
                assert_eq!(*x, s[k][i] * 0.5);
            }
        }
    }

    #[test]
    fn mismatched_lengths_are_errors_not_panics() {
        let (t, s, temp) = columns(5);
        let short = vec![1.0; 4];
        let mut b = block(&t, &s, &temp);
        assert!(b.check_lengths().is_ok());
        b.ref_height = Some(&short);
        assert!(matches!(
            b.check_lengths(),
            Err(CoreError::Shape { key: "ref_height", .. })
        ));
        let mut b = block(&t, &s, &temp);
        b.gyro = Axes::Columns([&s[0], &short, &s[2]]);
        assert!(b.check_lengths().is_err());
        b.gyro = Axes::Rows(&short);
        assert!(b.check_lengths().is_err());
    }
}
