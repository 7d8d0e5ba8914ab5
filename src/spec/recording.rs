//! Reading a recorded run (a bag or a video) as the front ends ask for it:
//! `whycode detect`'s `--topic`, `--every`, `--start` and `--end`, checked
//! once and built into [`ReadOptions`].

use super::{Problem, SpecError};
use crate::recording::ReadOptions;

/// What to read of a recording. `Default` reads every frame of the one
/// image topic.
#[derive(Debug, Clone, Default)]
pub struct RecordingSpec {
    /// A bag's image topic, when it has several.
    pub topic: Option<String>,
    /// Keep every n-th frame (default 1: all).
    pub every: Option<u64>,
    /// Seconds from the first frame where reading starts.
    pub start: Option<f64>,
    /// Seconds from the first frame where reading ends.
    pub end: Option<f64>,
}

/// Text that [`RecordingSpec::parse_time`] cannot read as a time.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{text}' is not a time (seconds like 12.5, or 1:30 for a minute and a half)")]
pub struct NotATime {
    /// The text, trimmed.
    pub text: String,
}

impl RecordingSpec {
    /// Checks the options and builds the reader's.
    pub fn build(&self) -> Result<ReadOptions, SpecError> {
        let every = self.every.unwrap_or(1);
        if every == 0 {
            return Err(SpecError::invalid(
                "every",
                "must be 1 or more (1 keeps every frame)",
            ));
        }
        let time = |option: &'static str, value: Option<f64>| -> Result<Option<i64>, SpecError> {
            match value {
                None => Ok(None),
                Some(s) if s.is_finite() && (0.0..1e9).contains(&s) => {
                    Ok(Some((s * 1e9).round() as i64))
                }
                Some(s) => Err(SpecError::invalid(
                    option,
                    format!("{s} s is not a time in the recording (0 or more seconds)"),
                )),
            }
        };
        let (start_ns, end_ns) = (time("start", self.start)?, time("end", self.end)?);
        if let (Some(start), Some(end)) = (start_ns, end_ns) {
            if end <= start {
                return Err(SpecError::of(
                    "end",
                    Problem::Conflict(format!(
                        "{} s is not after the start ({} s)",
                        end as f64 * 1e-9,
                        start as f64 * 1e-9
                    )),
                ));
            }
        }
        if self.topic.as_deref().is_some_and(|t| !t.starts_with('/')) {
            return Err(SpecError::invalid(
                "topic",
                "a topic name starts with '/' (as `ros2 bag info` lists it)",
            ));
        }
        Ok(ReadOptions {
            topic: self.topic.clone(),
            every,
            start_ns,
            end_ns,
        })
    }

    /// A time as users type it: seconds (`12.5`, `90s`) or a clock
    /// (`1:30`, `0:01:30.5`).
    pub fn parse_time(text: &str) -> Result<f64, NotATime> {
        let text = text.trim();
        let bad = || NotATime {
            text: text.to_string(),
        };
        let plain = text.strip_suffix('s').unwrap_or(text);
        let mut seconds = 0.0;
        for part in plain.split(':') {
            let value: f64 = part.parse().map_err(|_| bad())?;
            seconds = seconds * 60.0 + value;
        }
        Ok(seconds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_read_as_seconds_or_clocks() {
        assert_eq!(RecordingSpec::parse_time("12.5"), Ok(12.5));
        assert_eq!(RecordingSpec::parse_time("90s"), Ok(90.0));
        assert_eq!(RecordingSpec::parse_time("1:30"), Ok(90.0));
        assert_eq!(RecordingSpec::parse_time("0:01:30.5"), Ok(90.5));
        assert!(RecordingSpec::parse_time("soon").is_err());
    }

    #[test]
    fn windows_and_thinning_are_checked() {
        let spec = RecordingSpec {
            every: Some(0),
            ..RecordingSpec::default()
        };
        assert_eq!(spec.build().unwrap_err().option, Some("every"));
        let backwards = RecordingSpec {
            start: Some(5.0),
            end: Some(2.0),
            ..RecordingSpec::default()
        };
        assert_eq!(backwards.build().unwrap_err().option, Some("end"));
        let fine = RecordingSpec {
            start: Some(1.5),
            end: Some(2.0),
            every: Some(3),
            ..RecordingSpec::default()
        };
        let options = fine.build().unwrap();
        assert_eq!(
            (options.start_ns, options.end_ns, options.every),
            (Some(1_500_000_000), Some(2_000_000_000), 3)
        );
    }
}
