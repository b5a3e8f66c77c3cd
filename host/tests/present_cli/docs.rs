//! Documentation that stays inside the repository: `--help` texts name
//! docs/formats.md, and every relative link of the Markdown pages resolves.

use super::{plinth, repo};

/// Every `--help` that names the data contract names the file in the
/// repository (docs/formats.md), which exists.
#[test]
fn help_texts_point_inside_the_repository() {
    assert!(repo().join("docs/formats.md").is_file());
    let commands = [
        "identify", "simulate", "signals", "predict", "paper", "stream", "demo", "diagnose",
        "import", "extract", "plot", "accuracy",
    ];
    for c in commands {
        let out = plinth().args([c, "--help"]).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        for (i, _) in text.match_indices("formats.md") {
            assert!(
                text[..i].ends_with("docs/"),
                "plinth {c} --help names formats.md outside docs/: {text}"
            );
        }
        assert!(!text.contains(&["/work", "/shared"].concat()), "{c}");
    }
}

/// Every relative link in README.md and docs/*.md resolves to a file in
/// the repository, and no file of the repository refers to documents
/// outside it.
#[test]
fn documentation_links_resolve_and_stay_inside() {
    let root = repo();
    let mut pages = vec![
        root.join("README.md"),
        root.join("examples/field/README.md"),
    ];
    for e in std::fs::read_dir(root.join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            pages.push(p);
        }
    }
    let mut broken = Vec::new();
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        let mut rest = text.as_str();
        while let Some(i) = rest.find("](") {
            rest = &rest[i + 2..];
            let Some(end) = rest.find(')') else { break };
            let target = &rest[..end];
            rest = &rest[end..];
            if target.starts_with("http")
                || target.starts_with('#')
                || target.starts_with("mailto:")
            {
                continue;
            }
            let path = target.split('#').next().unwrap_or(target);
            let resolved = page.parent().unwrap().join(path);
            if !resolved.exists() {
                broken.push(format!("{}: {target}", page.display()));
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));

    let outside = ["/work", "/shared"].concat();
    let mut mentions = Vec::new();
    let mut stack = vec![root.clone()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            if name.starts_with('.') || name.starts_with("target") {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else if let Ok(bytes) = std::fs::read(&p) {
                if bytes
                    .windows(outside.len())
                    .any(|w| w == outside.as_bytes())
                {
                    mentions.push(p.display().to_string());
                }
            }
        }
    }
    assert!(mentions.is_empty(), "files naming {outside}: {mentions:?}");
}
