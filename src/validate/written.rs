//! How measured numbers are written in reports: pixels to 0.001 px and
//! ratios to one part per million. That is far finer than a photo measures
//! them, and coarse enough that the same photo gives the same report bytes
//! everywhere: the browser page's WebAssembly computes sin, cos and atan2
//! with Rust's own routines where the command line uses the C library's,
//! and the two round their last bits differently.
//!
//! Used with `#[serde(serialize_with = "...")]`; the values in memory keep
//! full precision.

use serde::Serializer;

fn rounded(value: f64, decimals: i32) -> f64 {
    // Powers of ten up to 10^22 are exact, and one rounding and one
    // correctly rounded division give the same result on every platform.
    let scale = 10f64.powi(decimals);
    (value * scale).round() / scale
}

const PIXEL_DECIMALS: i32 = 3;
const RATIO_DECIMALS: i32 = 6;

/// Image pixels, to 0.001 px.
pub fn pixels<S: Serializer>(value: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(rounded(*value, PIXEL_DECIMALS))
}

/// [`pixels`], when known.
pub fn pixels_opt<S: Serializer>(value: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match value {
        Some(v) => pixels(v, s),
        None => s.serialize_none(),
    }
}

/// A ratio (a scale, a relative size), to 1 ppm.
pub fn ratio<S: Serializer>(value: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(rounded(*value, RATIO_DECIMALS))
}

/// [`ratio`], when known.
pub fn ratio_opt<S: Serializer>(value: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match value {
        Some(v) => ratio(v, s),
        None => s.serialize_none(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize)]
    struct Written {
        #[serde(serialize_with = "pixels")]
        a: f64,
        #[serde(serialize_with = "pixels")]
        b: f64,
        #[serde(serialize_with = "ratio")]
        c: f64,
        #[serde(serialize_with = "ratio_opt")]
        d: Option<f64>,
        #[serde(serialize_with = "pixels_opt")]
        e: Option<f64>,
    }

    #[test]
    fn numbers_are_written_short_and_rounded() {
        let text = serde_json::to_string(&Written {
            a: 1_234.567_849_999,
            b: 12.0,
            c: 0.970_000_000_000_4,
            d: Some(1.000_012_345),
            e: None,
        })
        .unwrap();
        assert_eq!(
            text,
            r#"{"a":1234.568,"b":12.0,"c":0.97,"d":1.000012,"e":null}"#
        );
    }
}
