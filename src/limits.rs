//! The plausible range of every quantity a user can give, in one table for
//! the whole toolkit: the command line, the Python package and the browser
//! page check against these and nothing else, so a value one of them
//! accepts is never refused (or silently mangled) by another.
//!
//! The ranges are wide enough for every real use and narrow enough that a
//! slip (a metre for a millimetre, a stray exponent) is caught before it
//! prints a 0 mm marker or gives a pose a kilometre away.

use crate::units::format_number;

/// A closed range of plausible values of one quantity, in `unit`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// Smallest plausible value.
    pub min: f64,
    /// Largest plausible value.
    pub max: f64,
    /// The unit the values are in, as printed after a number ("mm", "dpi",
    /// "" for a plain ratio).
    pub unit: &'static str,
}

/// A value outside its [`Limit`] (or not a finite number at all).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("{} is outside {} to {}", with_unit(*value, limit.unit), format_number(limit.min), with_unit(limit.max, limit.unit))]
pub struct OutOfRange {
    /// The value given.
    pub value: f64,
    /// The range it had to be in.
    pub limit: Limit,
}

fn with_unit(value: f64, unit: &str) -> String {
    match unit {
        "" => format_number(value),
        "%" | "°" => format!("{}{unit}", format_number(value)),
        _ => format!("{} {unit}", format_number(value)),
    }
}

impl Limit {
    /// Whether `value` is a finite number in the range.
    pub fn contains(&self, value: f64) -> bool {
        value.is_finite() && self.min <= value && value <= self.max
    }

    /// `value` when it is in the range.
    pub fn check(&self, value: f64) -> Result<f64, OutOfRange> {
        if self.contains(value) {
            Ok(value)
        } else {
            Err(OutOfRange {
                value,
                limit: *self,
            })
        }
    }
}

/// Outer diameter of a marker's black disc, millimetres: from a marker read
/// under a microscope to one painted on a hangar floor.
pub const MARKER_DIAMETER_MM: Limit = Limit {
    min: 0.5,
    max: 10_000.0,
    unit: "mm",
};

/// PNG resolution. Above 1200 dpi a page is hundreds of megapixels; PDF and
/// SVG are exact at any size.
pub const DPI: Limit = Limit {
    min: 10.0,
    max: 1200.0,
    unit: "dpi",
};

/// Width or height of a simulated camera's image, pixels.
pub const IMAGE_SIDE_PX: Limit = Limit {
    min: 16.0,
    max: 20_000.0,
    unit: "px",
};

/// Horizontal field of view of a simulated ideal camera.
pub const FIELD_OF_VIEW_DEG: Limit = Limit {
    min: 1.0,
    max: 170.0,
    unit: "°",
};

/// Distance from a simulated camera to what it looks at, metres.
pub const CAMERA_DISTANCE_M: Limit = Limit {
    min: 0.01,
    max: 1000.0,
    unit: "m",
};

/// The scale a printer applied to a sheet (1 = printed at 100 %).
pub const PRINT_SCALE: Limit = Limit {
    min: 0.2,
    max: 5.0,
    unit: "",
};

/// Focus or motion blur of a simulated view, pixels. Past a few hundred
/// pixels nothing is left to see, and the cost grows with the length.
pub const BLUR_PX: Limit = Limit {
    min: 0.0,
    max: 500.0,
    unit: "px",
};

/// Brightest to darkest light across a simulated frame.
pub const LIGHT_GRADIENT: Limit = Limit {
    min: 1.0,
    max: 1000.0,
    unit: "",
};

/// Exposure of a simulated frame (1 puts white paper near grey 220).
pub const EXPOSURE: Limit = Limit {
    min: 0.001,
    max: 1000.0,
    unit: "",
};

/// Sensor noise of a simulated frame: Gaussian sigma in grey levels.
pub const NOISE_GREY_LEVELS: Limit = Limit {
    min: 0.0,
    max: 255.0,
    unit: "",
};

/// JPEG quality of a simulated frame.
pub const JPEG_QUALITY: Limit = Limit {
    min: 1.0,
    max: 100.0,
    unit: "",
};

/// How many loose markers one simulated scene holds.
pub const SCENE_MARKERS: Limit = Limit {
    min: 1.0,
    max: 100_000.0,
    unit: "",
};

/// Smallest black ring of a legacy marker worth reporting, pixels.
pub const LEGACY_MIN_INK_PX: Limit = Limit {
    min: 0.0,
    max: 1e9,
    unit: "px",
};

/// A side of an arena's rectangle of corner markers, metres: from a
/// tabletop maze to a sports hall.
pub const ARENA_SIDE_M: Limit = Limit {
    min: 0.05,
    max: 500.0,
    unit: "m",
};

/// Height of the markers located on an arena above its floor (markers on
/// robots, drones hovering low), metres.
pub const MARKER_HEIGHT_M: Limit = Limit {
    min: 0.0,
    max: 100.0,
    unit: "m",
};

/// Largest image side accepted by [`crate::image_io::load_gray`].
pub const MAX_SIDE: u32 = 30_000;
/// Largest image area accepted by [`crate::image_io::load_gray`], pixels.
pub const MAX_PIXELS: u64 = 400_000_000;

/// The largest image a reader accepts, checked against the file's header
/// before anything is decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SizeLimit {
    /// Longest side, pixels.
    pub max_side: u32,
    /// Largest area, pixels.
    pub max_pixels: u64,
}

impl SizeLimit {
    /// What [`crate::image_io::load_gray`] accepts: [`MAX_SIDE`] and [`MAX_PIXELS`].
    pub const FILES: SizeLimit = SizeLimit {
        max_side: MAX_SIDE,
        max_pixels: MAX_PIXELS,
    };

    /// What a compressed frame of a stream (a bag's or a topic's
    /// CompressedImage) may decode to: 64 megapixels, past any camera that
    /// streams, because a small PNG message can declare a huge image and
    /// each one would be decoded, frame after frame.
    pub const FRAMES: SizeLimit = SizeLimit {
        max_side: 16_384,
        max_pixels: 64_000_000,
    };

    /// Whether an image of `width` x `height` pixels is within the limit.
    pub fn admits(&self, width: u32, height: u32) -> bool {
        width <= self.max_side
            && height <= self.max_side
            && u64::from(width) * u64::from(height) <= self.max_pixels
    }
}

/// The longest page side a template or manifest may have, mm.
pub const MAX_PAGE_MM: f64 = 10_000.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_value_outside_says_the_range_in_its_unit() {
        let err = MARKER_DIAMETER_MM.check(1e-300).unwrap_err();
        assert_eq!(err.to_string(), "1e-300 mm is outside 0.5 to 10000 mm");
        assert_eq!(
            DPI.check(5000.0).unwrap_err().to_string(),
            "5000 dpi is outside 10 to 1200 dpi"
        );
        assert!(DPI.check(f64::NAN).is_err());
        assert_eq!(DPI.check(300.0), Ok(300.0));
    }
}
