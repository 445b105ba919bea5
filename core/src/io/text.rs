//! Shared plumbing of the readers and writers: reading a file as UTF-8,
//! byte offsets to lines, the CSV dialect (see the `io` module docs), number
//! parsing and formatting.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;

use crate::error::InputError;

/// Reads a whole file as UTF-8; returns the name to use in messages and the
/// text. Invalid UTF-8 is reported with its line.
pub(crate) fn read_text(path: &Path) -> Result<(String, String), InputError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| InputError::io(&file, e))?;
    match String::from_utf8(bytes) {
        Ok(text) => Ok((file, text)),
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
            Err(InputError::line_error(
                file,
                line,
                "not valid UTF-8 text (save the file as UTF-8)",
            ))
        }
    }
}

/// The 1-based line of a byte offset (offsets past the end give the last line).
pub(crate) fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    1 + text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// The shortest decimal form of `x` that parses back to exactly `x`
/// (Rust's `{:?}`: `0.1`, `-90.0`, `1e-7`, `1e16`; `NaN`, `inf`, `-inf`).
pub(crate) fn fmt_f64(x: f64) -> String {
    format!("{x:?}")
}

/// One CSV record and its 1-based line.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Record {
    pub line: usize,
    pub fields: Vec<String>,
}

/// Splits CSV text into records, skipping comments and trailing blank lines;
/// a blank line followed by more data is an error.
pub(crate) fn records(text: &str, file: &str) -> Result<Vec<Record>, InputError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out = Vec::new();
    let mut pending_blank: Option<usize> = None;
    for (i, raw) in text.split('\n').enumerate() {
        let line = i + 1;
        let content = raw.strip_suffix('\r').unwrap_or(raw);
        let trimmed = content.trim();
        if trimmed.is_empty() {
            pending_blank.get_or_insert(line);
            continue;
        }
        if trimmed.starts_with('#') {
            continue;
        }
        if let Some(blank) = pending_blank {
            return Err(InputError::line_error(
                file,
                blank,
                format!(
                    "blank line before more data (line {line}); only trailing blank lines \
                     are allowed: delete it, or start it with `#` to make it a comment"
                ),
            ));
        }
        out.push(Record {
            line,
            fields: split_fields(content, file, line)?,
        });
    }
    Ok(out)
}

/// Splits one line into fields (see the dialect in the `io` module docs).
fn split_fields(line_text: &str, file: &str, line: usize) -> Result<Vec<String>, InputError> {
    let mut fields = Vec::new();
    let mut chars = line_text.chars().peekable();
    loop {
        // Start of a field.
        while chars.peek().is_some_and(|&c| c == ' ' || c == '\t') {
            chars.next();
        }
        let mut field = String::new();
        if chars.peek() == Some(&'"') {
            chars.next();
            let column = fields.len() + 1;
            loop {
                match chars.next() {
                    None => {
                        return Err(InputError::line_error(
                            file,
                            line,
                            format!("unterminated quote in column {column}"),
                        ));
                    }
                    Some('"') if chars.peek() == Some(&'"') => {
                        chars.next();
                        field.push('"');
                    }
                    Some('"') => break,
                    Some(c) => field.push(c),
                }
            }
            while chars.peek().is_some_and(|&c| c == ' ' || c == '\t') {
                chars.next();
            }
            match chars.peek() {
                None | Some(',') => {}
                Some(&c) => {
                    return Err(InputError::line_error(
                        file,
                        line,
                        format!("unexpected `{c}` after the closing quote of column {column}"),
                    ));
                }
            }
        } else {
            while let Some(&c) = chars.peek() {
                if c == ',' {
                    break;
                }
                if c == '"' {
                    return Err(InputError::line_error(
                        file,
                        line,
                        format!(
                            "stray `\"` in column {}; quote the whole field, and double \
                             quotes inside it",
                            fields.len() + 1
                        ),
                    ));
                }
                field.push(c);
                chars.next();
            }
            field.truncate(field.trim_end_matches([' ', '\t']).len());
        }
        fields.push(field);
        match chars.next() {
            Some(',') => continue,
            _ => return Ok(fields),
        }
    }
}

/// Quotes a field for writing if reading it back would otherwise change it.
pub(crate) fn quote(field: &str) -> Cow<'_, str> {
    let needs = field.is_empty()
        || field.starts_with('#')
        || field.starts_with([' ', '\t'])
        || field.ends_with([' ', '\t'])
        || field.contains([',', '"', '\n', '\r'])
        || field.starts_with('\u{feff}');
    if needs {
        Cow::Owned(format!("\"{}\"", field.replace('"', "\"\"")))
    } else {
        Cow::Borrowed(field)
    }
}

/// Errors on a repeated column name in a header.
pub(crate) fn check_unique_columns(header: &Record, file: &str) -> Result<(), InputError> {
    let mut seen: HashMap<&str, usize> = HashMap::new();
    for (i, name) in header.fields.iter().enumerate() {
        if let Some(first) = seen.insert(name, i + 1) {
            return Err(InputError::field(
                file,
                header.line,
                name.clone(),
                format!(
                    "duplicate column (columns {first} and {}) in the header",
                    i + 1
                ),
            ));
        }
    }
    Ok(())
}

/// Checks a header against the expected column names: the same names, in the
/// same order. `expected_text` is shown in messages (e.g. `point,x,y,z`).
pub(crate) fn check_header(
    header: &Record,
    file: &str,
    expected: &[&str],
    expected_text: &str,
) -> Result<(), InputError> {
    check_unique_columns(header, file)?;
    for (i, want) in expected.iter().enumerate() {
        match header.fields.get(i) {
            Some(got) if got == want => {}
            Some(got) => {
                return Err(InputError::field(
                    file,
                    header.line,
                    got.clone(),
                    format!(
                        "unexpected column {} in the header: expected `{want}`; the header \
                         must be exactly `{expected_text}`",
                        i + 1
                    ),
                ));
            }
            None => {
                return Err(InputError::field(
                    file,
                    header.line,
                    *want,
                    format!(
                        "missing column {} in the header; the header must be exactly \
                         `{expected_text}`",
                        i + 1
                    ),
                ));
            }
        }
    }
    if let Some(extra) = header.fields.get(expected.len()) {
        return Err(InputError::field(
            file,
            header.line,
            extra.clone(),
            format!(
                "unexpected column {} in the header; the header must be exactly \
                 `{expected_text}`",
                expected.len() + 1
            ),
        ));
    }
    Ok(())
}

/// Checks that a data row has as many fields as the header.
pub(crate) fn check_row_width(
    row: &Record,
    file: &str,
    columns: &[String],
) -> Result<(), InputError> {
    let (got, want) = (row.fields.len(), columns.len());
    if got < want {
        // `got == 1` with an empty field is an all-blank row: still name the
        // first missing column.
        return Err(InputError::field(
            file,
            row.line,
            columns[got].clone(),
            format!("missing: the row has {got} columns, the header {want}"),
        ));
    }
    if got > want {
        return Err(InputError::line_error(
            file,
            row.line,
            format!(
                "the row has {got} columns, the header {want} (`{}`)",
                columns.join(",")
            ),
        ));
    }
    Ok(())
}

/// Parses a finite number from a CSV field.
pub(crate) fn parse_f64(s: &str, file: &str, line: usize, field: &str) -> Result<f64, InputError> {
    if s.is_empty() {
        return Err(InputError::field(file, line, field, "missing value"));
    }
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) if x.is_nan() || s.to_ascii_lowercase().contains("inf") => Err(InputError::field(
            file,
            line,
            field,
            format!("`{s}` is not a finite number"),
        )),
        Ok(_) => Err(InputError::field(
            file,
            line,
            field,
            format!("`{s}` is out of range of finite numbers"),
        )),
        Err(_) => Err(InputError::field(
            file,
            line,
            field,
            format!("`{s}` is not a number"),
        )),
    }
}

/// The candidate closest to `got` by edit distance, if it is close (a typo).
pub(crate) fn suggest<'a>(got: &str, candidates: &[&'a str]) -> Option<&'a str> {
    candidates
        .iter()
        .map(|&c| (edit_distance(got, c), c))
        .filter(|&(d, c)| d > 0 && d <= (c.chars().count() / 3).max(1))
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// Levenshtein distance, with a transposition counting as one edit.
fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut v = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                v = v.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = v;
        }
    }
    d[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields(line: &str) -> Vec<String> {
        split_fields(line, "f", 1).unwrap()
    }

    #[test]
    fn splitting() {
        assert_eq!(fields("a,b , c"), ["a", "b", "c"]);
        assert_eq!(fields(""), [""]);
        assert_eq!(fields("a,"), ["a", ""]);
        assert_eq!(
            fields("\"a,b\", \"x\"\"y\" ,\" s \""),
            ["a,b", "x\"y", " s "]
        );
        assert_eq!(fields("\"\""), [""]);
        let e = split_fields("a,\"b", "f.csv", 4).unwrap_err().to_string();
        assert_eq!(e, "f.csv:4: unterminated quote in column 2");
        let e = split_fields("a,\"b\"c", "f.csv", 4)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("f.csv:4: unexpected `c`"), "{e}");
        let e = split_fields("a,b\"c", "f.csv", 4).unwrap_err().to_string();
        assert!(e.starts_with("f.csv:4: stray"), "{e}");
    }

    #[test]
    fn quoting_round_trips() {
        for s in ["a", "", "#x", " a", "a ", "a,b", "x\"y", "S 1", "\u{feff}x"] {
            let q = quote(s);
            assert_eq!(fields(&q), [s], "{s:?} -> {q}");
        }
        assert_eq!(quote("S1"), "S1");
    }

    #[test]
    fn records_skip_comments_and_trailing_blanks() {
        let t = "\u{feff}# c\nh1,h2\r\n  # c2\n1,2\n\n \n# end\n";
        let r = records(t, "f").unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].line, 2);
        assert_eq!(r[0].fields, ["h1", "h2"]);
        assert_eq!(r[1].line, 4);
        let e = records("h\n\n1\n", "f.csv").unwrap_err();
        assert_eq!(e.line(), Some(2));
        assert!(e.to_string().starts_with("f.csv:2: blank line"), "{e}");
        assert!(records("", "f").unwrap().is_empty());
    }

    #[test]
    fn numbers() {
        assert_eq!(parse_f64("1.5", "f", 1, "x").unwrap(), 1.5);
        assert_eq!(parse_f64("-1e-7", "f", 1, "x").unwrap(), -1e-7);
        for (s, want) in [
            ("", "missing value"),
            ("abc", "not a number"),
            ("NaN", "not a finite"),
            ("-inf", "not a finite"),
            ("infinity", "not a finite"),
            ("1e400", "out of range"),
        ] {
            let e = parse_f64(s, "f.csv", 3, "q1").unwrap_err().to_string();
            assert!(e.starts_with("f.csv:3: field `q1`: "), "{e}");
            assert!(e.contains(want), "{s}: {e}");
        }
    }

    #[test]
    fn shortest_round_trip_format() {
        for x in [
            0.1,
            -90.0,
            1e-7,
            1e16,
            123456.789,
            -0.0,
            f64::MIN_POSITIVE,
            f64::MAX,
        ] {
            let s = fmt_f64(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
    }

    #[test]
    fn suggestions() {
        let keys = ["theta", "alpha", "beta", "a", "d", "limits"];
        assert_eq!(suggest("alpah", &keys), Some("alpha"));
        assert_eq!(suggest("theat", &keys), Some("theta"));
        assert_eq!(suggest("limit", &keys), Some("limits"));
        assert_eq!(suggest("b", &keys), Some("a"));
        assert_eq!(suggest("zzzzzz", &keys), None);
        assert_eq!(suggest("alpha", &keys), None);
    }

    #[test]
    fn lines() {
        let t = "a\nb\nc";
        assert_eq!(line_of(t, 0), 1);
        assert_eq!(line_of(t, 2), 2);
        assert_eq!(line_of(t, 100), 3);
    }
}
