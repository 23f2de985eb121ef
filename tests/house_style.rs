//! House style that a reader would otherwise have to police: comments say why, never when.
//! No comment in src/, glsl/, tests/, the scene files, the report's configuration or the
//! scripts names a development branch or an issue number, and no name carries one
//! (an `issue_` then a digit); the papers' sections and equations are what code cites.
use std::path::Path;

fn files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, out);
        } else {
            out.push(p);
        }
    }
}

#[test]
fn no_comment_narrates_history() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut all = Vec::new();
    files(&root.join("src"), &mut all);
    files(&root.join("glsl"), &mut all);
    files(&root.join("tests"), &mut all);
    files(&root.join("assets").join("scenes"), &mut all);
    files(&root.join("scripts"), &mut all);
    all.extend(["docs/report.toml", "x", ".ci/run", "build.rs"].map(|f| root.join(f)));
    let mut found = Vec::new();
    for p in all {
        let Ok(text) = std::fs::read_to_string(&p) else { continue };
        for (i, line) in text.lines().enumerate() {
            // Rust and GLSL comment with `//`; TOML and shell with `#`.
            let marker =
                if p.extension().is_some_and(|e| e == "rs" || e == "glsl" || e == "frag" || e == "vert" || e == "comp")
                {
                    "//"
                } else {
                    "#"
                };
            let lower = line.to_lowercase();
            let named = lower
                .match_indices("issue_")
                .any(|(k, _)| lower[k + 6..].chars().next().is_some_and(|c| c.is_ascii_digit()));
            if named {
                found.push(format!("{}:{}: {}", p.strip_prefix(root).unwrap().display(), i + 1, line.trim()));
                continue;
            }
            let Some(at) = line.find(marker) else { continue };
            let comment = line[at..].to_lowercase();
            let issue = comment
                .match_indices("issue ")
                .any(|(k, _)| comment[k + 6..].chars().next().is_some_and(|c| c.is_ascii_digit()));
            if issue || comment.contains("branch `") {
                found.push(format!("{}:{}: {}", p.strip_prefix(root).unwrap().display(), i + 1, line.trim()));
            }
        }
    }
    assert!(found.is_empty(), "comments that narrate history:\n{}", found.join("\n"));
}
