//! What the first bytes of a CSV file say about its layout, before the CSV
//! reader sees it: the encodings and separators spreadsheets write instead of
//! formats.md's (UTF-8, `,` between columns, `.` as the decimal point, plain
//! header names), each found and named with what is expected.

use std::io::Read;
use std::path::Path;

/// How a file may be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Bytes to skip at the start (a UTF-8 byte-order mark).
    pub skip: u64,
}

/// Why a file cannot be read as formats.md's CSV.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LayoutError {
    /// Not a regular file (a FIFO, a device, a directory).
    NotAFile(String),
    /// A layout problem at a line (1-based): what was found and what is expected.
    At(u64, String),
}

/// Checks `path`: a regular file, UTF-8, and a header in formats.md's layout
/// (`expected` is the header Plinth wants, e.g. `speed_hz,bearing,...`).
/// Headers that already name `first` (the first expected column) with `,`
/// separators pass unchanged; anything else that looks like a spreadsheet
/// export is described.
pub fn check(path: &Path, expected: &str) -> Result<Layout, LayoutError> {
    crate::input_file::ensure_regular(path).map_err(|e| LayoutError::NotAFile(e.to_string()))?;
    let mut head = Vec::with_capacity(4096);
    std::fs::File::open(path)
        .and_then(|f| f.take(4096).read_to_end(&mut head))
        .map_err(|e| LayoutError::NotAFile(e.to_string()))?;
    describe(&head, expected)
}

/// [`check`], then the file opened past its byte-order mark behind a
/// [`crate::input_file::BoundedLines`] reader (lines of at most
/// [`crate::input_file::MAX_LINE_BYTES`], no NUL bytes, and no more lines
/// than the memory available holds as table rows,
/// [`crate::sim::budget::table_lines`]): what every CSV reader of a table
/// reads from.
pub fn open(
    path: &Path,
    expected: &str,
) -> Result<std::io::BufReader<crate::input_file::BoundedLines<std::fs::File>>, LayoutError> {
    let available = crate::sim::budget::available_bytes();
    let lines = open_stream(path, expected)?;
    Ok(
        match crate::sim::budget::table_lines(available).zip(available) {
            Some((most, a)) => std::io::BufReader::new(lines.into_inner().with_max_lines(most, a)),
            None => lines,
        },
    )
}

/// [`open`] without the bound on lines: a recording, read a block at a time
/// (its memory does not grow with its length).
pub fn open_stream(
    path: &Path,
    expected: &str,
) -> Result<std::io::BufReader<crate::input_file::BoundedLines<std::fs::File>>, LayoutError> {
    let layout = check(path, expected)?;
    let mut handle = std::fs::File::open(path).map_err(|e| LayoutError::NotAFile(e.to_string()))?;
    std::io::Seek::seek(&mut handle, std::io::SeekFrom::Start(layout.skip))
        .map_err(|e| LayoutError::NotAFile(e.to_string()))?;
    Ok(std::io::BufReader::new(
        crate::input_file::BoundedLines::new(handle, crate::input_file::MAX_LINE_BYTES),
    ))
}

/// [`check`] on the first bytes of a file.
pub fn describe(head: &[u8], expected: &str) -> Result<Layout, LayoutError> {
    let at1 = |m: String| Err(LayoutError::At(1, m));
    if let Some(found) = crate::input_file::utf16_found(head) {
        return at1(format!(
            "{found}; expected UTF-8: save it as \"CSV UTF-8\" (Excel) or convert it (iconv -f UTF-16 -t UTF-8)"
        ));
    }
    let skip = if head.starts_with(crate::input_file::UTF8_BOM) {
        crate::input_file::UTF8_BOM.len()
    } else {
        0
    };
    let text = String::from_utf8_lossy(&head[skip..]);
    let line = text.lines().next().unwrap_or("").trim_end_matches('\r');
    let first = expected.split(',').next().unwrap_or("");
    let plain = line.split(',').map(str::trim).any(|f| f == first);
    if plain || line.trim().is_empty() {
        return Ok(Layout { skip: skip as u64 });
    }
    let shown: String = line.chars().take(60).collect();
    let ellipsis = if line.chars().count() > 60 { "..." } else { "" };
    let found = format!("`{shown}{ellipsis}`");
    if line.contains(';') && !line.contains(',') {
        let comma_decimals = text
            .lines()
            .nth(1)
            .is_some_and(|l| l.split(';').any(|f| is_comma_decimal(f.trim())));
        let decimals = if comma_decimals {
            " with decimal commas (a European spreadsheet export)"
        } else {
            ""
        };
        return at1(format!(
            "the header {found} is separated by `;`{decimals}; expected `,` between columns and `.` as the decimal point: `{expected}` (export with a comma list separator, or convert: sed 's/,/./g; s/;/,/g')"
        ));
    }
    if line.contains('\t') {
        return at1(format!(
            "the header {found} is tab-separated; expected `,` between columns: `{expected}` (convert: tr '\\t' ',')"
        ));
    }
    let unquoted: Vec<String> = line
        .split(',')
        .map(|f| f.trim().trim_matches('"').trim_matches('\'').to_string())
        .collect();
    if line.contains('"') && unquoted.iter().any(|f| f == first) {
        return at1(format!(
            "the header {found} has its names in quotes; expected plain names: `{expected}`"
        ));
    }
    if unquoted.iter().any(|f| f.eq_ignore_ascii_case(first)) {
        return at1(format!(
            "the header {found} names the columns in another case; expected exactly `{expected}`"
        ));
    }
    Ok(Layout { skip: skip as u64 })
}

/// `12,5` or `-0,003`: a number written with a decimal comma.
fn is_comma_decimal(f: &str) -> bool {
    let f = f.trim_matches('"');
    f.contains(',') && f.replacen(',', ".", 1).parse::<f64>().is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    const EXPECTED: &str = "speed_hz,bearing,rel_y_re";

    fn msg(bytes: &[u8]) -> String {
        match describe(bytes, EXPECTED) {
            Err(LayoutError::At(1, m)) => m,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn spreadsheet_layouts_are_named() {
        assert_eq!(
            describe(b"speed_hz,bearing,rel_y_re\n5,left,1e-6\n", EXPECTED),
            Ok(Layout { skip: 0 })
        );
        assert_eq!(
            describe(b"\xEF\xBB\xBFspeed_hz,bearing\n", EXPECTED),
            Ok(Layout { skip: 3 })
        );
        let m = msg(b"speed_hz;bearing;rel_y_re\n5,5;left;1,2E-06\n");
        assert!(m.contains("`;`") && m.contains("decimal commas"), "{m}");
        assert!(msg(b"speed_hz\tbearing\n").contains("tab-separated"));
        assert!(msg(b"\"speed_hz\",\"bearing\"\n").contains("in quotes"));
        let utf16: Vec<u8> = [0xFF, 0xFE]
            .into_iter()
            .chain("speed_hz,".bytes().flat_map(|b| [b, 0]))
            .collect();
        assert!(msg(&utf16).contains("UTF-16"));
        assert!(msg(&utf16[2..]).contains("NUL bytes"));
        assert!(msg(b"Speed_Hz,Bearing\n").contains("another case"));
    }
}
