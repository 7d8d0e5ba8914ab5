//! What the typed errors share.

/// An error's causes joined with ": " on one line, as the command line
/// prints an error chain (a cause its parent already quotes is left out).
/// Typed errors use it to carry the text of a parse that failed deep inside.
pub(crate) fn chain_on_one_line(err: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if text.is_empty() || parts.last().is_some_and(|p| p.contains(&text)) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}
