//! The ROS 2 command line, as `ros2 run` and `ros2 launch` pass it to a
//! node (rcl's rules): everything between `--ros-args` and `--` (or the end)
//! is ROS's: `-p name:=value`, `--params-file FILE`, `-r from:=to` (with
//! `__node`, `__ns`), `--log-level`, `--enable/--disable-rosout-logs`,
//! `--enable/--disable-stdout-logs`. Parameter values are YAML, as rcl reads
//! them; a params file maps node names (with `*` and `**` wildcards) to
//! `ros__parameters`. This module also resolves topic names against the
//! node's name, namespace and remapping rules.

use ros2_client::ParameterValue;
use std::path::{Path, PathBuf};

/// What the command line asked for.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RosArgs {
    /// `--help` outside the ROS arguments.
    pub help: bool,
    /// `--version` outside the ROS arguments.
    pub version: bool,
    /// Remapping rules in the order given (`-r`), `__node`/`__ns` included.
    pub remaps: Vec<Remap>,
    /// `-p` values, in the order given.
    pub params: Vec<(Option<String>, String, ParameterValue)>,
    /// `--params-file` files, in the order given.
    pub params_files: Vec<PathBuf>,
    /// `--log-level`: the least severe level printed.
    pub log_level: Option<LogLevel>,
    /// `--disable-rosout-logs` turns this off.
    pub rosout_logs: bool,
    /// `--disable-stdout-logs` turns this off.
    pub stdout_logs: bool,
}

/// A remapping rule `[node:]from:=to`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Remap {
    /// Applies only to the node of this name, when given.
    pub node: Option<String>,
    /// The name being replaced (or `__node`, `__ns`).
    pub from: String,
    /// Its replacement.
    pub to: String,
}

/// Severity of a log line, in rcutils' order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum LogLevel {
    /// Diagnostics.
    Debug,
    /// Normal operation.
    Info,
    /// Something the user should look at.
    Warn,
    /// Something failed.
    Error,
    /// The node cannot go on.
    Fatal,
}

impl LogLevel {
    /// The name printed in a log line.
    pub fn name(self) -> &'static str {
        match self {
            LogLevel::Debug => "DEBUG",
            LogLevel::Info => "INFO",
            LogLevel::Warn => "WARN",
            LogLevel::Error => "ERROR",
            LogLevel::Fatal => "FATAL",
        }
    }

    fn parse(text: &str) -> Option<LogLevel> {
        Some(match text.to_ascii_lowercase().as_str() {
            "debug" => LogLevel::Debug,
            "info" => LogLevel::Info,
            "warn" | "warning" => LogLevel::Warn,
            "error" => LogLevel::Error,
            "fatal" => LogLevel::Fatal,
            _ => return None,
        })
    }
}

/// The usage text for `--help`.
pub const USAGE: &str = "\
whycode_node: WhyCode markers from a ROS 2 camera topic to /tf and ~/markers

Usage: whycode_node [--help] [--version] [--ros-args ROS_ARGS... [--]]

ROS arguments (as `ros2 run` and launch files pass them):
  -p, --param NAME:=VALUE     set a parameter (VALUE is YAML: 12, 0.05, true, [1, 2])
  --params-file FILE          parameters from a YAML file (node name: ros__parameters: ...)
  -r, --remap FROM:=TO        remap a topic, e.g. -r image:=/camera/image_raw
  -r __node:=NAME             node name (default whycode)
  -r __ns:=/NAMESPACE         node namespace
  --log-level LEVEL           debug, info, warn, error or fatal
  --disable-rosout-logs       do not publish log lines on /rosout
  --disable-stdout-logs       do not print log lines

Environment: ROS_DOMAIN_ID (default 0); ROS_LOCALHOST_ONLY=1 or
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST keep DDS traffic on the loopback interface.
Parameters and topics: see ros2/README.md.";

impl RosArgs {
    /// Reads the arguments after the program name.
    pub fn parse<I, S>(args: I) -> Result<RosArgs, String>
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        let mut parsed = RosArgs {
            rosout_logs: true,
            stdout_logs: true,
            ..RosArgs::default()
        };
        let mut args = args.into_iter().map(Into::into);
        let mut in_ros = false;
        while let Some(arg) = args.next() {
            if arg == "--ros-args" {
                in_ros = true;
                continue;
            }
            if !in_ros {
                match arg.as_str() {
                    "-h" | "--help" => parsed.help = true,
                    "-V" | "--version" => parsed.version = true,
                    // What follows `--` outside ROS arguments is the
                    // program's; this one takes none.
                    _ => {
                        return Err(format!(
                            "unexpected argument '{arg}' (ROS arguments go after --ros-args)"
                        ))
                    }
                }
                continue;
            }
            let mut value_of =
                |flag: &str| args.next().ok_or_else(|| format!("{flag} needs a value"));
            match arg.as_str() {
                "--" => in_ros = false,
                "-p" | "--param" => {
                    let rule = value_of(&arg)?;
                    let (node, name, value) = split_rule(&rule, &arg)?;
                    let value = parse_value(value).map_err(|e| format!("{arg} {rule}: {e}"))?;
                    check_parameter_name(name).map_err(|e| format!("{arg} {rule}: {e}"))?;
                    parsed.params.push((node, name.to_string(), value));
                }
                "-r" | "--remap" => {
                    let rule = value_of(&arg)?;
                    let (node, from, to) = split_rule(&rule, &arg)?;
                    if to.is_empty() {
                        return Err(format!("{arg} {rule}: nothing after ':='"));
                    }
                    parsed.remaps.push(Remap {
                        node,
                        from: from.to_string(),
                        to: to.to_string(),
                    });
                }
                "--params-file" => parsed.params_files.push(PathBuf::from(value_of(&arg)?)),
                "--log-level" => {
                    let text = value_of(&arg)?;
                    // `name:=level` sets one logger's level; this node has one.
                    let level = text.rsplit(":=").next().unwrap_or(&text);
                    parsed.log_level = Some(LogLevel::parse(level).ok_or_else(|| {
                        format!("--log-level '{text}': not one of debug, info, warn, error, fatal")
                    })?);
                }
                "--enable-rosout-logs" => parsed.rosout_logs = true,
                "--disable-rosout-logs" => parsed.rosout_logs = false,
                "--enable-stdout-logs" => parsed.stdout_logs = true,
                "--disable-stdout-logs" => parsed.stdout_logs = false,
                // Logging to a file or to external libraries: this node
                // logs to stderr and /rosout only; accepted so that launch
                // files written for rclcpp nodes start it.
                "--enable-external-lib-logs" | "--disable-external-lib-logs" => {}
                "--log-config-file" | "--log-file-name" => {
                    value_of(&arg)?;
                }
                "-e" | "--enclave" => {
                    return Err(format!(
                        "{arg}: DDS security enclaves are not supported by this node"
                    ))
                }
                _ => return Err(format!("unknown ROS argument '{arg}'")),
            }
        }
        Ok(parsed)
    }

    /// The node's name and namespace after `__node` and `__ns` rules
    /// (`default_name` in the root namespace without them).
    pub fn node_name(&self, default_name: &str) -> Result<(String, String), String> {
        let mut name = default_name.to_string();
        let mut namespace = "/".to_string();
        // rcl applies the first matching rule of each kind.
        let applies = |r: &Remap| r.node.as_deref().is_none_or(|n| n == default_name);
        if let Some(r) = self
            .remaps
            .iter()
            .find(|r| applies(r) && (r.from == "__node" || r.from == "__name"))
        {
            name = r.to.clone();
        }
        if let Some(r) = self.remaps.iter().find(|r| applies(r) && r.from == "__ns") {
            namespace = r.to.clone();
        }
        if !namespace.starts_with('/') {
            namespace.insert(0, '/');
        }
        if namespace.len() > 1 && namespace.ends_with('/') {
            namespace.pop();
        }
        check_token(&name).map_err(|e| format!("node name '{name}': {e}"))?;
        if namespace != "/" {
            for token in namespace[1..].split('/') {
                check_token(token).map_err(|e| format!("namespace '{namespace}': {e}"))?;
            }
        }
        Ok((name, namespace))
    }

    /// The parameters for the node `node` (fully qualified, e.g.
    /// `/robot/whycode`) of base name `base`: every params file in order,
    /// then the `-p` values, later ones overriding earlier ones, as rclcpp
    /// resolves them.
    pub fn parameters(
        &self,
        node: &str,
        base: &str,
    ) -> Result<Vec<(String, ParameterValue)>, String> {
        let mut values: Vec<(String, ParameterValue)> = Vec::new();
        let mut set = |name: String, value: ParameterValue| {
            values.retain(|(n, _)| *n != name);
            values.push((name, value));
        };
        for path in &self.params_files {
            for (name, value) in read_params_file(path, node)? {
                set(name, value);
            }
        }
        for (target, name, value) in &self.params {
            if target.as_deref().is_none_or(|t| t == base) {
                set(name.clone(), value.clone());
            }
        }
        Ok(values)
    }

    /// The fully qualified topic `name` resolves to for the node `base`
    /// in `namespace`: expanded (`~` is the node's private namespace,
    /// a relative name lies in the node's namespace), then the first
    /// matching remapping rule applied.
    pub fn resolve(&self, name: &str, base: &str, namespace: &str) -> Result<String, String> {
        let expanded = expand(name, base, namespace)?;
        for rule in &self.remaps {
            if rule.from.starts_with("__") || rule.node.as_deref().is_some_and(|n| n != base) {
                continue;
            }
            let from = expand(&rule.from, base, namespace)
                .map_err(|e| format!("remapping rule {}:={}: {e}", rule.from, rule.to))?;
            if from == expanded {
                return expand(&rule.to, base, namespace)
                    .map_err(|e| format!("remapping rule {}:={}: {e}", rule.from, rule.to));
            }
        }
        Ok(expanded)
    }

    /// True when a rule remaps `name` (for this node).
    pub fn remaps_name(&self, name: &str, base: &str, namespace: &str) -> bool {
        let Ok(expanded) = expand(name, base, namespace) else {
            return false;
        };
        self.remaps.iter().any(|rule| {
            !rule.from.starts_with("__")
                && rule.node.as_deref().is_none_or(|n| n == base)
                && expand(&rule.from, base, namespace).is_ok_and(|from| from == expanded)
        })
    }
}

/// Splits `[node:]left:=right`.
fn split_rule<'a>(rule: &'a str, flag: &str) -> Result<(Option<String>, &'a str, &'a str), String> {
    let (left, right) = rule.split_once(":=").ok_or_else(|| {
        let form = if flag.starts_with("-r") || flag == "--remap" {
            "FROM:=TO"
        } else {
            "NAME:=VALUE"
        };
        format!("{flag} '{rule}': write {form}")
    })?;
    // A node prefix is `node:` before a name without colons.
    let (node, left) = match left.split_once(':') {
        Some((node, rest)) if !node.is_empty() && !rest.is_empty() => {
            (Some(node.to_string()), rest)
        }
        _ => (None, left),
    };
    if left.is_empty() {
        return Err(format!("{flag} '{rule}': nothing before ':='"));
    }
    Ok((node, left, right))
}

/// A parameter value written on the command line: YAML, as rcl reads it.
pub fn parse_value(text: &str) -> Result<ParameterValue, String> {
    let yaml: serde_yaml::Value =
        serde_yaml::from_str(text).map_err(|e| format!("'{text}' is not a YAML value: {e}"))?;
    yaml_value(&yaml).map_err(|e| format!("'{text}': {e}"))
}

/// A YAML scalar or list as a parameter value; lists hold one type
/// (integers among doubles are doubles).
fn yaml_value(yaml: &serde_yaml::Value) -> Result<ParameterValue, String> {
    use serde_yaml::Value;
    Ok(match yaml {
        Value::Bool(b) => ParameterValue::Boolean(*b),
        Value::Number(n) => match n.as_i64() {
            Some(i) => ParameterValue::Integer(i),
            None => ParameterValue::Double(n.as_f64().ok_or("number out of range")?),
        },
        Value::String(s) => ParameterValue::String(s.clone()),
        Value::Sequence(items) => {
            if items.iter().all(Value::is_bool) {
                // An empty list is read as an empty list of strings; the
                // node accepts an empty list for any list parameter.
                if items.is_empty() {
                    return Ok(ParameterValue::StringArray(Vec::new()));
                }
                ParameterValue::BooleanArray(items.iter().filter_map(Value::as_bool).collect())
            } else if items.iter().all(Value::is_i64) {
                ParameterValue::IntegerArray(items.iter().filter_map(Value::as_i64).collect())
            } else if items.iter().all(Value::is_number) {
                ParameterValue::DoubleArray(items.iter().filter_map(Value::as_f64).collect())
            } else if items.iter().all(Value::is_string) {
                ParameterValue::StringArray(
                    items
                        .iter()
                        .filter_map(|v| v.as_str().map(str::to_string))
                        .collect(),
                )
            } else {
                return Err("a list must hold values of one type".into());
            }
        }
        Value::Null => return Err("no value".into()),
        Value::Mapping(_) => return Err("a mapping is not a parameter value".into()),
        Value::Tagged(tagged) => yaml_value(&tagged.value)?,
    })
}

/// Parameter names: dot-separated tokens of letters, digits and `_`.
fn check_parameter_name(name: &str) -> Result<(), String> {
    if name
        .split('.')
        .all(|t| !t.is_empty() && t.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
    {
        Ok(())
    } else {
        Err(format!("'{name}' is not a parameter name"))
    }
}

/// One token of a ROS name: letters, digits and `_`, not starting with a
/// digit, no `__`.
fn check_token(token: &str) -> Result<(), String> {
    if token.is_empty() {
        return Err("empty name".into());
    }
    if let Some(bad) = token
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '_'))
    {
        return Err(format!("'{bad}' is not allowed in a name"));
    }
    if token.starts_with(|c: char| c.is_ascii_digit()) {
        return Err("a name must not start with a digit".into());
    }
    if token.contains("__") {
        return Err("a name must not contain '__'".into());
    }
    Ok(())
}

/// The fully qualified form of a topic name.
pub fn expand(name: &str, base: &str, namespace: &str) -> Result<String, String> {
    let ns = namespace.trim_end_matches('/');
    let full = if name == "~" {
        format!("{ns}/{base}")
    } else if let Some(rest) = name.strip_prefix("~/") {
        format!("{ns}/{base}/{rest}")
    } else if name.starts_with('/') {
        name.to_string()
    } else {
        format!("{ns}/{name}")
    };
    if full.ends_with('/') || full.contains("//") {
        return Err(format!("'{name}' is not a valid topic name"));
    }
    for token in full[1..].split('/') {
        check_token(token).map_err(|e| format!("topic '{name}': {e}"))?;
    }
    Ok(full)
}

/// The parameters a params file gives the node `node` (fully qualified).
fn read_params_file(path: &Path, node: &str) -> Result<Vec<(String, ParameterValue)>, String> {
    // A regular file of bounded size: `--params-file /dev/zero` would
    // otherwise grow without end, and a FIFO wait forever.
    let text = whycode::input::read_text(path, whycode::FileKind::Params)
        .map_err(|e| whycode::error::one_line(&e))?;
    params_from_yaml(&text, node).map_err(|e| format!("{}: {e}", path.display()))
}

/// The parameters a params file's text gives the node `node`: every entry
/// whose key matches the node, in file order.
pub fn params_from_yaml(text: &str, node: &str) -> Result<Vec<(String, ParameterValue)>, String> {
    use serde_yaml::Value;
    let yaml: Value = serde_yaml::from_str(text).map_err(|e| format!("not YAML: {e}"))?;
    let Value::Mapping(nodes) = yaml else {
        return Err("a params file maps node names to ros__parameters".into());
    };
    let mut out = Vec::new();
    for (key, entry) in &nodes {
        let key = key.as_str().ok_or("node names must be strings")?;
        if !node_matches(key, node) {
            continue;
        }
        let params = entry
            .get("ros__parameters")
            .ok_or_else(|| format!("'{key}' has no ros__parameters"))?;
        flatten("", params, &mut out).map_err(|e| format!("'{key}': {e}"))?;
    }
    Ok(out)
}

/// Nested mappings become dotted names (`tag: {ids: [1]}` is `tag.ids`).
fn flatten(
    prefix: &str,
    value: &serde_yaml::Value,
    out: &mut Vec<(String, ParameterValue)>,
) -> Result<(), String> {
    let serde_yaml::Value::Mapping(map) = value else {
        return Err(format!("'{prefix}' must be a mapping of parameters"));
    };
    for (key, value) in map {
        let key = match key {
            serde_yaml::Value::String(s) => s.clone(),
            other => serde_yaml::to_string(other)
                .map(|s| s.trim().to_string())
                .map_err(|e| e.to_string())?,
        };
        let name = if prefix.is_empty() {
            key
        } else {
            format!("{prefix}.{key}")
        };
        if value.is_mapping() {
            flatten(&name, value, out)?;
        } else {
            let parsed = yaml_value(value).map_err(|e| format!("{name}: {e}"))?;
            out.retain(|(n, _)| *n != name);
            out.push((name, parsed));
        }
    }
    Ok(())
}

/// Does the params-file key `pattern` name `node` (fully qualified)? `*`
/// stands for one token, `**` for any number; a key without a leading
/// slash is relative to the root.
fn node_matches(pattern: &str, node: &str) -> bool {
    fn tokens(s: &str) -> Vec<&str> {
        s.split('/').filter(|t| !t.is_empty()).collect()
    }
    fn matches(p: &[&str], n: &[&str]) -> bool {
        match p.split_first() {
            None => n.is_empty(),
            Some((&"**", rest)) => (0..=n.len()).any(|skip| matches(rest, &n[skip..])),
            Some((first, rest)) => match n.split_first() {
                Some((token, n_rest)) => (*first == "*" || first == token) && matches(rest, n_rest),
                None => false,
            },
        }
    }
    matches(&tokens(pattern), &tokens(node))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(line: &str) -> Result<RosArgs, String> {
        RosArgs::parse(line.split_whitespace())
    }

    #[test]
    fn parameters_are_yaml_values() {
        let args = parse(
            "--ros-args -p bits:=12 -p diameter:=0.05 -p legacy:=true -p camera_frame:=cam \
             -p tag.ids:=[3,4] -p tag.sizes:=[0.05,1] -p tag.frames:=[a,b] -p name:='12'",
        )
        .unwrap();
        let values: Vec<_> = args
            .params
            .iter()
            .map(|(_, n, v)| (n.as_str(), v))
            .collect();
        assert_eq!(
            values,
            [
                ("bits", &ParameterValue::Integer(12)),
                ("diameter", &ParameterValue::Double(0.05)),
                ("legacy", &ParameterValue::Boolean(true)),
                ("camera_frame", &ParameterValue::String("cam".into())),
                ("tag.ids", &ParameterValue::IntegerArray(vec![3, 4])),
                ("tag.sizes", &ParameterValue::DoubleArray(vec![0.05, 1.0])),
                (
                    "tag.frames",
                    &ParameterValue::StringArray(vec!["a".into(), "b".into()])
                ),
                ("name", &ParameterValue::String("12".into())),
            ]
        );
    }

    #[test]
    fn values_as_launch_ros_writes_them_are_read() {
        // launch_ros passes a Parameter action as `-p name:=<yaml.dump(value)>`,
        // which ends a scalar with a document end marker and writes lists in
        // block style.
        assert_eq!(
            parse_value("0.05\n...\n").unwrap(),
            ParameterValue::Double(0.05)
        );
        assert_eq!(
            parse_value("raw\n...\n").unwrap(),
            ParameterValue::String("raw".into())
        );
        assert_eq!(
            parse_value("- 1\n- 2\n").unwrap(),
            ParameterValue::IntegerArray(vec![1, 2])
        );
        assert_eq!(parse_value("true").unwrap(), ParameterValue::Boolean(true));
    }

    #[test]
    fn bad_arguments_are_refused_with_a_reason() {
        for (line, needle) in [
            ("--ros-args -p bits", "NAME:=VALUE"),
            ("--ros-args -p :=3", "nothing before"),
            ("--ros-args -p bits:=", "no value"),
            ("--ros-args -p bits:=[1,a]", "one type"),
            ("--ros-args -p", "needs a value"),
            ("--ros-args -r image", "FROM:=TO"),
            ("--ros-args --log-level loud", "debug, info"),
            ("--ros-args --frobnicate", "unknown ROS argument"),
            ("--ros-args --enclave /x", "not supported"),
            ("-p bits:=3", "after --ros-args"),
        ] {
            let err = parse(line).unwrap_err();
            assert!(err.contains(needle), "{line}: {err}");
        }
    }

    #[test]
    fn ros_sections_end_at_double_dash_and_may_repeat() {
        let args = parse("--ros-args -p a:=1 -- --help --ros-args -r x:=y").unwrap();
        assert!(args.help);
        assert_eq!(args.params.len(), 1);
        assert_eq!(args.remaps.len(), 1);
        assert!(args.rosout_logs && args.stdout_logs);
        let args = parse("--ros-args --disable-rosout-logs --log-level warn").unwrap();
        assert!(!args.rosout_logs);
        assert_eq!(args.log_level, Some(LogLevel::Warn));
        let args = parse("--ros-args --log-level whycode:=debug").unwrap();
        assert_eq!(args.log_level, Some(LogLevel::Debug));
    }

    #[test]
    fn node_name_and_namespace_come_from_remapping() {
        let (name, ns) = parse("").unwrap().node_name("whycode").unwrap();
        assert_eq!((name.as_str(), ns.as_str()), ("whycode", "/"));
        let args = parse("--ros-args -r __node:=left -r __ns:=/robot/eyes").unwrap();
        assert_eq!(
            args.node_name("whycode").unwrap(),
            ("left".into(), "/robot/eyes".into())
        );
        // A rule for another node does not apply.
        let args = parse("--ros-args -r other:__node:=x -r whycode:__ns:=ns").unwrap();
        assert_eq!(
            args.node_name("whycode").unwrap(),
            ("whycode".into(), "/ns".into())
        );
        assert!(parse("--ros-args -r __node:=9lives")
            .unwrap()
            .node_name("whycode")
            .is_err());
        assert!(parse("--ros-args -r __ns:=/a//b")
            .unwrap()
            .node_name("whycode")
            .is_err());
    }

    #[test]
    fn topics_resolve_through_the_first_matching_rule() {
        let args = parse(
            "--ros-args -r image:=/cam/image_raw -r ~/markers:=found -r other:camera_info:=/x \
             -r image:=/never",
        )
        .unwrap();
        let r = |name| args.resolve(name, "whycode", "/robot").unwrap();
        assert_eq!(r("image"), "/cam/image_raw");
        assert_eq!(r("~/markers"), "/robot/found");
        assert_eq!(r("camera_info"), "/robot/camera_info");
        assert_eq!(r("/tf"), "/tf");
        assert_eq!(r("~/debug_image"), "/robot/whycode/debug_image");
        assert!(args.remaps_name("image", "whycode", "/robot"));
        assert!(!args.remaps_name("camera_info", "whycode", "/robot"));
        // In the root namespace, the rules match the names there.
        assert_eq!(
            args.resolve("image", "whycode", "/").unwrap(),
            "/cam/image_raw"
        );
        assert_eq!(args.resolve("~/markers", "whycode", "/").unwrap(), "/found");
        let plain = parse("").unwrap();
        assert_eq!(plain.resolve("image", "whycode", "/").unwrap(), "/image");
        assert_eq!(
            plain.resolve("~/markers", "whycode", "/").unwrap(),
            "/whycode/markers"
        );
        assert!(args.resolve("bad name", "whycode", "/").is_err());
        assert!(args.resolve("a//b", "whycode", "/").is_err());
    }

    #[test]
    fn params_files_match_node_names_with_wildcards() {
        let text = "
/**:
  ros__parameters:
    use_sim_time: false
    diameter: 0.1
whycode:
  ros__parameters:
    bits: 12
    tag:
      ids: [1, 2]
      frames: [left, right]
/robot/whycode:
  ros__parameters:
    diameter: 0.05
/*/other:
  ros__parameters:
    bits: 4
";
        let root = params_from_yaml(text, "/whycode").unwrap();
        assert_eq!(
            root,
            [
                ("use_sim_time".to_string(), ParameterValue::Boolean(false)),
                ("diameter".to_string(), ParameterValue::Double(0.1)),
                ("bits".to_string(), ParameterValue::Integer(12)),
                (
                    "tag.ids".to_string(),
                    ParameterValue::IntegerArray(vec![1, 2])
                ),
                (
                    "tag.frames".to_string(),
                    ParameterValue::StringArray(vec!["left".into(), "right".into()])
                ),
            ]
        );
        let robot = params_from_yaml(text, "/robot/whycode").unwrap();
        assert_eq!(
            robot,
            [
                ("use_sim_time".to_string(), ParameterValue::Boolean(false)),
                ("diameter".to_string(), ParameterValue::Double(0.05)),
            ]
        );
        assert!(params_from_yaml("whycode: {}", "/whycode").is_err());
        assert!(params_from_yaml("[1, 2]", "/whycode").is_err());
        assert!(node_matches("/**/whycode", "/a/b/whycode"));
        assert!(node_matches("/**", "/whycode"));
        assert!(!node_matches("/*/whycode", "/whycode"));
    }

    /// The launch files load whycode.params.yaml: launching without
    /// arguments must behave as the node with no parameters.
    #[test]
    fn the_shipped_params_file_holds_the_node_defaults() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("launch/whycode.params.yaml");
        let text = std::fs::read_to_string(&path).unwrap();
        let params = params_from_yaml(&text, "/robot/whycode_left").unwrap();
        let names: Vec<&str> = params.iter().map(|(n, _)| n.as_str()).collect();
        assert!(
            names.contains(&"bits") && names.contains(&"diameter"),
            "{names:?}"
        );
        let settings = crate::params::Settings::from_parameters(&params).unwrap();
        assert_eq!(settings, crate::params::Settings::default());
    }

    #[test]
    fn the_example_params_file_names_and_sizes_markers() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("launch/example.params.yaml");
        let text = std::fs::read_to_string(&path).unwrap();
        let params = params_from_yaml(&text, "/whycode").unwrap();
        let settings = crate::params::Settings::from_parameters(&params).unwrap();
        crate::params::detector_config(&settings, None).unwrap();
        assert_eq!(settings.tag(2), ("charger".into(), Some(0.1)));
        assert_eq!(settings.tag(3), ("whycode_3".into(), Some(0.05)));
    }

    #[test]
    fn command_line_values_override_params_files_for_this_node_only() {
        let dir = std::env::temp_dir().join(format!("whycode-ros2-args-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("p.yaml");
        std::fs::write(
            &file,
            "whycode:\n  ros__parameters:\n    bits: 12\n    distance: 3\n",
        )
        .unwrap();
        let line = format!(
            "--ros-args -p bits:=6 --params-file {} -p other:distance:=5",
            file.display()
        );
        let params = parse(&line)
            .unwrap()
            .parameters("/whycode", "whycode")
            .unwrap();
        assert_eq!(
            params,
            [
                ("distance".to_string(), ParameterValue::Integer(3)),
                ("bits".to_string(), ParameterValue::Integer(6)),
            ]
        );
        let missing = parse("--ros-args --params-file /nonexistent/p.yaml")
            .unwrap()
            .parameters("/whycode", "whycode")
            .unwrap_err();
        assert!(missing.contains("/nonexistent/p.yaml"), "{missing}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
