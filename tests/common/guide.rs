//! The guide's Markdown files, shared by `tests/doc_links.rs` and `tests/doc_errors.rs`.

use pulldown_cmark::Options;
use std::path::{Path, PathBuf};

/// The repository's root (this package is the workspace root).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// GitHub-flavoured Markdown's extensions that change where links, headings and code are.
pub fn options() -> Options {
    Options::ENABLE_TABLES
        | Options::ENABLE_FOOTNOTES
        | Options::ENABLE_STRIKETHROUGH
        | Options::ENABLE_TASKLISTS
        | Options::ENABLE_HEADING_ATTRIBUTES
}

/// Every Markdown file under `dir` (relative to `root`), sorted.
fn markdown_under(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(root.join(dir))
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").file_name())
        .collect();
    entries.sort();
    for name in entries {
        let rel = dir.join(&name);
        if root.join(&rel).is_dir() {
            markdown_under(root, &rel, out);
        } else if rel.extension().is_some_and(|e| e == "md") {
            out.push(rel);
        }
    }
}

/// The files of the guide, relative to the root: README.md, CONTRIBUTING.md, docs/**/*.md, and
/// the folders' READMEs that the guide links to. Each must exist.
pub fn files() -> Vec<PathBuf> {
    let root = root();
    let mut files: Vec<PathBuf> = ["README.md", "CONTRIBUTING.md"]
        .iter()
        .map(PathBuf::from)
        .collect();
    markdown_under(&root, Path::new("docs"), &mut files);
    for readme in [
        "emu/core/README.md",
        "emu/tests/programs/README.md",
        "firmware/README.md",
        "eeprom/README.md",
        "scripts/kilombo/README.md",
    ] {
        files.push(PathBuf::from(readme));
    }
    for f in &files {
        assert!(root.join(f).is_file(), "{} is missing", f.display());
    }
    files
}
