//! Physical quantities as users type them: lengths with units, angles.

use std::fmt;
use std::str::FromStr;

/// A length, stored in millimetres. Parses "50mm", "5cm", "0.05m", "2in",
/// "2\"" and "12.5 mm"; a bare number is refused, since guessing the unit is
/// how markers get printed at the wrong size.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Length {
    mm: f64,
}

impl Length {
    /// A length of `mm` millimetres.
    pub fn from_mm(mm: f64) -> Length {
        Length { mm }
    }

    /// A length of `m` metres.
    pub fn from_m(m: f64) -> Length {
        Length { mm: m * 1000.0 }
    }

    /// The length in millimetres.
    pub fn mm(self) -> f64 {
        self.mm
    }

    /// The length in metres.
    pub fn m(self) -> f64 {
        self.mm / 1000.0
    }

    /// The length in inches.
    pub fn inches(self) -> f64 {
        self.mm / 25.4
    }

    /// A length whose bare numbers are metres, as the reference tools take a
    /// detector's marker diameter and an arena's size.
    pub fn parse_metres(text: &str) -> Result<Length, LengthError> {
        Length::parse_with_default_unit(text, "m")
    }

    /// A height above a floor: a length whose bare numbers are metres, or
    /// 0 (on the floor) with or without a unit.
    pub fn parse_height(text: &str) -> Result<Length, LengthError> {
        let t = text.trim();
        let number = t.trim_end_matches(|c: char| c.is_ascii_alphabetic());
        if number.parse::<f64>().is_ok_and(|v| v == 0.0) {
            return Ok(Length::from_mm(0.0));
        }
        Length::parse_metres(text)
    }

    /// Parses a length whose bare numbers mean `default_unit` (e.g. "m" for a
    /// detector's marker diameter, where the reference tools take metres).
    pub fn parse_with_default_unit(text: &str, default_unit: &str) -> Result<Length, LengthError> {
        let t = text.trim();
        if !t.is_empty() && t.parse::<f64>().is_ok() {
            return format!("{t}{default_unit}").parse();
        }
        t.parse()
    }
}

/// Text that is not a length (see [`Length`]); `text` is as given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LengthError {
    /// No number first.
    #[error("'{text}' is not a length (write e.g. 50mm, 5cm, 0.05m or 2in)")]
    NotANumber {
        /// The text.
        text: String,
    },
    /// A number without a unit.
    #[error("'{text}' has no unit (write e.g. {value}mm, {value}cm, {value}m or {value}in)")]
    NoUnit {
        /// The text.
        text: String,
        /// The number.
        value: f64,
    },
    /// A unit that is not one of the lengths'.
    #[error("'{text}': unknown unit '{unit}' (use mm, cm, m or in)")]
    UnknownUnit {
        /// The text.
        text: String,
        /// The unit.
        unit: String,
    },
    /// Zero, negative, or too large to hold.
    #[error("'{text}' must be a positive length")]
    NotPositive {
        /// The text.
        text: String,
    },
}

impl FromStr for Length {
    type Err = LengthError;

    fn from_str(text: &str) -> Result<Length, LengthError> {
        let t = text.trim();
        let (number, unit) = t.split_at(number_prefix_len(t));
        let value: f64 = number.parse().map_err(|_| LengthError::NotANumber {
            text: text.to_string(),
        })?;
        let factor = match unit.trim() {
            "mm" => 1.0,
            "cm" => 10.0,
            "m" => 1000.0,
            "in" | "\"" | "inch" | "inches" => 25.4,
            "pt" => 25.4 / 72.0,
            "" => {
                return Err(LengthError::NoUnit {
                    text: text.to_string(),
                    value,
                })
            }
            other => {
                return Err(LengthError::UnknownUnit {
                    text: text.to_string(),
                    unit: other.to_string(),
                })
            }
        };
        let mm = value * factor;
        if !mm.is_finite() || mm <= 0.0 {
            return Err(LengthError::NotPositive {
                text: text.to_string(),
            });
        }
        Ok(Length { mm })
    }
}

impl fmt::Display for Length {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}mm", trim_float(self.mm))
    }
}

/// Length of the decimal number at the start of `text`: sign, digits,
/// fraction and exponent ("-1.5e3" of "-1.5e3mm"). An "e" not followed by
/// digits belongs to the unit.
fn number_prefix_len(text: &str) -> usize {
    let bytes = text.as_bytes();
    let digits = |mut i: usize| {
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut i = 0;
    if matches!(bytes.first(), Some(b'+' | b'-')) {
        i = 1;
    }
    i = digits(i);
    if bytes.get(i) == Some(&b'.') {
        i = digits(i + 1);
    }
    if matches!(bytes.get(i), Some(b'e' | b'E')) {
        let mut j = i + 1;
        if matches!(bytes.get(j), Some(b'+' | b'-')) {
            j += 1;
        }
        let end = digits(j);
        if end > j {
            i = end;
        }
    }
    i
}

/// An angle, stored in radians. Parses "30deg", "30°", "0.5rad". Like a
/// length, an angle needs its unit: a bare "0.5" could be either.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Angle {
    rad: f64,
}

impl Angle {
    /// An angle of `deg` degrees.
    pub fn from_degrees(deg: f64) -> Angle {
        Angle {
            rad: deg.to_radians(),
        }
    }

    /// The angle in radians.
    pub fn radians(self) -> f64 {
        self.rad
    }

    /// The angle in degrees.
    pub fn degrees(self) -> f64 {
        self.rad.to_degrees()
    }
}

/// Text that is not an angle (see [`Angle`]); `text` is as given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AngleError {
    /// A number without a unit.
    #[error("'{text}' has no unit (write e.g. {}deg or {}rad)", format_number(*value), format_number(*value))]
    NoUnit {
        /// The text.
        text: String,
        /// The number.
        value: f64,
    },
    /// No number before the unit.
    #[error("'{text}' is not an angle (write e.g. 30deg or 0.5rad)")]
    NotANumber {
        /// The text.
        text: String,
    },
    /// An infinite angle.
    #[error("'{text}' is not a finite angle")]
    NotFinite {
        /// The text.
        text: String,
    },
}

impl FromStr for Angle {
    type Err = AngleError;

    fn from_str(text: &str) -> Result<Angle, AngleError> {
        let t = text.trim();
        let (number, to_rad) = if let Some(n) = t.strip_suffix("deg").or(t.strip_suffix('°')) {
            (n, std::f64::consts::PI / 180.0)
        } else if let Some(n) = t.strip_suffix("rad") {
            (n, 1.0)
        } else {
            if let Ok(value) = t.parse::<f64>() {
                return Err(AngleError::NoUnit {
                    text: text.to_string(),
                    value,
                });
            }
            (t, std::f64::consts::PI / 180.0)
        };
        let value: f64 = number.trim().parse().map_err(|_| AngleError::NotANumber {
            text: text.to_string(),
        })?;
        if !value.is_finite() {
            return Err(AngleError::NotFinite {
                text: text.to_string(),
            });
        }
        Ok(Angle {
            rad: value * to_rad,
        })
    }
}

/// Text that is not a length in pixels.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{0}' is not a length in pixels (write e.g. 2px)")]
pub struct NotPixels(pub String);

/// A length in image pixels: `2px`, or a bare number of pixels.
pub fn parse_pixels(text: &str) -> Result<f64, NotPixels> {
    let t = text.trim();
    let number = t.strip_suffix("px").unwrap_or(t).trim();
    number
        .parse::<f64>()
        .map_err(|_| NotPixels(text.to_string()))
}

/// Formats a number the way a person would type it back: plain for
/// everyday magnitudes, exponent notation for huge or tiny ones, so a
/// message never echoes hundreds of digits.
pub fn format_number(v: f64) -> String {
    let magnitude = v.abs();
    if magnitude != 0.0 && !(1e-4..1e9).contains(&magnitude) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Formats a float without trailing zeros ("40", "12.5").
pub fn trim_float(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// A printer's scale as people write it: 0.97 or 97% (the command line's
/// `--print-scale`, the browser page's field).
pub fn parse_scale(text: &str) -> Result<f64, NotAScale> {
    let t = text.trim();
    match t.strip_suffix('%') {
        Some(p) => p.trim().parse::<f64>().map(|p| p / 100.0),
        None => t.parse::<f64>(),
    }
    .map_err(|_| NotAScale {
        text: text.to_string(),
    })
}

/// Text that [`parse_scale`] cannot read as a scale; `text` is as given.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{text}' is not a scale (write e.g. 0.97 or 97%)")]
pub struct NotAScale {
    /// The text.
    pub text: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_parse_with_units() {
        assert_eq!("50mm".parse::<Length>().unwrap().mm(), 50.0);
        assert_eq!("5cm".parse::<Length>().unwrap().mm(), 50.0);
        assert_eq!("0.122m".parse::<Length>().unwrap().mm(), 122.0);
        assert_eq!("2in".parse::<Length>().unwrap().mm(), 50.8);
        assert_eq!("12.5 mm".parse::<Length>().unwrap().mm(), 12.5);
        assert!("50".parse::<Length>().is_err());
        assert!("-5mm".parse::<Length>().is_err());
        assert!("5furlongs".parse::<Length>().is_err());
        assert_eq!("1e3mm".parse::<Length>().unwrap().mm(), 1000.0);
        assert_eq!("2.5E-1m".parse::<Length>().unwrap().mm(), 250.0);
        assert!("2em"
            .parse::<Length>()
            .unwrap_err()
            .to_string()
            .contains("unknown unit 'em'"));
        assert_eq!(
            Length::parse_with_default_unit("0.122", "m").unwrap().mm(),
            122.0
        );
    }

    #[test]
    fn angles_parse() {
        assert!((("30deg".parse::<Angle>().unwrap().degrees()) - 30.0).abs() < 1e-12);
        assert!((("0.5rad".parse::<Angle>().unwrap().radians()) - 0.5).abs() < 1e-12);
        assert!("45"
            .parse::<Angle>()
            .unwrap_err()
            .to_string()
            .contains("has no unit"));
        assert!((("-45deg".parse::<Angle>().unwrap().degrees()) + 45.0).abs() < 1e-12);
    }
}
