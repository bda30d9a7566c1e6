//! The guide's links, checked offline: every relative link in README.md, CONTRIBUTING.md and
//! docs/**/*.md (and in the other README.md files of the repository) names a file or folder
//! inside the repository, and every `#anchor` names a heading of the target Markdown file
//! (GitHub's slug) or an explicit id (`<a id="…">`, `{#id}`). http(s) and mailto links are not
//! fetched. The Markdown is parsed with `pulldown-cmark`, so links in code are not links and
//! reference-style links count.

#[path = "common/guide.rs"]
mod guide;

use guide::{options, root};
use pulldown_cmark::{Event, Parser, Tag, TagEnd};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Component, Path, PathBuf};

/// GitHub's anchor for a heading's text: lower case; letters, digits, `-` and `_` kept, spaces
/// to `-`, everything else dropped. (Duplicates are numbered by [`anchors`].)
fn slug(text: &str) -> String {
    let mut out = String::new();
    for c in text.trim().chars() {
        if c == ' ' {
            out.push('-');
        } else if c.is_alphanumeric() || c == '-' || c == '_' {
            out.extend(c.to_lowercase());
        }
    }
    out
}

/// The value of `id="…"` or `name="…"` in one HTML tag's text, if it has one.
fn html_ids(html: &str) -> Vec<String> {
    let mut ids = Vec::new();
    for attr in ["id=", "name="] {
        let mut rest = html;
        while let Some(at) = rest.find(attr) {
            let before = rest[..at].chars().last();
            rest = &rest[at + attr.len()..];
            if !matches!(before, Some(c) if c.is_whitespace()) {
                continue;
            }
            let Some(quote) = rest.chars().next().filter(|q| *q == '"' || *q == '\'') else {
                continue;
            };
            if let Some(end) = rest[1..].find(quote) {
                ids.push(rest[1..1 + end].to_string());
            }
        }
    }
    ids
}

/// One link found in a Markdown file: its destination and the line it is on.
struct Link {
    dest: String,
    line: usize,
}

/// Every anchor a Markdown text defines (headings' slugs, numbered as GitHub numbers
/// duplicates, and explicit ids) and every link and image it holds.
fn scan(text: &str) -> (BTreeSet<String>, Vec<Link>) {
    let mut anchors = BTreeSet::new();
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut links = Vec::new();
    let mut heading: Option<(String, Option<String>)> = None;
    let line_of = |offset: usize| text[..offset].matches('\n').count() + 1;
    for (event, range) in Parser::new_ext(text, options()).into_offset_iter() {
        match event {
            Event::Start(Tag::Heading { id, .. }) => {
                heading = Some((String::new(), id.map(|i| i.to_string())));
            }
            Event::End(TagEnd::Heading(_)) => {
                if let Some((words, id)) = heading.take() {
                    if let Some(id) = id {
                        anchors.insert(id);
                    } else {
                        let base = slug(&words);
                        let n = seen.entry(base.clone()).or_insert(0);
                        let anchor = if *n == 0 {
                            base.clone()
                        } else {
                            format!("{base}-{n}")
                        };
                        *n += 1;
                        anchors.insert(anchor);
                    }
                }
            }
            Event::Text(t) | Event::Code(t) => {
                if let Some((words, _)) = heading.as_mut() {
                    words.push_str(&t);
                }
            }
            Event::Html(h) | Event::InlineHtml(h) => anchors.extend(html_ids(&h)),
            Event::Start(Tag::Link { dest_url, .. })
            | Event::Start(Tag::Image { dest_url, .. }) => {
                links.push(Link {
                    dest: dest_url.to_string(),
                    line: line_of(range.start),
                });
            }
            _ => {}
        }
    }
    (anchors, links)
}

/// `%xx` escapes decoded (a link to `a%20b.md` names `a b.md`).
fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok());
        if bytes[i] == b'%'
            && let Some(b) = hex.and_then(|h| u8::from_str_radix(h, 16).ok())
        {
            out.push(b);
            i += 3;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// `a/./b/../c` as `a/c`, without touching the file system; `None` when it climbs above `/`.
fn normalise(path: &Path) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            other => out.push(other),
        }
    }
    Some(out)
}

/// The broken links of the Markdown files `files` (paths relative to `root`), one line each:
/// `file:line: link: what is wrong`.
fn broken_links(root: &Path, files: &[PathBuf]) -> Vec<String> {
    let mut scanned: BTreeMap<PathBuf, (BTreeSet<String>, Vec<Link>)> = BTreeMap::new();
    let mut problems = Vec::new();
    let mut anchors_of = |path: &Path| -> Option<BTreeSet<String>> {
        if !scanned.contains_key(path) {
            let text = std::fs::read_to_string(root.join(path)).ok()?;
            scanned.insert(path.to_path_buf(), scan(&text));
        }
        scanned.get(path).map(|(a, _)| a.clone())
    };
    for file in files {
        let text = std::fs::read_to_string(root.join(file))
            .unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let (own, links) = scan(&text);
        for link in links {
            let at = format!("{}:{}: ({})", file.display(), link.line, link.dest);
            let dest = link.dest.as_str();
            if dest.starts_with("http://")
                || dest.starts_with("https://")
                || dest.starts_with("mailto:")
            {
                continue;
            }
            if let Some(colon) = dest.find(':')
                && dest[..colon]
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '+')
            {
                problems.push(format!("{at}: a scheme the check does not know"));
                continue;
            }
            let (path_part, anchor) = match dest.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (dest, None),
            };
            let path_part = percent_decode(path_part);
            let target = if path_part.is_empty() {
                file.clone()
            } else {
                let joined = if let Some(from_root) = path_part.strip_prefix('/') {
                    PathBuf::from(from_root)
                } else {
                    file.parent().unwrap_or(Path::new("")).join(&path_part)
                };
                match normalise(&joined) {
                    Some(t) => t,
                    None => {
                        problems.push(format!("{at}: points outside the repository"));
                        continue;
                    }
                }
            };
            if target.as_os_str().is_empty() {
                problems.push(format!("{at}: points at the repository's root, not a file"));
                continue;
            }
            let on_disk = root.join(&target);
            if !on_disk.exists() {
                problems.push(format!("{at}: no file {}", target.display()));
                continue;
            }
            let Some(anchor) = anchor else { continue };
            let anchor = percent_decode(anchor);
            if target.extension().is_some_and(|e| e == "md") {
                let known = if target == *file {
                    Some(own.clone())
                } else {
                    anchors_of(&target)
                };
                match known {
                    Some(set) if set.contains(&anchor) => {}
                    Some(_) => problems.push(format!(
                        "{at}: no heading or id #{anchor} in {}",
                        target.display()
                    )),
                    None => problems.push(format!("{at}: cannot read {}", target.display())),
                }
            } else {
                problems.push(format!(
                    "{at}: an anchor into {}, which is not Markdown",
                    target.display()
                ));
            }
        }
    }
    problems
}

#[test]
fn every_relative_link_and_anchor_in_the_guide_resolves() {
    let root = root();
    let files = guide::files();
    let problems = broken_links(&root, &files);
    assert!(
        problems.is_empty(),
        "{} broken link(s) in the guide:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn slugs_follow_github() {
    assert_eq!(slug("The subcommands"), "the-subcommands");
    assert_eq!(slug("§2.3 Q15 & Q7: the formats"), "23-q15--q7-the-formats");
    assert_eq!(slug("run --help"), "run---help");
    assert_eq!(slug("snake_case and (parens)"), "snake_case-and-parens");
    assert_eq!(slug("Über η = 0.03"), "über-η--003");
    assert_eq!(percent_decode("a%20b.md"), "a b.md");
    assert_eq!(percent_decode("100%"), "100%");
    assert_eq!(percent_decode("%zz%é"), "%zz%é");
    let (anchors, _) = scan("# A\n\n## A\n\n### A\n\n## `code` *in* [a link](x.md)\n");
    let want: BTreeSet<String> = ["a", "a-1", "a-2", "code-in-a-link"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(anchors, want);
    let (anchors, _) = scan("<a id=\"s1\"></a>\n\n## Titled {#custom}\n");
    assert!(
        anchors.contains("s1") && anchors.contains("custom"),
        "{anchors:?}"
    );
}

/// The checker itself finds what it is for, on a small tree of its own.
#[test]
fn the_check_reports_broken_files_and_anchors() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("doc_links_fixture");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("d")).unwrap();
    std::fs::write(
        dir.join("d/b.md"),
        "# Three crates\n\n## Same\n\n## Same\n\n<a id=\"x\"></a>\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("a.md"),
        "# Top\n\
         [ok](d/b.md#three-crates) [ok](d/b.md#same-1) [ok](d/b.md#x) [ok](#top)\n\
         [ok](https://example.invalid/#nowhere) [ok](d/)\n\
         [bad](d/b.md#two-crates)\n\
         [bad](missing.md)\n\
         [bad](#nowhere)\n\
         [bad](../outside.md)\n\
         [bad]\n\n[bad]: d/b.md#same-2\n\
         `[not a link](missing.md)`\n\n```\n[not a link](missing.md)\n```\n",
    )
    .unwrap();
    let problems = broken_links(&dir, &[PathBuf::from("a.md")]);
    let text = problems.join("\n");
    assert_eq!(problems.len(), 5, "{text}");
    for want in [
        "a.md:4: (d/b.md#two-crates): no heading or id #two-crates in d/b.md",
        "a.md:5: (missing.md): no file missing.md",
        "a.md:6: (#nowhere): no heading or id #nowhere in a.md",
        "a.md:7: (../outside.md): points outside the repository",
        "(d/b.md#same-2): no heading or id #same-2",
    ] {
        assert!(text.contains(want), "missing {want:?} in:\n{text}");
    }
}
