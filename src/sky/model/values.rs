//! The field types that check their own range while they are read, so that a bad value is
//! rejected with the exact TOML span of its field.

use serde::{Deserialize, Deserializer};

macro_rules! checked_f32 {
    ($(#[$doc:meta])* $name:ident, $check:expr, $expect:literal) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, Default, PartialEq, PartialOrd)]
        pub struct $name(pub f32);
        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let v = f64::deserialize(d)?;
                let ok: fn(f64) -> bool = $check;
                if v.is_finite() && ok(v) {
                    Ok($name(v as f32))
                } else {
                    Err(serde::de::Error::custom(format!("expected {}, found {v}", $expect)))
                }
            }
        }
        impl $name {
            /// The checked value.
            pub fn get(self) -> f32 {
                self.0
            }
        }
    };
}

checked_f32!(
    /// Any finite number (NaN and infinities are rejected).
    Finite, |_| true, "a finite number");
checked_f32!(
    /// A finite number > 0.
    Positive, |v| v > 0.0, "a finite number > 0");
checked_f32!(
    /// A finite number >= 0.
    NonNegative, |v| v >= 0.0, "a finite number >= 0");
checked_f32!(
    /// A number in [0, 1].
    Unit, |v| (0.0..=1.0).contains(&v), "a number in [0, 1]");
checked_f32!(
    /// A phase-function asymmetry, strictly between -1 and 1.
    Asymmetry, |v| v > -1.0 && v < 1.0, "a number strictly between -1 and 1");
checked_f32!(
    /// Atmospheric turbidity, [1, 10].
    Turbidity, |v| (1.0..=10.0).contains(&v), "a turbidity in [1, 10]");
checked_f32!(
    /// A light factor of Braun and Cohen's model, [0, 255].
    LightFactor, |v| (0.0..=255.0).contains(&v), "a light factor in [0, 255]");
checked_f32!(
    /// An angle in degrees within [0, 90].
    Angle90, |v| (0.0..=90.0).contains(&v), "an angle in degrees within [0, 90]");
checked_f32!(
    /// An elevation in degrees, [-90, 90].
    Elevation, |v| (-90.0..=90.0).contains(&v), "an elevation in degrees within [-90, 90]");

/// Per-channel coefficients >= 0 (km^-1): one number for all three channels (grey), or three.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coefficients(pub [NonNegative; 3]);

impl Coefficients {
    /// The coefficients as f64, r g b.
    pub fn rgb(self) -> [f64; 3] {
        self.0.map(|c| c.get() as f64)
    }
}

impl<'de> Deserialize<'de> for Coefficients {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Form {
            Grey(f64),
            Rgb(Vec<f64>),
        }
        let expect = "one number >= 0 (grey) or three, [r, g, b]";
        let (values, found) = match Form::deserialize(d).map_err(|_| serde::de::Error::custom(format!("expected {expect}")))? {
            Form::Grey(v) => (vec![v; 3], v.to_string()),
            Form::Rgb(v) => (v.clone(), format!("{v:?}")),
        };
        match values[..] {
            [r, g, b] if values.iter().all(|v| v.is_finite() && *v >= 0.0) => Ok(Coefficients([r, g, b].map(|v| NonNegative(v as f32)))),
            _ => Err(serde::de::Error::custom(format!("expected {expect}, found {found}"))),
        }
    }
}

/// Transparency priority, 0..=63.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Priority(pub u8);

impl<'de> Deserialize<'de> for Priority {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = i64::deserialize(d)?;
        if (0..=63).contains(&v) {
            Ok(Priority(v as u8))
        } else {
            Err(serde::de::Error::custom(format!("expected a priority in 0..=63, found {v}")))
        }
    }
}

/// A sample count of a physical model, 1..=1024.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepCount(pub u32);

impl<'de> Deserialize<'de> for StepCount {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = i64::deserialize(d)?;
        if (1..=1024).contains(&v) {
            Ok(StepCount(v as u32))
        } else {
            Err(serde::de::Error::custom(format!("expected a sample count in 1..=1024, found {v}")))
        }
    }
}
