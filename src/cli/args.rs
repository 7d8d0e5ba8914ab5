//! Flag groups shared by several subcommands, declared once so that every
//! subcommand spells, defaults and checks them the same way.

use anyhow::{bail, Result};
use std::path::PathBuf;
use whycode::detect::Target;
use whycode::limits;
use whycode::render::job::PrintError;
use whycode::render::RenderError;
use whycode::spec::{cli_option, Bits, SpecError, TargetSpec};
use whycode::units::Length;

/// Which ID family: generated from `--bits` and `--distance`, or loaded
/// from a family file.
#[derive(Debug, clap::Args)]
pub struct FamilyArgs {
    /// Code length of the ID family, 2 to 24 bits [default: 8]; `detect`
    /// also takes `auto`: each ring's bit count (4-24) read from the ring
    #[arg(
        long,
        short = 'b',
        value_name = "BITS",
        value_parser = bits_or_auto,
        allow_hyphen_values = true,
        conflicts_with = "family"
    )]
    pub bits: Option<Bits>,

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

fn bits_or_auto(text: &str) -> Result<Bits, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        Ok(Bits::Auto)
    } else {
        whole_number(text).map(Bits::Count)
    }
}

/// A whole number, refused with one message whatever the typo (a sign, a
/// fraction, a huge value).
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
    /// The Hamming distance given; a length is refused.
    fn hamming(&self) -> Result<Option<u32>> {
        match &self.distance {
            None => Ok(None),
            Some(DistanceArg::Hamming(d)) => Ok(Some(*d)),
            Some(DistanceArg::Length { text, .. }) => bail!(
                "--distance '{text}': --distance is the family's Hamming distance, a whole number (2, 3, ...)"
            ),
        }
    }

    /// The library's spec of the family these flags name.
    pub fn spec(&self) -> Result<TargetSpec> {
        Ok(TargetSpec {
            bits: self.bits,
            distance: self.hamming()?,
            family_file: self.family.clone(),
            ..TargetSpec::default()
        })
    }
}

impl MarkerKindArgs {
    /// The library's spec of the markers these flags name.
    pub fn spec(&self) -> Result<TargetSpec> {
        Ok(TargetSpec {
            legacy: self.legacy,
            ..self.family.spec()?
        })
    }

    /// Which markers these flags name: legacy circles, or WhyCode markers
    /// of the family (or of any bit count).
    pub fn resolve(&self) -> Result<Target> {
        self.spec()?.resolve().map_err(spec_error)
    }
}

/// A print job's error in the command line's words.
pub fn print_error(err: PrintError) -> anyhow::Error {
    match err {
        PrintError::Option(err) => spec_error(err),
        PrintError::Render(err @ RenderError::SelfCheck { .. }) => {
            anyhow::anyhow!("{err} (nothing written; --no-check skips the check)")
        }
        PrintError::Render(err) => err.into(),
    }
}

pub use whycode::units::parse_scale;

/// A library spec's error in the command line's words (`--camera-distance`
/// where the spec says `camera_distance`).
pub fn spec_error(err: SpecError) -> anyhow::Error {
    anyhow::anyhow!(err.message_with(cli_option))
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
    limits::DPI.check(value).map_err(|e| e.to_string())
}

/// A finite decimal number ("3", "0.5", "-2", "1e3").
pub fn parse_plain_number(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("'{text}' is not a number")),
    }
}
