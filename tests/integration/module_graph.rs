//! The library's modules form layers: each top-level module of `src/` may
//! use the ones below it and never one above, so no two modules import each
//! other, directly or around a loop. The graph is read from the source
//! (`crate::module` paths outside comments, strings and test code), so a new
//! `use` that closes a loop fails here with the loop and the files that make
//! it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// One source file: its path under `src/` and its text.
struct Source {
    path: PathBuf,
    text: String,
}

fn read_sources(dir: &Path, root: &Path, out: &mut Vec<Source>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            read_sources(&path, root, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path).unwrap();
            let path = path.strip_prefix(root).unwrap().to_path_buf();
            out.push(Source { path, text });
        }
    }
}

/// The text with comments removed and string and character literals
/// emptied, so braces and paths inside them are not read as code.
fn code_only(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut k = 0;
    while k < chars.len() {
        let c = chars[k];
        let next = chars.get(k + 1).copied();
        if c == '/' && next == Some('/') {
            while k < chars.len() && chars[k] != '\n' {
                k += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while k < chars.len() {
                if chars[k] == '/' && chars.get(k + 1) == Some(&'*') {
                    depth += 1;
                    k += 2;
                } else if chars[k] == '*' && chars.get(k + 1) == Some(&'/') {
                    depth -= 1;
                    k += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    k += 1;
                }
            }
        } else if c == 'r' && (next == Some('"') || next == Some('#')) && !ident_before(&chars, k) {
            // A raw string: r"…" or r#"…"#.
            let mut hashes = 0;
            let mut j = k + 1;
            while chars.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if chars.get(j) != Some(&'"') {
                out.push(c);
                k += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= chars.len() {
                    break;
                }
                if chars[j] == '"' && (0..hashes).all(|h| chars.get(j + 1 + h) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            out.push_str("\"\"");
            k = j;
        } else if c == '"' {
            k += 1;
            while k < chars.len() && chars[k] != '"' {
                k += if chars[k] == '\\' { 2 } else { 1 };
            }
            k += 1;
            out.push_str("\"\"");
        } else if c == '\'' {
            // A character literal ('x', '\n', '\u{7f}'), not a lifetime.
            let close = if next == Some('\\') {
                (k + 2..chars.len().min(k + 12)).find(|&j| chars[j] == '\'')
            } else if chars.get(k + 2) == Some(&'\'') {
                Some(k + 2)
            } else {
                None
            };
            match close {
                Some(j) => {
                    out.push_str("' '");
                    k = j + 1;
                }
                None => {
                    out.push(c);
                    k += 1;
                }
            }
        } else {
            out.push(c);
            k += 1;
        }
    }
    out
}

fn ident_before(chars: &[char], k: usize) -> bool {
    k > 0 && (chars[k - 1].is_alphanumeric() || chars[k - 1] == '_')
}

/// The code with every `#[cfg(test)]` item cut out; the names of test
/// modules declared in other files (`#[cfg(test)] mod name;`) go to
/// `test_files`.
fn without_tests(code: &str, test_files: &mut Vec<String>) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let item = &rest[at + "#[cfg(test)]".len()..];
        let brace = item.find('{');
        let semi = item.find(';');
        let end = match (brace, semi) {
            (_, Some(s)) if brace.is_none_or(|b| s < b) => {
                let decl = item[..s].trim();
                if let Some(name) = decl.split_whitespace().last() {
                    if decl.split_whitespace().any(|w| w == "mod") {
                        test_files.push(name.to_string());
                    }
                }
                s + 1
            }
            (Some(b), _) => {
                let mut depth = 0;
                let mut end = item.len();
                for (j, ch) in item[b..].char_indices() {
                    match ch {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = b + j + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                end
            }
            _ => item.len(),
        };
        rest = &item[end..];
    }
    out.push_str(rest);
    out
}

/// The top-level modules each `crate::` path of `code` names, first
/// segments only (`crate::{a::X, b}` names `a` and `b`).
fn crate_paths(code: &str) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let boundary = rest[..at]
            .chars()
            .next_back()
            .is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        rest = &rest[at + "crate::".len()..];
        if !boundary {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            // The group's items, split at the commas of its own level.
            let mut depth = 0;
            let mut items = vec![String::new()];
            for ch in group.chars() {
                match ch {
                    '}' if depth == 0 => break,
                    ',' if depth == 0 => items.push(String::new()),
                    _ => {
                        depth += i32::from(ch == '{') - i32::from(ch == '}');
                        items.last_mut().unwrap().push(ch);
                    }
                }
            }
            for item in items {
                names.insert(leading_name(item.trim_start()));
            }
        } else {
            names.insert(leading_name(rest));
        }
    }
    names.remove("");
    names
}

fn leading_name(text: &str) -> String {
    text.chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// The top-level module a file under `src/` belongs to (`None` for the
/// crate roots).
fn module_of(path: &Path) -> Option<String> {
    let first = path.components().next()?.as_os_str().to_str()?;
    match first {
        "lib.rs" | "main.rs" => None,
        name => Some(name.trim_end_matches(".rs").to_string()),
    }
}

/// Module → the modules it uses → the files that use them.
type Graph = BTreeMap<String, BTreeMap<String, BTreeSet<PathBuf>>>;

fn graph(sources: &[Source]) -> Graph {
    let modules: BTreeSet<String> = sources.iter().filter_map(|s| module_of(&s.path)).collect();
    let mut test_files = Vec::new();
    let cleaned: Vec<String> = sources
        .iter()
        .map(|s| without_tests(&code_only(&s.text), &mut test_files))
        .collect();
    let mut graph = Graph::new();
    for (source, code) in sources.iter().zip(&cleaned) {
        let Some(from) = module_of(&source.path) else {
            continue;
        };
        let stem = source
            .path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("");
        if test_files.iter().any(|t| t == stem) {
            continue;
        }
        let uses = graph.entry(from.clone()).or_default();
        for to in crate_paths(code) {
            if to != from && modules.contains(&to) {
                uses.entry(to).or_default().insert(source.path.clone());
            }
        }
    }
    graph
}

/// A loop of modules, if there is one: `[a, b, c]` for a → b → c → a.
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &Graph,
        done: &mut BTreeSet<String>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        if let Some(k) = path.iter().position(|p| p == node) {
            return Some(path[k..].to_vec());
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flat_map(|uses| uses.keys()) {
            if let Some(cycle) = visit(next, graph, done, path) {
                return Some(cycle);
            }
        }
        path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|node| visit(node, graph, &mut done, &mut Vec::new()))
}

fn describe(cycle: &[String], graph: &Graph) -> String {
    let mut lines = vec![format!("{} → {}", cycle.join(" → "), cycle[0])];
    for (k, from) in cycle.iter().enumerate() {
        let to = &cycle[(k + 1) % cycle.len()];
        let files: Vec<String> = graph[from][to]
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        lines.push(format!("  {from} → {to}: {}", files.join(", ")));
    }
    lines.join("\n")
}

fn library_sources() -> Vec<Source> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut sources = Vec::new();
    read_sources(&root, &root, &mut sources);
    sources
}

#[test]
fn the_modules_form_layers_without_a_loop() {
    let sources = library_sources();
    let graph = graph(&sources);
    // The reader must see the edges that exist, or an empty graph passes.
    assert!(graph["detect"].contains_key("family"), "{graph:?}");
    assert!(graph["session"].contains_key("detect"));
    assert!(graph["spec"].contains_key("session"));
    if let Some(cycle) = find_cycle(&graph) {
        panic!(
            "the modules import each other around a loop:\n{}",
            describe(&cycle, &graph)
        );
    }
}

#[test]
fn a_use_that_closes_a_loop_is_found() {
    let mut sources = library_sources();
    let limits = sources
        .iter_mut()
        .find(|s| s.path == Path::new("limits.rs"))
        .expect("src/limits.rs");
    limits
        .text
        .push_str("\nuse crate::{units, spec::SpecError};\n");
    let graph = graph(&sources);
    let cycle = find_cycle(&graph).expect("limits → spec → limits is a loop");
    assert!(cycle.contains(&"limits".to_string()) && cycle.contains(&"spec".to_string()));
    assert!(describe(&cycle, &graph).contains("limits.rs"));
}

#[test]
fn tests_comments_and_strings_make_no_edges() {
    let text = r##"
        use crate::units::Mm; // crate::detect in a comment
        /* crate::render */
        const A: &str = "crate::simulate";
        const B: &str = r#"crate::session"#;
        fn f<'a>(x: &'a str) -> char { let _ = crate::{geometry::X, math}; '{' }
        #[cfg(test)]
        mod tests {
            use crate::spec::SpecError;
            fn g() { let _ = "}"; }
        }
        #[cfg(test)]
        mod test_images;
        fn after() { crate::pose::f(); }
    "##;
    let mut test_files = Vec::new();
    let code = without_tests(&code_only(text), &mut test_files);
    let names: Vec<String> = crate_paths(&code).into_iter().collect();
    assert_eq!(names, ["geometry", "math", "pose", "units"]);
    assert_eq!(test_files, ["test_images"]);
}
