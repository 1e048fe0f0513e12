//! The one error type of the core: every expected failure (a setting out of range, input arrays that do not
//! fit, a sample no IMU delivers, an estimate that leaves its physical range) is a [`CoreError`]; library code
//! does not panic on data. Messages name the quantity (by its SI key of the binding, e.g. `lat_rad`), its
//! value in user units (deg, deg/s, deg/h, m, Hz, s, g) and the limit, e.g.
//! `lat_rad: latitude 91.5 deg is outside [-89, 89] deg`.

use crate::units;
use std::fmt;

/// An expected failure of the core (see the module docs). `key()` names the setting or input.
#[derive(Clone, Debug, PartialEq)]
pub enum CoreError {
    /// A setting outside its range or inconsistent with another one.
    Setting { key: &'static str, message: String },
    /// Input arrays whose lengths or shapes do not fit together.
    Shape { key: &'static str, message: String },
    /// An input sample that no IMU delivers (not finite, or beyond the sensor limits of `limits`);
    /// `index` counts from 0 within the call.
    Sample {
        key: &'static str,
        index: usize,
        message: String,
    },
    /// An estimate or the navigated state left its physical range at `t_s` \[s\] from the start: the data do
    /// not fit the model (e.g. a log that is not a static base).
    Diverged {
        key: &'static str,
        t_s: f64,
        message: String,
    },
    /// A result asked for before its span is complete.
    Incomplete { done: u64, needed: u64 },
}

impl CoreError {
    /// The setting or input the error is about (an SI key of the binding, e.g. `lat_rad`, `dtheta_rad`).
    pub fn key(&self) -> &'static str {
        match self {
            CoreError::Setting { key, .. }
            | CoreError::Shape { key, .. }
            | CoreError::Sample { key, .. }
            | CoreError::Diverged { key, .. } => key,
            CoreError::Incomplete { .. } => "samples",
        }
    }
}

impl CoreError {
    /// The same error with a sample index counted `by` samples later (a block's index made the call's).
    pub(crate) fn offset(self, by: usize) -> Self {
        match self {
            CoreError::Sample { key, index, message } => CoreError::Sample {
                key,
                index: index + by,
                message,
            },
            other => other,
        }
    }
}

impl fmt::Display for CoreError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CoreError::Setting { key, message } | CoreError::Shape { key, message } => write!(f, "{key}: {message}"),
            CoreError::Sample { key, index, message } => write!(f, "{key}: sample {index}: {message}"),
            CoreError::Diverged { key, t_s, message } => write!(f, "{key}: at t = {} s: {message}", sig(*t_s)),
            CoreError::Incomplete { done, needed } => {
                write!(f, "alignment not complete: {done} of {needed} samples processed")
            }
        }
    }
}

impl std::error::Error for CoreError {}

/// `Ok(())` if `ok`, else a [`CoreError::Setting`] naming `key`.
pub(crate) fn check(ok: bool, key: &'static str, message: impl Into<String>) -> Result<(), CoreError> {
    if ok {
        Ok(())
    } else {
        Err(CoreError::Setting {
            key,
            message: message.into(),
        })
    }
}

/// As [`check`], with the message formatted only on failure (the validations run on every call of the core, some
/// of them per chunk or per piece of a route: formatting their numbers every time cost more than the checks).
pub(crate) fn check_with(ok: bool, key: &'static str, message: impl FnOnce() -> String) -> Result<(), CoreError> {
    if ok {
        Ok(())
    } else {
        Err(CoreError::Setting {
            key,
            message: message(),
        })
    }
}

/// As [`check_with`], for inputs that do not fit together: a [`CoreError::Shape`] naming `key`.
pub(crate) fn check_shape_with(ok: bool, key: &'static str, message: impl FnOnce() -> String) -> Result<(), CoreError> {
    check_with(ok, key, message).map_err(|e| match e {
        CoreError::Setting { key, message } => CoreError::Shape { key, message },
        other => other,
    })
}

/// User units of messages: the SI value is converted before printing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Unit {
    /// rad printed in deg.
    Deg,
    /// rad/s printed in deg/s.
    DegPerS,
    /// rad/s printed in deg/h.
    DegPerH,
    /// rad/s^2 printed in deg/s^2.
    DegPerS2,
    /// m/s^2 printed in g (9.80665 m/s^2).
    G,
    /// Printed as it is, with this unit name (m, m/s, Hz, s, deg C, "").
    Si(&'static str),
    /// Multiplied by the factor, printed with the name (e.g. rad/sqrt(s) in deg/sqrt(h)).
    Scaled(f64, &'static str),
}

/// rad/sqrt(s) printed in deg/sqrt(h) (angle random walk).
pub(crate) const DEG_PER_RTH: Unit = Unit::Scaled(units::SQRT_HOUR / units::DEG, "deg/sqrt(h)");
/// rad/s/sqrt(s) printed in deg/h/sqrt(h) (rate random walk).
pub(crate) const DEG_H_PER_RTH: Unit = Unit::Scaled(units::HOUR * units::SQRT_HOUR / units::DEG, "deg/h/sqrt(h)");
/// m/s^2 printed in ug (1 ug = 9.80665e-6 m/s^2).
pub(crate) const MICRO_G: Unit = Unit::Scaled(1.0 / units::MICRO_G, "ug");
/// m/s/sqrt(s) printed in ug/sqrt(Hz) (velocity random walk).
pub(crate) const MICRO_G_PER_RTHZ: Unit = Unit::Scaled(1.0 / units::MICRO_G, "ug/sqrt(Hz)");
/// A ratio printed in ppm.
pub(crate) const PPM: Unit = Unit::Scaled(1e6, "ppm");
/// rad printed in arcsec.
pub(crate) const ARCSEC: Unit = Unit::Scaled(units::HOUR / units::DEG, "arcsec");
/// rad/s/degC printed in deg/h/degC (a thermal coefficient of the drift).
pub(crate) const DEG_H_PER_C: Unit = Unit::Scaled(units::HOUR / units::DEG, "deg/h/degC");

impl Unit {
    fn convert(self, x: f64) -> f64 {
        match self {
            Unit::Deg | Unit::DegPerS | Unit::DegPerS2 => x.to_degrees(),
            Unit::DegPerH => x.to_degrees() * units::HOUR,
            Unit::G => x / units::STANDARD_GRAVITY,
            Unit::Si(_) => x,
            Unit::Scaled(factor, _) => x * factor,
        }
    }

    /// Inverse of the display conversion: `x` in this unit to SI.
    pub(crate) fn to_si(self, x: f64) -> f64 {
        x / self.convert(1.0)
    }

    fn name(self) -> &'static str {
        match self {
            Unit::Deg => "deg",
            Unit::DegPerS => "deg/s",
            Unit::DegPerH => "deg/h",
            Unit::DegPerS2 => "deg/s^2",
            Unit::G => "g",
            Unit::Si(n) | Unit::Scaled(_, n) => n,
        }
    }

    /// `x` (SI) in this unit, e.g. "91.5 deg".
    pub(crate) fn show(self, x: f64) -> String {
        let n = self.name();
        if n.is_empty() {
            sig(self.convert(x))
        } else {
            format!("{} {n}", sig(self.convert(x)))
        }
    }
}

/// Check that `x` (SI) lies in [lo, hi] (SI) and is finite; the message gives the quantity, the value and
/// the limits in `unit`.
pub(crate) fn in_range(
    key: &'static str,
    quantity: &str,
    x: f64,
    lo: f64,
    hi: f64,
    unit: Unit,
) -> Result<(), CoreError> {
    check_with(x.is_finite() && x >= lo && x <= hi, key, || {
        format!(
            "{quantity} {} is outside [{}, {}]{}",
            unit.show(x),
            sig(unit.convert(lo)),
            sig(unit.convert(hi)),
            match unit.name() {
                "" => String::new(),
                n => format!(" {n}"),
            }
        )
    })
}

/// Values (SI) in `unit` as "(a, b, c) unit".
pub(crate) fn show_all(v: &[f64], unit: Unit) -> String {
    let items: Vec<String> = v.iter().map(|&x| sig(unit.convert(x))).collect();
    match unit.name() {
        "" => format!("({})", items.join(", ")),
        n => format!("({}) {n}", items.join(", ")),
    }
}

/// Check that every element of `v` (SI) lies in [lo, hi] and is finite; the message shows all of them.
pub(crate) fn all_in_range(
    key: &'static str,
    quantity: &str,
    v: &[f64],
    lo: f64,
    hi: f64,
    unit: Unit,
) -> Result<(), CoreError> {
    check_with(v.iter().all(|x| x.is_finite() && *x >= lo && *x <= hi), key, || {
        format!(
            "{quantity} {} is outside [{}, {}]{}",
            show_all(v, unit),
            sig(unit.convert(lo)),
            sig(unit.convert(hi)),
            match unit.name() {
                "" => String::new(),
                n => format!(" {n}"),
            }
        )
    })
}

/// Check that every element of `v` (SI) is finite, positive and at most `hi`; the message shows all of them.
pub(crate) fn all_positive_at_most(
    key: &'static str,
    quantity: &str,
    v: &[f64],
    hi: f64,
    unit: Unit,
) -> Result<(), CoreError> {
    check_with(v.iter().all(|x| x.is_finite() && *x > 0.0 && *x <= hi), key, || {
        format!(
            "{quantity} {} is outside (0, {}]{}",
            show_all(v, unit),
            sig(unit.convert(hi)),
            match unit.name() {
                "" => String::new(),
                n => format!(" {n}"),
            }
        )
    })
}

/// A number with 6 significant digits, without trailing zeros (90 not 90.00000, 1e-300 in exponent form).
pub(crate) fn sig(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".to_string();
    }
    let e = x.abs().log10().floor();
    if (-4.0..15.0).contains(&e) {
        let decimals = (5.0 - e).max(0.0) as usize;
        let s = format!("{x:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{x:.5e}");
        match s.split_once('e') {
            Some((m, exp)) if m.contains('.') => format!("{}e{exp}", m.trim_end_matches('0').trim_end_matches('.')),
            _ => s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_passing_check_formats_no_message() {
        let mut formatted = 0;
        assert!(check_with(true, "k", || {
            formatted += 1;
            String::new()
        })
        .is_ok());
        assert_eq!(formatted, 0);
        let e = check_with(false, "k", || format!("x {}", sig(1.5))).unwrap_err();
        assert_eq!(e.to_string(), "k: x 1.5");
        assert!(in_range("k", "q", 2.0, 0.0, 1.0, Unit::Si("m")).is_err());
        assert!(in_range("k", "q", f64::NAN, 0.0, 1.0, Unit::Si("m")).is_err());
        assert!(in_range("k", "q", 0.5, 0.0, 1.0, Unit::Si("m")).is_ok());
    }

    #[test]
    fn numbers_print_short() {
        assert_eq!(sig(90.0), "90");
        assert_eq!(sig(-89.5), "-89.5");
        assert_eq!(sig(1.0 / 3.0), "0.333333");
        assert_eq!(sig(1e-300), "1e-300");
        assert_eq!(sig(1.5e20), "1.5e20");
        assert_eq!(sig(f64::NAN), "NaN");
        assert_eq!(sig(0.0), "0");
    }

    #[test]
    fn range_messages_use_user_units() {
        let e = in_range("lat_rad", "latitude", 1.6, -1.0, 1.0, Unit::Deg).unwrap_err();
        assert_eq!(e.key(), "lat_rad");
        assert_eq!(
            e.to_string(),
            "lat_rad: latitude 91.6732 deg is outside [-57.2958, 57.2958] deg"
        );
        let e = in_range("b", "bias", 1e-5, 0.0, 0.0, Unit::DegPerH).unwrap_err();
        assert!(e.to_string().contains("2.06265 deg/h"), "{e}");
        assert!(in_range("x", "x", f64::NAN, 0.0, 1.0, Unit::Si("m")).is_err());
        assert!(in_range("x", "x", 0.5, 0.0, 1.0, Unit::Si("m")).is_ok());
    }
}
