//! The code's layout, checked against what the documents say of it: `docs/design.md`'s
//! module table names every module of the library with exactly the modules it imports, in
//! an order where each uses only those above it (no cycle, no import from a higher floor);
//! the binary's command modules import each other without a cycle; the deep engine's module
//! doc maps every file under `src/orbit`; no source file grows past 900 lines; and the
//! library reports errors as types (no `Result<_, String>` outside the command line and the
//! viewer).
//!
//! Imports are read from the text: `crate::NAME` (and `crate::{A, B}`) in a module's files,
//! leaving out test code (files named `tests.rs` and inline `#[cfg(test)] mod tests { .. }` blocks) and
//! comments.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `dir` (sorted).
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = vec![];
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A file's code without its unit tests and comments.
fn code(path: &Path) -> String {
    if path.file_name().is_some_and(|n| n == "tests.rs") {
        return String::new();
    }
    let text = std::fs::read_to_string(path).unwrap();
    let text = match text.find("#[cfg(test)]\nmod tests {") {
        Some(i) => &text[..i],
        None => &text[..],
    };
    text.lines().map(|l| l.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n")
}

/// The names that follow `prefix` in `text` (`prefix` then an identifier, or a braced list
/// of them).
fn names_after(text: &str, prefix: &str) -> BTreeSet<String> {
    let ident = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
    let mut out = BTreeSet::new();
    for (i, _) in text.match_indices(prefix) {
        let before = text[..i].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let rest = &text[i + prefix.len()..];
        if let Some(list) = rest.strip_prefix('{') {
            let list = &list[..list.find('}').unwrap_or(list.len())];
            out.extend(list.split(',').map(|s| ident(s.trim())).filter(|s| !s.is_empty()));
        } else {
            out.insert(ident(rest));
        }
    }
    out
}

/// The library's top-level modules, from `src/lib.rs`.
fn library_modules() -> Vec<String> {
    let lib = std::fs::read_to_string(root().join("src/lib.rs")).unwrap();
    lib.lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod ").or_else(|| l.trim().strip_prefix("mod ")))
        .map(|l| l.trim_end_matches(';').to_string())
        .collect()
}

/// The files of top-level module `m` (a file or a folder).
fn module_files(m: &str) -> Vec<PathBuf> {
    let dir = root().join("src").join(m);
    if dir.is_dir() { rust_files(&dir) } else { vec![root().join(format!("src/{m}.rs"))] }
}

/// The library modules each top-level module imports, read from the code.
fn imports() -> BTreeMap<String, BTreeSet<String>> {
    let modules = library_modules();
    let mut out = BTreeMap::new();
    for m in &modules {
        let mut uses = BTreeSet::new();
        for f in module_files(m) {
            uses.extend(names_after(&code(&f), "crate::").into_iter().filter(|u| u != m && modules.contains(u)));
        }
        out.insert(m.clone(), uses);
    }
    let mut cli = BTreeSet::new();
    for f in rust_files(&root().join("src/cli")).into_iter().chain([root().join("src/main.rs")]) {
        cli.extend(names_after(&code(&f), "deepfield::").into_iter().filter(|u| modules.contains(u)));
    }
    out.insert("cli".to_string(), cli);
    out
}

/// `docs/design.md`'s module table: (modules of the row, the modules they use), in order.
fn design_table() -> Vec<(Vec<String>, BTreeSet<String>)> {
    let text = std::fs::read_to_string(root().join("docs/design.md")).unwrap();
    let start = text.find("| module | holds | uses |").expect("design.md has the module table");
    let ticked = |cell: &str| -> Vec<String> {
        cell.split('`').skip(1).step_by(2).map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect()
    };
    text[start..]
        .lines()
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            assert_eq!(cells.len(), 5, "a row of module | holds | uses: {l}");
            let uses = if cells[3] == "std" { BTreeSet::new() } else { ticked(cells[3]).into_iter().collect() };
            (ticked(cells[1]), uses)
        })
        .collect()
}

#[test]
fn the_design_documents_module_table_is_the_codes() {
    let actual = imports();
    let table = design_table();
    let mut listed = BTreeSet::new();
    let mut above: BTreeSet<String> = BTreeSet::new();
    let mut wrong = vec![];
    for (row, uses) in &table {
        let mut used = BTreeSet::new();
        for m in row {
            listed.insert(m.clone());
            match actual.get(m) {
                Some(a) => used.extend(a.iter().cloned()),
                None => wrong.push(format!("`{m}` is in the table but is no module of the crate")),
            }
        }
        let used: BTreeSet<String> = used.into_iter().filter(|u| !row.contains(u)).collect();
        if &used != uses {
            wrong.push(format!("{row:?}: the table says it uses {uses:?}, the code uses {used:?}"));
        }
        let higher: Vec<&String> = used.iter().filter(|u| !above.contains(*u)).collect();
        if !higher.is_empty() {
            wrong.push(format!("{row:?} uses {higher:?}, which the table lists later (a higher floor, or a cycle)"));
        }
        above.extend(row.iter().cloned());
    }
    for m in actual.keys() {
        if !listed.contains(m) {
            wrong.push(format!("`{m}` is missing from the table"));
        }
    }
    assert!(wrong.is_empty(), "docs/design.md's module table disagrees with the code:\n{}", wrong.join("\n"));
}

#[test]
fn the_command_modules_import_each_other_without_a_cycle() {
    let dir = root().join("src/cli");
    let names: BTreeSet<String> =
        rust_files(&dir).iter().map(|f| f.file_stem().unwrap().to_string_lossy().into_owned()).collect();
    let graph: BTreeMap<String, BTreeSet<String>> = rust_files(&dir)
        .iter()
        .map(|f| {
            let me = f.file_stem().unwrap().to_string_lossy().into_owned();
            let uses = names_after(&code(f), "super::").into_iter().filter(|u| names.contains(u) && *u != me).collect();
            (me, uses)
        })
        .collect();
    // Depth-first search for a back edge.
    fn visit(
        n: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(n) {
            Some(2) => return None,
            Some(1) => {
                let at = path.iter().position(|p| p == n).unwrap();
                return Some(path[at..].iter().cloned().chain([n.to_string()]).collect());
            }
            _ => {}
        }
        state.insert(n.to_string(), 1);
        path.push(n.to_string());
        for m in g.get(n).into_iter().flatten() {
            if let Some(cycle) = visit(m, g, state, path) {
                return Some(cycle);
            }
        }
        path.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in graph.keys() {
        if let Some(cycle) = visit(n, &graph, &mut state, &mut vec![]) {
            panic!("src/cli imports in a cycle: {}", cycle.join(" -> "));
        }
    }
}

#[test]
fn the_deep_engines_module_doc_maps_every_file() {
    let dir = root().join("src/orbit");
    let doc: String = std::fs::read_to_string(dir.join("mod.rs"))
        .unwrap()
        .lines()
        .take_while(|l| l.starts_with("//!") || l.is_empty())
        .collect::<Vec<_>>()
        .join("\n");
    let missing: Vec<String> = rust_files(&dir)
        .iter()
        .map(|f| f.strip_prefix(&dir).unwrap().to_string_lossy().replace('\\', "/"))
        .filter(|rel| !doc.contains(&format!("`{rel}`")))
        .collect();
    assert!(missing.is_empty(), "src/orbit/mod.rs's module doc does not name {missing:?}");
}

#[test]
fn no_source_file_is_longer_than_900_lines() {
    let long: Vec<String> = rust_files(&root().join("src"))
        .iter()
        .map(|f| (f, std::fs::read_to_string(f).unwrap().lines().count()))
        .filter(|(_, n)| *n > 900)
        .map(|(f, n)| format!("{} ({n} lines)", f.strip_prefix(root()).unwrap().display()))
        .collect();
    assert!(long.is_empty(), "split these by concept: {long:?}");
}

#[test]
fn the_library_reports_errors_as_types() {
    let src = root().join("src");
    let mut found = vec![];
    for f in rust_files(&src) {
        let rel = f.strip_prefix(&src).unwrap().to_string_lossy().replace('\\', "/");
        if rel.starts_with("cli/") || rel.starts_with("viewer/") || rel == "main.rs" {
            continue;
        }
        for (k, line) in code(&f).lines().enumerate() {
            let squeezed: String = line.split_whitespace().collect();
            if squeezed.contains("Result<") && squeezed.contains(",String>") {
                found.push(format!("src/{rel}:{}: {}", k + 1, line.trim()));
            }
        }
    }
    assert!(found.is_empty(), "string errors in the library:\n{}", found.join("\n"));
}
