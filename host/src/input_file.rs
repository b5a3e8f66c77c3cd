//! Input files that must be regular files: a FIFO, socket or device named
//! where a table, machine file, configuration or JSON file is expected is
//! refused at once (reading a FIFO with no writer would block forever).

use std::io::{Error, ErrorKind, Read};
use std::path::Path;

/// Checks that `path` is a regular file (symbolic links followed); the
/// error says what it is instead and what is expected.
pub fn ensure_regular(path: &Path) -> std::io::Result<()> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        return Ok(());
    }
    let kind = if meta.is_dir() {
        "a directory"
    } else {
        "not a regular file (a FIFO, socket or device)"
    };
    Err(Error::new(
        ErrorKind::InvalidInput,
        format!("is {kind}: give it as a regular file"),
    ))
}

/// [`std::fs::read_to_string`] of a regular file only ([`ensure_regular`]
/// first, so a FIFO never blocks).
pub fn read_to_string(path: &Path) -> std::io::Result<String> {
    ensure_regular(path)?;
    let bytes = std::fs::metadata(path)?.len();
    if bytes > MAX_TEXT_BYTES {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!(
                "is {bytes} bytes long; a configuration, machine or JSON file is at most {MAX_TEXT_BYTES} bytes: is it the right file?"
            ),
        ));
    }
    let text = utf8_text(std::fs::read(path)?)?;
    check_line_lengths(&text)?;
    Ok(text)
}

/// The UTF-8 byte-order mark, which editors on Windows write at the start
/// of a text file; formats.md's files are UTF-8 with or without it.
pub const UTF8_BOM: &[u8] = &[0xEF, 0xBB, 0xBF];

/// `bytes` as UTF-8 text without its byte-order mark (JSON readers refuse
/// one at "line 1 column 1"). UTF-16 ([`utf16_found`]) is named as such;
/// any other byte that is not UTF-8 is named by its line and column
/// [1-based] and value, never echoing the line: a Latin-1 or Windows-1252
/// file (an accented name) otherwise failed with "stream did not contain
/// valid UTF-8" and no place.
pub fn utf8_text(mut bytes: Vec<u8>) -> std::io::Result<String> {
    if let Some(found) = utf16_found(&bytes) {
        return Err(Error::new(
            ErrorKind::InvalidData,
            format!("{found}; expected UTF-8 text: convert it (iconv -f UTF-16 -t UTF-8)"),
        ));
    }
    if bytes.starts_with(UTF8_BOM) {
        bytes.drain(..UTF8_BOM.len());
    }
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let good = String::from_utf8_lossy(&bytes[..at]);
        let line = good.matches('\n').count() + 1;
        let column = good.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        Error::new(
            ErrorKind::InvalidData,
            format!(
                "line {line}, column {column}: byte 0x{:02X} is not UTF-8 (a Latin-1 or Windows-1252 file?): save it as UTF-8 (iconv -f WINDOWS-1252 -t UTF-8)",
                bytes[at]
            ),
        )
    })
}

/// The line and column [1-based] of the `nth` (1-based) place where the
/// JSON file at `path` writes `"key": "value"`, at the value, or (1, 1):
/// serde's values carry no position, so an error about a value (a bearing
/// listed twice) is placed by its text.
pub fn json_value_place(path: &Path, key: &str, value: &str, nth: usize) -> (usize, usize) {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let value = format!("\"{value}\"");
    let at = json_keys(&text, key)
        .filter(|&(_, v)| v.starts_with(&value))
        .map(|(_, v)| text.len() - v.len())
        .nth(nth.saturating_sub(1));
    at.map_or((1, 1), |at| line_column(&text, at))
}

/// The line and column [1-based] of the `nth` (1-based) place where the
/// JSON `text` writes the key `"key":`, at the key's opening quote, or
/// (1, 1) when it has fewer (serde's values carry no position).
pub fn json_key_place(text: &str, key: &str, nth: usize) -> (usize, usize) {
    json_keys(text, key)
        .nth(nth.saturating_sub(1))
        .map_or((1, 1), |(at, _)| line_column(text, at))
}

/// Each place `text` writes `"key":`, in order: the byte where the quoted
/// key starts and what follows its colon (blanks skipped).
fn json_keys<'a>(text: &'a str, key: &str) -> impl Iterator<Item = (usize, &'a str)> + 'a {
    let key = format!("\"{key}\"");
    let len = key.len();
    text.match_indices(&key)
        .map(|(k, _)| k)
        .collect::<Vec<_>>()
        .into_iter()
        .filter_map(move |k| {
            let rest = text[k + len..].trim_start().strip_prefix(':')?;
            Some((k, rest.trim_start()))
        })
}

/// The line and column [1-based, in characters] of byte `at` of `text`.
pub fn line_column(text: &str, at: usize) -> (usize, usize) {
    let before = &text[..at];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        before.matches('\n').count() + 1,
        before[line_start..].chars().count() + 1,
    )
}

/// What the first bytes of a file say if it is UTF-16 text: its byte-order
/// mark, or NUL bytes between its characters (a quarter or more of its first
/// 200 bytes); `None` otherwise. The phrase names what was found, for the
/// caller to add what is expected.
pub fn utf16_found(head: &[u8]) -> Option<String> {
    if head.starts_with(&[0xFF, 0xFE]) || head.starts_with(&[0xFE, 0xFF]) {
        let order = if head[0] == 0xFF { "little" } else { "big" };
        return Some(format!(
            "the file is UTF-16 text ({order}-endian byte-order mark {:02X} {:02X})",
            head[0], head[1]
        ));
    }
    let zeros = head.iter().take(200).filter(|&&b| b == 0).count();
    (zeros > 0 && zeros * 4 >= head.len().min(200)).then(|| {
        "the file has NUL bytes between its characters (UTF-16 without a byte-order mark?)".into()
    })
}

/// The largest text file [`read_to_string`] reads whole [bytes]: 64 MiB
/// (configuration, machine, layout and JSON files are kilobytes).
pub const MAX_TEXT_BYTES: u64 = 64 << 20;

/// The longest line any text input may have [bytes]: 1 MiB. A table,
/// recording or configuration line is at most a few kilobytes; a longer one
/// is a binary file or a file with no line ends, refused before it is held
/// in memory whole.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// A text reader that refuses, as an I/O error of kind `InvalidData`, a line
/// longer than a bound [bytes], any NUL byte (never text) and, when given,
/// more lines than a table can hold in memory, naming the line [1-based] and
/// never echoing its content. Memory stays bounded by the reader above it
/// holding at most one line (and, for a table, at most the lines allowed).
///
/// Line ends are given as `\n` whatever the file has (`\r\n` from Windows,
/// a lone `\r` from old Macs): the csv crate counts a line only at a `\n`
/// it consumes and consumes only the `\r` of a `\r\n` ending a record, so
/// a CRLF file's errors were placed a line early (rust-csv issue 395). The
/// lines the readers name are then the file's lines, as an editor numbers them.
pub struct BoundedLines<R> {
    inner: R,
    /// One byte read from `inner` and not yet given (the byte after a `\r`
    /// that ended a read).
    carry: Option<u8>,
    /// The current line [1-based].
    line: u64,
    /// Bytes of the current line so far.
    run: usize,
    max: usize,
    /// The most lines allowed and the memory they stand for [bytes].
    max_lines: Option<(u64, u64)>,
}

impl<R: Read> BoundedLines<R> {
    /// Wraps `inner` with lines of at most `max` bytes.
    pub fn new(inner: R, max: usize) -> Self {
        BoundedLines {
            inner,
            carry: None,
            line: 1,
            run: 0,
            max,
            max_lines: None,
        }
    }

    /// Also refuses a line past `lines` (a table's rows held in memory,
    /// [`crate::sim::budget::TABLE_ROW_BYTES`] each, within `available`
    /// bytes [bytes], named in the error).
    pub fn with_max_lines(mut self, lines: u64, available: u64) -> Self {
        self.max_lines = Some((lines, available));
        self
    }
}

impl<R: Read> BoundedLines<R> {
    /// Reads from `inner` into `buf` with every `\r\n` and lone `\r` given
    /// as `\n`; a `\r` that ends what was read is held back until the next
    /// byte says which it is. Returns the bytes given (0 only at the end).
    fn read_line_ends(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        loop {
            let start = usize::from(self.carry.is_some());
            if let Some(b) = self.carry.take() {
                buf[0] = b;
            }
            let n = if start < buf.len() {
                self.inner.read(&mut buf[start..])?
            } else {
                // A carried `\r` and room for one byte: peek at the next.
                let mut next = [0u8; 1];
                let k = self.inner.read(&mut next)?;
                if k == 1 && next[0] != b'\n' {
                    self.carry = Some(next[0]);
                }
                if buf[0] == b'\r' {
                    buf[0] = b'\n';
                }
                return Ok(1);
            };
            let total = start + n;
            let (mut read, mut given) = (0, 0);
            while read < total {
                let b = buf[read];
                read += 1;
                if b == b'\r' {
                    if read == total && n > 0 {
                        // Ends the read: CRLF or a lone CR, the next read says.
                        self.carry = Some(b'\r');
                        break;
                    }
                    if read < total && buf[read] == b'\n' {
                        continue;
                    }
                    buf[given] = b'\n';
                } else {
                    buf[given] = b;
                }
                given += 1;
            }
            if given > 0 || total == 0 {
                return Ok(given);
            }
        }
    }
}

impl<R: Read> Read for BoundedLines<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.read_line_ends(buf)?;
        // Line by line: each run of bytes up to a line end or a NUL is
        // judged at once (the same errors at the same line and byte as a
        // byte-by-byte check, at a fraction of its cost on large tables).
        let mut rest = &buf[..n];
        while !rest.is_empty() {
            let end = line_end(rest);
            let bytes = end.unwrap_or(rest.len());
            if bytes > 0 {
                if let Some((most, available)) = self.max_lines.filter(|_| self.run == 0) {
                    if self.line > most {
                        return Err(Error::new(
                            ErrorKind::InvalidData,
                            format!(
                                "line {}: more than {most} lines: a table's rows are held in memory (about {} bytes each) and this machine has {} MB available: is it the right file? ({} caps the memory Plinth plans for)",
                                self.line,
                                crate::sim::budget::TABLE_ROW_BYTES,
                                available >> 20,
                                crate::sim::budget::MEMORY_ENV
                            ),
                        ));
                    }
                }
                self.run += bytes;
                if self.run > self.max {
                    return Err(Error::new(
                        ErrorKind::InvalidData,
                        format!(
                            "line {} is longer than {} bytes (a text line here is at most a few kilobytes): is it the right file, with line ends?",
                            self.line, self.max
                        ),
                    ));
                }
            }
            let Some(at) = end else {
                break;
            };
            if rest[at] == 0 {
                return Err(Error::new(
                    ErrorKind::InvalidData,
                    format!(
                        "line {}, byte {}: a NUL byte: this is not UTF-8 text (a binary file, or UTF-16: convert it with iconv -f UTF-16 -t UTF-8)",
                        self.line,
                        self.run + 1
                    ),
                ));
            }
            self.line += 1;
            self.run = 0;
            rest = &rest[at + 1..];
        }
        Ok(n)
    }
}

/// The position of the first line end or NUL byte of `bytes`: eight bytes
/// at a time (a word has a zero byte when (x − 0x01…01) & !x & 0x80…80 is
/// not zero; a line end is a zero byte of x ^ 0x0a…0a), the word that has
/// one searched byte by byte. The same position as a byte-by-byte search.
fn line_end(bytes: &[u8]) -> Option<usize> {
    const ONES: u64 = u64::from_ne_bytes([0x01; 8]);
    const HIGH: u64 = u64::from_ne_bytes([0x80; 8]);
    const LINE_ENDS: u64 = u64::from_ne_bytes([b'\n'; 8]);
    let has_zero = |x: u64| x.wrapping_sub(ONES) & !x & HIGH != 0;
    let mut start = 0;
    for word in bytes.chunks_exact(8) {
        let Ok(word) = <[u8; 8]>::try_from(word) else {
            break;
        };
        let x = u64::from_ne_bytes(word);
        if has_zero(x) || has_zero(x ^ LINE_ENDS) {
            break;
        }
        start += 8;
    }
    bytes[start..]
        .iter()
        .position(|&b| b == b'\n' || b == 0)
        .map(|p| start + p)
}

/// Checks that no line of `text` is longer than [`MAX_LINE_BYTES`]; the
/// error names the line [1-based] and its length, not its content.
pub fn check_line_lengths(text: &str) -> std::io::Result<()> {
    for (i, line) in text.split('\n').enumerate() {
        if line.len() > MAX_LINE_BYTES {
            return Err(Error::new(
                ErrorKind::InvalidData,
                format!(
                    "line {} is {} bytes long (at most {MAX_LINE_BYTES}): is it the right file, with line ends?",
                    i + 1,
                    line.len()
                ),
            ));
        }
    }
    Ok(())
}

/// The widest piece of a line a TOML error shows [characters]: the parser's
/// own message quotes the whole line, which may be megabytes of nonsense.
const TOML_EXCERPT_CHARS: usize = 60;

/// A TOML parse error of `text` as `line L, column C: message` with at most
/// [`TOML_EXCERPT_CHARS`] characters of the line around the column (never
/// the whole line).
pub fn toml_error(text: &str, e: &toml::de::Error) -> String {
    let Some(span) = e.span() else {
        return format!("TOML: {}", e.message().trim_end());
    };
    let at = span.start.min(text.len());
    let at = (0..=at)
        .rev()
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(0);
    let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[at..].find('\n').map_or(text.len(), |i| at + i);
    let (line, column) = line_column(text, at);
    let whole = &text[line_start..line_end];
    let before: Vec<char> = text[line_start..at].chars().collect();
    let from = before.len().saturating_sub(TOML_EXCERPT_CHARS / 2);
    let excerpt: String = whole.chars().skip(from).take(TOML_EXCERPT_CHARS).collect();
    let clipped = from > 0 || whole.chars().count() > from + TOML_EXCERPT_CHARS;
    format!(
        "TOML parse error at line {line}, column {column}: {} (the line: `{}{excerpt}{}`)",
        e.message().trim_end(),
        if from > 0 { "…" } else { "" },
        if clipped && whole.chars().count() > from + TOML_EXCERPT_CHARS {
            "…"
        } else {
            ""
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_json_value_is_placed_at_its_nth_key_value_pair_only() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("id.json");
        let text = "{\"noise\": {\"left\": 1},\n \"p\": [{\"bearing\": \"left\"},\n  {\"bearing\":\n   \"left\"}]}";
        std::fs::write(&path, text).unwrap();
        assert_eq!(json_value_place(&path, "bearing", "left", 1), (2, 20));
        assert_eq!(json_value_place(&path, "bearing", "left", 2), (4, 4));
        assert_eq!(json_value_place(&path, "bearing", "left", 3), (1, 1));
        assert_eq!(json_value_place(&path, "bearing", "right", 1), (1, 1));
    }

    #[test]
    fn text_that_is_not_utf8_is_named_by_line_column_and_byte() {
        let text = |b: &[u8]| utf8_text(b.to_vec()).map_err(|e| e.to_string());
        assert_eq!(text(b"\xEF\xBB\xBFa = 1\n").unwrap(), "a = 1\n");
        assert_eq!(text("µ = 1\n".as_bytes()).unwrap(), "µ = 1\n");
        let e = text(b"a = 1\nname = \"l\xE9ft\"\n").unwrap_err();
        assert!(
            e.starts_with("line 2, column 10: byte 0xE9 is not UTF-8"),
            "{e}"
        );
        let e = text(b"\xFF\xFEa\0=\0").unwrap_err();
        assert!(e.contains("UTF-16 text (little-endian"), "{e}");
        let e = text(b"a\0 \0=\0 \0\x31\0").unwrap_err();
        assert!(e.contains("NUL bytes between its characters"), "{e}");
        assert!(utf16_found(b"a = 1\n").is_none());
    }

    #[test]
    fn toml_errors_name_line_and_column_without_the_whole_line() {
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct T {
            a: u32,
        }
        let deep = format!(
            "a = 1\nb = {}{}\n",
            "[".repeat(100_000),
            "]".repeat(100_000)
        );
        let e = toml::from_str::<T>(&deep).unwrap_err();
        let m = toml_error(&deep, &e);
        assert!(m.starts_with("TOML parse error at line 2, column"), "{m}");
        assert!(m.len() < 400, "{} bytes: {m}", m.len());
        let text = "a = \"x\"\n";
        let e = toml::from_str::<T>(text).unwrap_err();
        let m = toml_error(text, &e);
        assert!(
            m.contains("line 1, column 5") && m.contains("`a = \"x\"`"),
            "{m}"
        );
        let dup = "a = 1\na = 2\n";
        let m = toml_error(dup, &toml::from_str::<T>(dup).unwrap_err());
        assert!(m.contains("line 2") && m.contains("duplicate"), "{m}");
    }

    #[test]
    fn directories_are_refused_and_files_read() {
        let t = tempfile::tempdir().unwrap();
        let e = read_to_string(t.path()).unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
        let f = t.path().join("a.toml");
        std::fs::write(&f, "x = 1\n").unwrap();
        assert_eq!(read_to_string(&f).unwrap(), "x = 1\n");
        let missing = read_to_string(&t.path().join("none")).unwrap_err();
        assert_eq!(missing.kind(), ErrorKind::NotFound);
        let long = t.path().join("long.toml");
        std::fs::write(
            &long,
            format!("a = 1\nb = \"{}\"\n", "x".repeat(MAX_LINE_BYTES)),
        )
        .unwrap();
        let e = read_to_string(&long).unwrap_err().to_string();
        assert!(e.contains("line 2 is") && !e.contains("xxx"), "{e}");
    }

    fn read_all(bytes: &[u8], max: usize) -> std::io::Result<Vec<u8>> {
        let mut out = Vec::new();
        BoundedLines::new(bytes, max).read_to_end(&mut out)?;
        Ok(out)
    }

    #[test]
    fn line_ends_are_found_where_a_byte_by_byte_search_finds_them() {
        let mut text: Vec<u8> = (0..300u32).map(|i| b' ' + (i * 37 % 90) as u8).collect();
        for end in [
            None,
            Some(0),
            Some(1),
            Some(7),
            Some(8),
            Some(9),
            Some(63),
            Some(299),
        ] {
            for mark in [b'\n', 0, 0x8a, 0x0b] {
                let mut t = text.clone();
                if let Some(at) = end {
                    t[at] = mark;
                }
                for from in [0, 1, 5, 8, 13] {
                    let slice = &t[from.min(t.len())..];
                    let expected = slice.iter().position(|&b| b == b'\n' || b == 0);
                    assert_eq!(line_end(slice), expected, "{end:?} {mark} {from}");
                }
            }
        }
        text.truncate(5);
        assert_eq!(line_end(&text), None);
        assert_eq!(line_end(b""), None);
    }

    #[test]
    fn long_lines_and_nul_bytes_are_refused_by_line() {
        assert_eq!(read_all(b"ab\ncd\n", 2).unwrap(), b"ab\ncd\n");
        let e = read_all(b"ab\ncde\n", 2).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InvalidData);
        assert!(
            e.to_string().contains("line 2 is longer than 2 bytes"),
            "{e}"
        );
        let e = read_all(b"a\nb\nc\0", 10).unwrap_err().to_string();
        assert!(e.contains("line 3, byte 2: a NUL byte"), "{e}");
    }

    #[test]
    fn a_table_longer_than_memory_allows_is_refused_at_its_first_extra_line() {
        let lines = |n: usize| "1,2\n".repeat(n).into_bytes();
        let read = |bytes: Vec<u8>| {
            let mut out = Vec::new();
            BoundedLines::new(&bytes[..], 100)
                .with_max_lines(3, 3 << 20)
                .read_to_end(&mut out)
                .map(|_| out.len())
        };
        assert_eq!(read(lines(3)).unwrap(), 12);
        let e = read(lines(4)).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InvalidData);
        let e = e.to_string();
        assert!(
            e.starts_with("line 4: more than 3 lines") && e.contains("3 MB available"),
            "{e}"
        );
    }

    #[test]
    fn a_long_run_of_nul_bytes_fails_at_the_first_with_bounded_memory() {
        // 64 MiB of zeros, read through a CSV reader: fails at byte 1.
        let zeros = std::io::repeat(0).take(64 << 20);
        let mut r = csv::ReaderBuilder::new()
            .has_headers(false)
            .from_reader(BoundedLines::new(zeros, MAX_LINE_BYTES));
        let e = r.records().next().unwrap().unwrap_err().to_string();
        assert!(e.contains("line 1, byte 1: a NUL byte"), "{e}");
        let ones = std::io::repeat(b'1').take(64 << 20);
        let mut r = csv::ReaderBuilder::new()
            .has_headers(false)
            .from_reader(BoundedLines::new(ones, MAX_LINE_BYTES));
        let e = r.records().next().unwrap().unwrap_err().to_string();
        assert!(e.contains("line 1 is longer than 1048576 bytes"), "{e}");
    }

    /// A reader giving at most `step` bytes per read (a file read in pieces).
    struct Pieces<'a> {
        bytes: &'a [u8],
        step: usize,
    }

    impl Read for Pieces<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = self.step.min(buf.len()).min(self.bytes.len());
            buf[..n].copy_from_slice(&self.bytes[..n]);
            self.bytes = &self.bytes[n..];
            Ok(n)
        }
    }

    #[test]
    fn crlf_and_lone_cr_are_given_as_lf_whatever_the_reads_cut() {
        let cases: [(&[u8], &[u8]); 7] = [
            (b"a,b\r\nc,d\r\n", b"a,b\nc,d\n"),
            (b"a\rb\rc", b"a\nb\nc"),
            (b"a\r\r\nb\r", b"a\n\nb\n"),
            (b"\r\n\r\n", b"\n\n"),
            (b"\r", b"\n"),
            (b"no line end", b"no line end"),
            (b"a\n\rb", b"a\n\nb"),
        ];
        for (input, expected) in cases {
            for step in 1..=input.len().max(1) {
                for out_len in [1usize, 2, 3, 64] {
                    let mut r = BoundedLines::new(Pieces { bytes: input, step }, 100);
                    let mut out = Vec::new();
                    let mut buf = vec![0u8; out_len];
                    loop {
                        let n = r.read(&mut buf).unwrap();
                        if n == 0 {
                            break;
                        }
                        out.extend_from_slice(&buf[..n]);
                    }
                    assert_eq!(out, expected, "{input:?} step {step} buf {out_len}");
                }
            }
        }
    }

    #[test]
    fn a_crlf_table_error_is_placed_at_the_files_line() {
        // rust-csv counts a line only at a `\n` it consumes: straight on a
        // CRLF file, the bad cell of line 4 is placed at line 3.
        let text = b"x,y\r\n1,2\r\n3,4\r\n5,abc\r\n6,7\r\n";
        fn bad_line<R: Read>(r: csv::Reader<R>) -> Option<u64> {
            r.into_records().find_map(|rec| {
                let rec = rec.ok()?;
                (&rec[1] == "abc").then(|| rec.position().map_or(0, csv::Position::line))
            })
        }
        let plain = csv::Reader::from_reader(&text[..]);
        assert_eq!(bad_line(plain), Some(3), "rust-csv fixed issue 395?");
        let bounded = csv::Reader::from_reader(BoundedLines::new(&text[..], 100));
        assert_eq!(bad_line(bounded), Some(4));
    }
}
