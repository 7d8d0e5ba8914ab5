//! Error text shared by every front end.

/// An error's causes joined with ": " on one line, white space folded, a
/// cause its parent already quotes (image decoding errors do) left out.
/// This is the line the command line prints after `whycode: error:`, the
/// message of a Python `WhycodeError` and of the browser page's errors, and
/// the text typed errors carry for a parse that failed deep inside.
pub fn one_line(err: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in err.chain() {
        let text = shorten_words(
            &cause
                .to_string()
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" "),
        );
        if text.is_empty() || parts.last().is_some_and(|p| p.contains(&text)) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}

/// The longest run without white space an error quotes whole: a 50 MB string
/// in a family file is shown by its ends, not echoed to the terminal.
const MAX_QUOTED: usize = 100;

/// `text` with every run of more than [`MAX_QUOTED`] characters between
/// spaces cut to its first and last few, and how long it was.
pub fn shorten_words(text: &str) -> String {
    text.split(' ')
        .map(|word| {
            let count = word.chars().count();
            if count <= MAX_QUOTED {
                return word.to_string();
            }
            let head: String = word.chars().take(MAX_QUOTED / 2).collect();
            let tail: String = word.chars().skip(count - 20).collect();
            format!("{head}...{tail} ({count} characters)")
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_huge_quoted_value_is_cut_to_its_ends() {
        let huge = "x".repeat(50_000_000);
        let err = anyhow::anyhow!("invalid type: string \"{huge}\", expected u32");
        let line = super::one_line(&err.context("fam.json"));
        assert!(line.len() < 300, "{}", line.len());
        assert!(
            line.starts_with("fam.json: invalid type: string \"xxxx"),
            "{line}"
        );
        assert!(line.ends_with("characters) expected u32"), "{line}");
    }
}
