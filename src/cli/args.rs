//! Flag groups shared by several subcommands, declared once so that every
//! subcommand spells, defaults and checks them the same way.

use anyhow::{bail, Result};
use std::path::PathBuf;
use whycode::detect::Target;
use whycode::family::{Family, DEFAULT_BITS, DEFAULT_DISTANCE};
use whycode::units::{format_number, Length};

/// Which ID family: generated from `--bits` and `--distance`, or loaded
/// from a family file.
#[derive(Debug, clap::Args)]
pub struct FamilyArgs {
    /// Code length of the ID family, 2 to 24 bits; `detect` also takes
    /// `auto`: each ring's bit count (4-24) read from the ring
    #[arg(
        long,
        short = 'b',
        value_name = "BITS",
        default_value_t = DEFAULT_BITS,
        value_parser = bits_or_auto,
        allow_hyphen_values = true,
        conflicts_with = "family"
    )]
    pub bits: u32,

    /// Minimum cyclic Hamming distance between the family's IDs, 1 to the
    /// bit count (2 detects a misread bit, 3 corrects it) [default: 2]
    #[arg(
        long,
        short = 'd',
        value_name = "D",
        value_parser = parse_distance,
        allow_hyphen_values = true,
        conflicts_with = "family"
    )]
    pub distance: Option<DistanceArg>,

    /// ID family from a family file (written by `whycode ids --format json`)
    /// instead of --bits and --distance
    #[arg(long, value_name = "FILE")]
    pub family: Option<PathBuf>,
}

/// The family flags plus `--legacy`, for the subcommands that also handle
/// the original WhyCon circles.
#[derive(Debug, clap::Args)]
pub struct MarkerKindArgs {
    #[command(flatten)]
    pub family: FamilyArgs,

    /// Legacy WhyCon circles without an ID ring
    #[arg(long, conflicts_with_all = ["bits", "distance", "family"])]
    pub legacy: bool,
}

/// What `--distance` was given as. It is the Hamming distance everywhere;
/// `simulate --distance 0.8m` (a length) is the camera distance's old
/// spelling, kept for one release.
#[derive(Debug, Clone)]
pub enum DistanceArg {
    Hamming(u32),
    Length { length: Length, text: String },
}

fn parse_distance(text: &str) -> Result<DistanceArg, String> {
    if let Ok(d) = text.trim().parse::<u32>() {
        return Ok(DistanceArg::Hamming(d));
    }
    match text.parse::<Length>() {
        Ok(length) => Ok(DistanceArg::Length {
            length,
            text: text.to_string(),
        }),
        Err(_) => Err(format!(
            "'{text}' is not a Hamming distance (a whole number from 1 to the bit count)"
        )),
    }
}

/// A whole number, refused with one message whatever the typo (a sign, a
/// fraction, a huge value).
/// `--bits auto` (stands for no fixed count).
pub const AUTO_BITS: u32 = 0;

fn bits_or_auto(text: &str) -> Result<u32, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        Ok(AUTO_BITS)
    } else {
        whole_number(text)
    }
}

pub fn whole_number(text: &str) -> Result<u32, String> {
    let t = text.trim();
    t.parse::<u32>().map_err(|_| {
        if !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit()) {
            format!("{} is far too large", shorten_digits(t))
        } else {
            format!("'{text}' is not a whole number")
        }
    })
}

/// A long run of digits shortened for a message ("123...789, 40 digits").
fn shorten_digits(digits: &str) -> String {
    if digits.len() <= 20 {
        digits.to_string()
    } else {
        format!(
            "{}...{} ({} digits)",
            &digits[..3],
            &digits[digits.len() - 3..],
            digits.len()
        )
    }
}

impl FamilyArgs {
    /// The Hamming distance given (or the default); a length is refused.
    pub fn hamming(&self) -> Result<u32> {
        match &self.distance {
            None => Ok(DEFAULT_DISTANCE),
            Some(DistanceArg::Hamming(d)) => Ok(*d),
            Some(DistanceArg::Length { text, .. }) => bail!(
                "--distance '{text}': --distance is the family's Hamming distance, a whole number (2, 3, ...)"
            ),
        }
    }

    /// The family these flags name.
    pub fn resolve(&self) -> Result<Family> {
        match &self.family {
            Some(path) => Ok(Family::load(path)?),
            None if self.bits == AUTO_BITS => {
                bail!("--bits auto reads each marker's bit count from its ring: only `detect` takes it")
            }
            None => Ok(Family::generate(self.bits, self.hamming()?)?),
        }
    }

    /// Flags naming the family, for messages ("--bits 8 --distance 2" or
    /// "--family lab.json").
    pub fn describe(&self) -> String {
        match &self.family {
            Some(path) => format!("--family {}", path.display()),
            None => match self.hamming() {
                Ok(d) => format!("--bits {} --distance {d}", self.bits),
                Err(_) => format!("--bits {}", self.bits),
            },
        }
    }
}

impl MarkerKindArgs {
    /// Which markers these flags name: legacy circles, or WhyCode markers
    /// of the family.
    pub fn resolve(&self) -> Result<Target> {
        if self.legacy {
            Ok(Target::WhyCon)
        } else if self.family.bits == AUTO_BITS && self.family.family.is_none() {
            let distance = match self.family.distance {
                Some(_) => {
                    let d = self.family.hamming()?;
                    // A distance no bit count accepts is refused up front.
                    Family::generate(DEFAULT_BITS.max(d), d)?;
                    Some(d)
                }
                None => None,
            };
            Ok(Target::AnyBits { distance })
        } else {
            self.family.resolve().map(Target::WhyCode)
        }
    }
}

/// Output formats of the subcommands that print records.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Aligned columns, for reading
    Table,
    /// One row per record, with a header
    Csv,
    /// Machine-readable records
    Json,
}

/// `--format`.
#[derive(Debug, clap::Args)]
pub struct FormatArg {
    /// Output format
    #[arg(long, short = 'f', value_enum, default_value_t = Format::Table)]
    pub format: Format,
}

/// Lowest and highest PNG resolution. Above 1200 dpi a page is hundreds of
/// megapixels; PDF and SVG are exact at any size.
pub const DPI_RANGE: std::ops::RangeInclusive<f64> = 10.0..=1200.0;

/// `--dpi`.
#[derive(Debug, clap::Args)]
pub struct DpiArg {
    /// Resolution of PNG output, 10 to 1200 dots per inch (PDF and SVG are
    /// exact at any size)
    #[arg(long, default_value = "300", value_parser = parse_dpi, allow_hyphen_values = true)]
    pub dpi: f64,
}

fn parse_dpi(text: &str) -> Result<f64, String> {
    let value = parse_plain_number(text)?;
    if !DPI_RANGE.contains(&value) {
        return Err(format!(
            "{} dpi is outside {} to {} dpi",
            format_number(value),
            DPI_RANGE.start(),
            DPI_RANGE.end()
        ));
    }
    Ok(value)
}

/// A finite decimal number ("3", "0.5", "-2", "1e3").
pub fn parse_plain_number(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("'{text}' is not a number")),
    }
}
