//! The documentation holds together (issue 37): the README stays a first screen (at most
//! [`README_LINES`] lines) that points into the book under `docs/`; every relative link in the
//! README, the book and the folders' READMEs reaches a file, and every `#anchor` a heading
//! (GitHub's and mdBook's slugs: lower case, spaces to `-`, punctuation dropped); every page
//! of the book is in its table of contents (`docs/SUMMARY.md`, mdBook's format); and every
//! cite of the catalogue in the sources (`docs/catalogue.md §N`) names a numbered entry there;
//! and each recipe's file list is what its own `grep` finds. No tool but `sh` and `grep` is
//! needed: a forge renders these pages as they are, and CI pays for no book build.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The README's budget: what umbra is, the two commands, the status, where to read on.
const README_LINES: usize = 200;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every file under `dir` whose name ends with one of `ends` (build output and hidden
/// folders left out), sorted.
fn files_under(dir: &Path, ends: &[&str]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() {
                if name != "target" && !name.starts_with('.') {
                    stack.push(p);
                }
            } else if ends.iter().any(|x| name.ends_with(x)) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The pages checked: the README, the book, and the READMEs of the folders users open.
fn pages() -> Vec<PathBuf> {
    let root = root();
    let mut out = vec![
        root.join("README.md"),
        root.join("cases/README.md"),
        root.join("golden/README.md"),
    ];
    out.extend(files_under(&root.join("docs"), &[".md"]));
    out
}

/// The text outside fenced code blocks, line by line (1-based numbers).
fn prose(text: &str) -> Vec<(usize, String)> {
    let mut fenced = false;
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            out.push((n + 1, line.to_string()));
        }
    }
    out
}

/// A heading's anchor as GitHub and mdBook make it.
fn slug(heading: &str) -> String {
    let mut text = String::new();
    // A link in a heading counts by its words.
    let mut rest = heading.replace('`', "");
    while let (Some(a), Some(b)) = (rest.find("]("), rest.find(')')) {
        if b < a {
            break;
        }
        rest = format!("{}{}", &rest[..a], &rest[b + 1..]).replacen('[', "", 1);
    }
    for c in rest.trim().to_lowercase().chars() {
        if c.is_alphanumeric() || c == '-' || c == '_' {
            text.push(c);
        } else if c == ' ' {
            text.push('-');
        }
    }
    text
}

/// Every anchor a page's headings make (a repeated heading gets `-1`, `-2`, …).
fn anchors(page: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(page).unwrap_or_default();
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    for (_, line) in prose(&text) {
        let hashes = line.chars().take_while(|c| *c == '#').count();
        if !(1..=6).contains(&hashes) || !line[hashes..].starts_with(' ') {
            continue;
        }
        let s = slug(line[hashes..].trim().trim_end_matches('#'));
        let n = seen.entry(s.clone()).or_insert(0);
        out.insert(if *n == 0 {
            s.clone()
        } else {
            format!("{s}-{n}")
        });
        *n += 1;
    }
    out
}

/// The relative link targets on a line (`[text](target)`), inline code left out.
fn links(line: &str) -> Vec<String> {
    let mut code = false;
    let plain: String = line
        .chars()
        .filter(|c| {
            if *c == '`' {
                code = !code;
            }
            !code && *c != '`'
        })
        .collect();
    plain
        .match_indices("](")
        .filter_map(|(i, _)| {
            let rest = &plain[i + 2..];
            let end = rest.find(')')?;
            Some(
                rest[..end]
                    .split_whitespace()
                    .next()
                    .unwrap_or("")
                    .to_string(),
            )
        })
        .filter(|t| !t.is_empty() && !t.contains("://") && !t.starts_with("mailto:"))
        .collect()
}

#[test]
fn every_relative_link_and_anchor_resolves() {
    let pages = pages();
    assert!(pages.len() > 10, "the book was not found: {pages:?}");
    let mut broken = Vec::new();
    let mut checked = 0;
    for page in &pages {
        let text = std::fs::read_to_string(page).expect("page");
        for (n, line) in prose(&text) {
            for target in links(&line) {
                checked += 1;
                let (file, anchor) = target.split_once('#').unwrap_or((&target, ""));
                let to = if file.is_empty() {
                    page.clone()
                } else {
                    page.parent().expect("a folder").join(file)
                };
                if !to.exists() {
                    broken.push(format!("{}:{n}: {target}: no such file", page.display()));
                } else if !anchor.is_empty() && !anchors(&to).contains(anchor) {
                    broken.push(format!("{}:{n}: {target}: no such heading", page.display()));
                }
            }
        }
    }
    assert!(checked > 100, "only {checked} links found");
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_readme_is_a_first_screen_and_the_book_is_whole() {
    let root = root();
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README");
    let lines = readme.lines().count();
    assert!(
        lines <= README_LINES,
        "README.md is {lines} lines; move detail into the book under docs/ (at most {README_LINES})"
    );
    assert!(readme.contains("cargo xtask conformance") && readme.contains("cargo xtask test"));
    let summary = std::fs::read_to_string(root.join("docs/SUMMARY.md")).expect("SUMMARY.md");
    let listed: BTreeSet<String> = links(&summary.replace('\n', " ")).into_iter().collect();
    for p in files_under(&root.join("docs"), &[".md"]) {
        let rel = p
            .strip_prefix(root.join("docs"))
            .expect("under docs")
            .display()
            .to_string();
        if rel == "SUMMARY.md" {
            continue;
        }
        assert!(
            listed.contains(&rel),
            "docs/{rel} is not in docs/SUMMARY.md"
        );
    }
}

#[test]
fn every_cite_of_the_catalogue_names_an_entry() {
    let root = root();
    let entries: BTreeSet<String> = std::fs::read_to_string(root.join("docs/catalogue.md"))
        .expect("catalogue")
        .lines()
        .filter_map(|l| l.strip_prefix("### "))
        .filter_map(|l| l.split_once(". ").map(|(n, _)| n.to_string()))
        .collect();
    assert!(entries.len() >= 17, "{entries:?}");
    let mut files: Vec<PathBuf> = ["crates", "cases", "tests", "xtask", "expectations"]
        .iter()
        .flat_map(|d| files_under(&root.join(d), &[".rs", ".json", ".md", ".txt"]))
        .collect();
    let mut unknown = Vec::new();
    let mut cites = 0;
    // This file names what it forbids.
    files.retain(|f| !f.ends_with("tests/docs.rs"));
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap_or_default();
        for (i, _) in text.match_indices("docs/catalogue.md §") {
            let n: String = text[i + "docs/catalogue.md §".len()..]
                .chars()
                .take_while(char::is_ascii_digit)
                .collect();
            cites += 1;
            if !entries.contains(&n) {
                unknown.push(format!("{}: §{n}", f.display()));
            }
        }
        assert!(
            !text.contains("EDGE_CASES") && !text.contains("../shared/"),
            "{} cites a document outside the repository; cite docs/ instead",
            f.display()
        );
    }
    assert!(cites > 20, "only {cites} cites found");
    assert!(
        unknown.is_empty(),
        "cites of no catalogue entry: {unknown:?}"
    );
}

#[test]
fn the_checker_reads_links_and_headings_as_a_forge_does() {
    assert_eq!(
        links("see [a](b.md#c-d), `[not](x.md)` and [web](https://x.org) [top](#e)"),
        ["b.md#c-d", "#e"]
    );
    assert_eq!(
        slug("3. \"AMD needs a colour attachment\""),
        "3-amd-needs-a-colour-attachment"
    );
    assert_eq!(slug("`--shard` and [merge](ci.md)"), "--shard-and-merge");
    assert_eq!(slug("Sharded in CI: `--shard`"), "sharded-in-ci---shard");
}

/// Each recipe's `grep -rn …` block, run as written from the repository's root: the source
/// files it finds. A recipe whose text after the block says "As of this writing" lists its
/// hits as bullets (`- \`path\``), and that list must be exactly what the grep finds; any
/// other recipe must name every source file its grep finds (a precedent that now touches a
/// file the recipe does not name is a recipe that drifted).
#[test]
fn each_recipes_file_list_is_what_its_own_grep_finds() {
    let root = root();
    let mut greps = 0;
    let mut drift = Vec::new();
    for recipe in files_under(&root.join("docs/recipes"), &[".md"]) {
        let text = std::fs::read_to_string(&recipe).expect("recipe");
        let lines: Vec<&str> = text.lines().collect();
        let name = recipe.file_name().map(|n| n.to_string_lossy().into_owned());
        for (at, line) in lines.iter().enumerate() {
            if !line.starts_with("grep -rn ") || lines.get(at.wrapping_sub(1)) != Some(&"```sh") {
                continue;
            }
            greps += 1;
            let out = std::process::Command::new("sh")
                .arg("-c")
                .arg(line)
                .current_dir(&root)
                .output()
                .expect("sh runs the recipe's grep");
            let hits: BTreeSet<String> = String::from_utf8_lossy(&out.stdout)
                .lines()
                .filter_map(|l| l.split(':').next())
                .filter(|f| f.ends_with(".rs"))
                .map(str::to_string)
                .collect();
            assert!(!hits.is_empty(), "{name:?}: `{line}` finds nothing");
            // The bullets right after "As of this writing", if the recipe lists its hits.
            let after = &lines[at + 1..];
            let listed: Option<BTreeSet<String>> = after
                .iter()
                .take_while(|l| !l.starts_with("## "))
                .position(|l| l.contains("As of this writing"))
                .map(|p| {
                    after[p + 1..]
                        .iter()
                        .skip_while(|l| !l.starts_with("- "))
                        .take_while(|l| l.starts_with("- ") || l.starts_with("  "))
                        .filter(|l| l.starts_with("- "))
                        .flat_map(|l| {
                            // Every backticked path before the item's first colon.
                            let head = l.split("`:").next().unwrap_or(l);
                            head.split('`')
                                .skip(1)
                                .step_by(2)
                                .filter(|p| p.ends_with(".rs"))
                                .map(str::to_string)
                                .collect::<Vec<_>>()
                        })
                        .collect()
                });
            let named = |hit: &str| match &listed {
                Some(list) => list.iter().any(|l| hit.ends_with(&format!("/{l}"))),
                None => text.contains(hit),
            };
            for hit in &hits {
                if !named(hit) {
                    drift.push(format!(
                        "{name:?}: its grep finds {hit}, which it does not name"
                    ));
                }
            }
            for l in listed.iter().flatten() {
                if !hits.iter().any(|h| h.ends_with(&format!("/{l}"))) {
                    drift.push(format!("{name:?}: lists {l}, which its grep does not find"));
                }
            }
        }
    }
    assert!(greps >= 2, "only {greps} recipe greps found");
    assert!(
        drift.is_empty(),
        "recipes drifted from their code: {drift:#?}"
    );
}
