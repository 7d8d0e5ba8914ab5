//! Log lines as rclcpp prints them (`[WARN] [1732623872.123456789]
//! [whycode]: ...`) on stderr, and on /rosout for `ros2 topic echo
//! /rosout` and rqt_console; plus the rule that a bad input is reported
//! once per cause, not once per frame.

use crate::args::LogLevel;
use ros2_client::dds::{NodeLoggingHandle, RosoutRaw};
use std::collections::HashSet;
use std::sync::Mutex;
use std::time::{SystemTime, UNIX_EPOCH};

/// The node's logger. Shared between the node loop and the parameter
/// service thread.
pub struct Logger {
    name: String,
    level: LogLevel,
    stdout: bool,
    rosout: Mutex<Option<NodeLoggingHandle>>,
    reported: Mutex<HashSet<String>>,
}

impl Logger {
    /// A logger named after the node, printing `level` and above.
    pub fn new(name: &str, level: LogLevel, stdout: bool) -> Logger {
        Logger {
            name: name.to_string(),
            level,
            stdout,
            rosout: Mutex::new(None),
            reported: Mutex::new(HashSet::new()),
        }
    }

    /// From now on, lines also go to /rosout.
    pub fn attach_rosout(&self, handle: NodeLoggingHandle) {
        *self.rosout.lock().expect("logger lock") = Some(handle);
    }

    /// From now on, lines go to stderr only (the node is leaving).
    pub fn detach_rosout(&self) {
        *self.rosout.lock().expect("logger lock") = None;
    }

    /// Logs one line.
    pub fn log(&self, level: LogLevel, message: &str) {
        if level < self.level {
            return;
        }
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default();
        if self.stdout {
            eprintln!(
                "[{}] [{}.{:09}] [{}]: {message}",
                level.name(),
                now.as_secs(),
                now.subsec_nanos(),
                self.name
            );
        }
        if let Some(handle) = self.rosout.lock().expect("logger lock").as_ref() {
            let stamp = ros2_client::builtin_interfaces::Time::from_nanos(
                i64::try_from(now.as_nanos()).unwrap_or(i64::MAX),
            );
            let rosout_level = match level {
                LogLevel::Debug => ros2_client::log::LogLevel::Debug,
                LogLevel::Info => ros2_client::log::LogLevel::Info,
                LogLevel::Warn => ros2_client::log::LogLevel::Warn,
                LogLevel::Error => ros2_client::log::LogLevel::Error,
                LogLevel::Fatal => ros2_client::log::LogLevel::Fatal,
            };
            handle.rosout_raw(stamp, rosout_level, &self.name, message, file!(), "", 0);
        }
    }

    /// Logs at info level.
    pub fn info(&self, message: &str) {
        self.log(LogLevel::Info, message);
    }

    /// Logs at warning level.
    pub fn warn(&self, message: &str) {
        self.log(LogLevel::Warn, message);
    }

    /// Logs at error level.
    pub fn error(&self, message: &str) {
        self.log(LogLevel::Error, message);
    }

    /// Logs `message` the first time `cause` comes up; true if it did.
    pub fn once(&self, level: LogLevel, cause: &str, message: &str) -> bool {
        let first = self
            .reported
            .lock()
            .expect("logger lock")
            .insert(cause.to_string());
        if first {
            self.log(level, message);
        }
        first
    }

    /// Lets `cause` be reported again (it went away, and may come back).
    pub fn forget(&self, cause: &str) {
        self.reported.lock().expect("logger lock").remove(cause);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cause_is_reported_once_until_forgotten() {
        let log = Logger::new("test", LogLevel::Fatal, false);
        assert!(log.once(LogLevel::Warn, "encoding x", "bad"));
        assert!(!log.once(LogLevel::Warn, "encoding x", "bad again"));
        assert!(log.once(LogLevel::Warn, "encoding y", "other"));
        log.forget("encoding x");
        assert!(log.once(LogLevel::Warn, "encoding x", "back"));
    }
}
