//! Which markers: a family from its parameters or its file, any bit count,
//! or legacy WhyCon circles.

use super::{Problem, SpecError};
use crate::detect::Target;
use crate::family::{Family, DEFAULT_BITS, DEFAULT_DISTANCE};
use std::path::PathBuf;

/// A ring's bit count as asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bits {
    /// Codes of exactly this many bits.
    Count(u32),
    /// Whatever count each ring shows (4-24); detection only.
    Auto,
}

/// Which markers a job is about, as every front end names them: the
/// family's parameters (`bits`, `distance`), a family file or a family
/// already in hand, or `legacy` WhyCon circles. The default is the default
/// family (8 bits, distance 2).
#[derive(Debug, Clone, Default)]
pub struct TargetSpec {
    /// Legacy WhyCon circles, which have no ID ring.
    pub legacy: bool,
    /// Code length; `None` is [`DEFAULT_BITS`].
    pub bits: Option<Bits>,
    /// Minimum cyclic Hamming distance; `None` is [`DEFAULT_DISTANCE`]
    /// (and, with [`Bits::Auto`], no IDs: codes only).
    pub distance: Option<u32>,
    /// A family file (`whycode ids --format json`).
    pub family_file: Option<PathBuf>,
    /// A family already loaded or generated (the Python binding's
    /// `Family` objects).
    pub family: Option<Family>,
}

impl TargetSpec {
    /// The default family's markers.
    pub fn whycode() -> TargetSpec {
        TargetSpec::default()
    }

    /// Legacy WhyCon circles.
    pub fn legacy() -> TargetSpec {
        TargetSpec {
            legacy: true,
            ..TargetSpec::default()
        }
    }

    /// The spec of a family in hand (`None`: legacy circles).
    pub fn of_family(family: Option<&Family>) -> TargetSpec {
        match family {
            Some(family) => TargetSpec {
                family: Some(family.clone()),
                ..TargetSpec::default()
            },
            None => TargetSpec::legacy(),
        }
    }

    /// Which markers these options name. See [`Target::resolve`].
    pub fn resolve(&self) -> Result<Target, SpecError> {
        let named_family = self.family.is_some() || self.family_file.is_some();
        if self.legacy && (named_family || self.bits.is_some() || self.distance.is_some()) {
            return Err(SpecError::of(
                "legacy",
                Problem::Conflict(
                    "WhyCon circles have no ID family: leave out bits, distance and family".into(),
                ),
            ));
        }
        if self.legacy {
            return Ok(Target::WhyCon);
        }
        if named_family && (self.bits.is_some() || self.distance.is_some()) {
            return Err(SpecError::of(
                "family",
                Problem::Conflict(
                    "a family names its own bits and distance: give one or the other".into(),
                ),
            ));
        }
        if let Some(family) = &self.family {
            return Ok(Target::WhyCode(family.clone()));
        }
        if let Some(path) = &self.family_file {
            let family = Family::load(path).map_err(SpecError::general)?;
            return Ok(Target::WhyCode(family));
        }
        match self.bits.unwrap_or(Bits::Count(DEFAULT_BITS)) {
            Bits::Auto => {
                if let Some(d) = self.distance {
                    // A distance that no bit count accepts is refused up front.
                    Family::generate(DEFAULT_BITS.max(d), d)
                        .map_err(|e| SpecError::of("distance", e))?;
                }
                Ok(Target::AnyBits {
                    distance: self.distance,
                })
            }
            Bits::Count(bits) => {
                let distance = self.distance.unwrap_or(DEFAULT_DISTANCE);
                let family = Family::generate(bits, distance).map_err(|e| {
                    let option = match e {
                        crate::family::FamilyError::Bits(_) => "bits",
                        _ => "distance",
                    };
                    SpecError::of(option, e)
                })?;
                Ok(Target::WhyCode(family))
            }
        }
    }

    /// The one family these options name, for jobs that need one (listing
    /// IDs, simulating loose markers): legacy circles and any-count
    /// reading are refused.
    pub fn family(&self) -> Result<Family, SpecError> {
        match self.resolve()? {
            Target::WhyCode(family) => Ok(family),
            Target::AnyBits { .. } => Err(SpecError::invalid(
                "bits",
                "auto reads each marker's bit count from its ring: only detection takes it",
            )),
            Target::WhyCon => Err(SpecError::invalid(
                "legacy",
                "WhyCon circles have no IDs to list or place: choose a family",
            )),
        }
    }

    /// The family for print jobs: `None` for legacy circles.
    pub fn printable_family(&self) -> Result<Option<Family>, SpecError> {
        match self.resolve()? {
            Target::WhyCon => Ok(None),
            _ => self.family().map(Some),
        }
    }
}

impl Target {
    /// Which markers `spec` names: the one place where legacy, bit count,
    /// distance and family file become a target, for every front end.
    pub fn resolve(spec: &TargetSpec) -> Result<Target, SpecError> {
        spec.resolve()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_way_of_naming_markers_resolves_once() {
        assert_eq!(
            TargetSpec::default().resolve().unwrap(),
            Target::WhyCode(Family::generate(8, 2).unwrap())
        );
        assert_eq!(TargetSpec::legacy().resolve().unwrap(), Target::WhyCon);
        let auto = TargetSpec {
            bits: Some(Bits::Auto),
            distance: Some(3),
            ..TargetSpec::default()
        };
        assert_eq!(
            auto.resolve().unwrap(),
            Target::AnyBits { distance: Some(3) }
        );
        assert_eq!(auto.family().unwrap_err().option, Some("bits"));
        let clash = TargetSpec {
            legacy: true,
            bits: Some(Bits::Count(12)),
            ..TargetSpec::default()
        };
        assert_eq!(clash.resolve().unwrap_err().option, Some("legacy"));
        let too_far = TargetSpec {
            bits: Some(Bits::Count(6)),
            distance: Some(7),
            ..TargetSpec::default()
        };
        let err = too_far.resolve().unwrap_err();
        assert_eq!(err.option, Some("distance"));
        assert_eq!(
            err.message_with(super::super::cli_option),
            "--distance: distance must be between 1 and the bit count 6, got 7"
        );
    }
}
