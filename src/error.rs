//! Error text shared by every front end.

/// An error's causes joined with ": " on one line, white space folded, a
/// cause its parent already quotes (image decoding errors do) left out.
/// This is the line the command line prints after `whycode: error:`, the
/// message of a Python `WhycodeError` and of the browser page's errors, and
/// the text typed errors carry for a parse that failed deep inside.
pub fn one_line(err: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in err.chain() {
        let text = cause
            .to_string()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        if text.is_empty() || parts.last().is_some_and(|p| p.contains(&text)) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}
