//! Names of bearings, bases, channels and transducers: checked once where
//! they are read, and turned into file names by one function that cannot
//! leave its directory.
//!
//! A name (docs/robustness.md, "Names") is 1 to [`MAX_NAME_CHARS`]
//! characters of letters and digits (any script), space, and
//! `_ - . + # ( )`; it does not start or end with a space and is not made of
//! dots only (`.`, `..`). Path separators (`/`, `\`), `:`, quotes, commas,
//! semicolons and control characters are refused: a name becomes a CSV
//! field, a list element in `base.csv` (`;`) and part of figure file names.
//!
//! [`file_in`] builds the path of a file named after a name: every
//! character outside `A-Z a-z 0-9 _ - . +` (and a leading `.`) is written as
//! `%XX` (its UTF-8 bytes), so the file name is never a path, never hidden,
//! and two different names never share a file.

use std::path::{Path, PathBuf};

/// The longest name accepted [characters].
pub const MAX_NAME_CHARS: usize = 64;

/// The longest file name [`file_in`] builds [bytes] (file systems allow 255).
pub const MAX_FILE_NAME_BYTES: usize = 240;

/// The characters a name may hold besides letters and digits, for messages.
pub const NAME_CHARACTERS: &str =
    "letters, digits, space and _ - . + # ( ) (at most 64 characters, no / \\ : , ; quotes or control characters)";

/// Why `name` is not a valid name (`None` when it is).
pub fn problem(name: &str) -> Option<String> {
    if name.is_empty() {
        return Some("the name is empty".into());
    }
    let n = name.chars().count();
    if n > MAX_NAME_CHARS {
        return Some(format!(
            "the name is {n} characters long; at most {MAX_NAME_CHARS} are allowed"
        ));
    }
    if let Some(c) = name.chars().find(|c| c.is_control()) {
        return Some(format!(
            "the name holds the control character U+{:04X}",
            c as u32
        ));
    }
    if let Some(c) = name
        .chars()
        .find(|&c| !(c.is_alphanumeric() || " _-.+#()".contains(c)))
    {
        let hint = if c == '/' || c == '\\' {
            " (a path separator: names are never paths; write e.g. `DE-NDE`)"
        } else {
            ""
        };
        return Some(format!("the character {c:?} is not allowed{hint}"));
    }
    if name.trim() != name {
        return Some("the name starts or ends with a space".into());
    }
    if name.chars().all(|c| c == '.') {
        return Some(format!("{name:?} is not a name (only dots)"));
    }
    None
}

/// Checks `name`: `Err` says what is wrong and what is allowed, e.g.
/// ``bearing `../x`: the character '/' is not allowed ...``; `what` is the
/// kind of name ("bearing", "base", "channel", "transducer").
pub fn check(what: &str, name: &str) -> Result<(), String> {
    match problem(name) {
        None => Ok(()),
        Some(p) => {
            let shown: String = name.chars().take(MAX_NAME_CHARS).collect();
            let more = if name.chars().count() > MAX_NAME_CHARS {
                "..."
            } else {
                ""
            };
            // Control characters escaped, everything else as written.
            let shown: String = shown
                .chars()
                .map(|c| {
                    if c.is_control() {
                        c.escape_debug().to_string()
                    } else {
                        c.to_string()
                    }
                })
                .collect();
            Err(format!(
                "{what} `{shown}{more}`: {p}; a name uses {NAME_CHARACTERS}"
            ))
        }
    }
}

/// The file name for `stem` (a fixed prefix joined with names, e.g.
/// `bode_DE_rel`): safe characters kept, every other byte written as `%XX`,
/// a leading `.` too; never empty, never `.`/`..`, never holds a separator.
/// Too long a result is cut and ended with a hash of the whole stem, so
/// different stems stay different.
pub fn file_name(stem: &str) -> String {
    let mut out = String::with_capacity(stem.len());
    for (i, b) in stem.bytes().enumerate() {
        let safe =
            b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'+') || (b == b'.' && i > 0);
        if safe {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    if out.is_empty() {
        out.push('%'); // never the encoding of a byte (always %XX)
    }
    if out.len() > MAX_FILE_NAME_BYTES {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in stem.bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        out.truncate(MAX_FILE_NAME_BYTES - 17);
        out.push_str(&format!("~{h:016x}"));
    }
    out
}

/// Whether `name` is a file name [`file_name`] can produce: only
/// `A-Z a-z 0-9 _ - . + %`, no leading `.`, not empty, not too long.
pub fn is_file_name(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= MAX_FILE_NAME_BYTES + 4
        && !name.starts_with('.')
        && name.bytes().all(|b| {
            b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'+' | b'.' | b'%' | b'~')
        })
}

/// `dir/` + [`file_name`]`(stem)`: a path directly inside `dir`, whatever
/// `stem` holds (figure writers add `.png`/`.svg` to it).
pub fn file_in(dir: &Path, stem: &str) -> PathBuf {
    dir.join(file_name(stem))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hostile_names_are_refused_and_field_names_pass() {
        for ok in [
            "DE", "NDE", "B1", "left", "pump DE", "Lager-2", "Brg.3", "Ø1", "x+y", "#4 (HP)",
        ] {
            assert_eq!(problem(ok), None, "{ok}");
        }
        for bad in [
            "",
            ".",
            "..",
            "...",
            "../../../x",
            "DE/NDE",
            "a\\b",
            "a\nb",
            "a\u{0}b",
            " a",
            "a ",
            "a,b",
            "a;b",
            "\"a\"",
            "C:x",
            &"x".repeat(65),
        ] {
            assert!(problem(bad).is_some(), "{bad:?}");
        }
        let e = check("bearing", "DE/NDE").unwrap_err();
        assert!(
            e.contains("bearing `DE/NDE`") && e.contains("path separator"),
            "{e}"
        );
        let e = check("bearing", &"y".repeat(100_000)).unwrap_err();
        assert!(
            e.len() < 400,
            "the message does not echo a long name: {}",
            e.len()
        );
    }

    #[test]
    fn file_names_never_leave_their_directory_and_stay_distinct() {
        let dir = Path::new("/tmp/out/figures");
        let stems = [
            "bode_../../../x_rel",
            "..",
            ".",
            "",
            "/etc/passwd",
            "a/b",
            "a b",
            "a_b",
            ".hidden",
            "a%2Fb",
            "\u{0}",
            "bode_DE_rel",
        ];
        let mut seen = std::collections::BTreeSet::new();
        for s in stems {
            let p = file_in(dir, s);
            assert_eq!(p.parent(), Some(dir), "{s:?} -> {}", p.display());
            let n = p.file_name().unwrap().to_str().unwrap();
            assert!(
                n != "." && n != ".." && !n.starts_with('.') && !n.contains('/'),
                "{n}"
            );
            assert!(seen.insert(n.to_string()), "{s:?} collides");
            assert!(is_file_name(n), "{n}");
        }
        assert_eq!(file_name("bode_DE_rel"), "bode_DE_rel");
        for bad in ["", ".x", "..", "a/b", "a b", "a\\b"] {
            assert!(!is_file_name(bad), "{bad}");
        }
        let long = file_in(dir, &"é".repeat(300));
        assert!(long.file_name().unwrap().len() <= MAX_FILE_NAME_BYTES);
        assert_ne!(file_name(&"é".repeat(300)), file_name(&"é".repeat(301)));
    }
}
