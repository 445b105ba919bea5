//! Shared plumbing of the readers and writers: reading a file (or standard
//! input) as UTF-8, byte offsets to lines, the CSV dialect (see the `io`
//! module docs) on top of the `csv` crate, number parsing and formatting.

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use csv::{ReaderBuilder, StringRecord, Terminator, Trim};

use crate::error::{InputError, quoted};

/// The name readers give `path` in messages: `<stdin>` for `-`, else the
/// path as it displays.
///
/// ```
/// use aacmm_core::io::source_name;
/// assert_eq!(source_name(std::path::Path::new("-")), "<stdin>");
/// assert_eq!(source_name(std::path::Path::new("data/p.csv")), "data/p.csv");
/// ```
pub fn source_name(path: &Path) -> String {
    if path.as_os_str() == "-" {
        "<stdin>".to_string()
    } else {
        path.display().to_string()
    }
}

/// The longest line a reader accepts: far beyond any header or row of the
/// toolkit's files (a 7-joint row is about 100 bytes), short enough that a
/// hostile file of one endless line is refused after 1 MiB rather than held
/// whole, copied into a header and echoed.
pub(crate) const MAX_LINE: usize = 1 << 20;

/// The largest settings file (an arm, a campaign) read: thousands of times
/// what one holds (a few kilobytes), so that a hostile or mistaken file is
/// refused before its whole text and its parse are held.
pub(crate) const MAX_SETTINGS: usize = 16 << 20;

/// [`read_text`] for a settings file (TOML): one larger than
/// [`MAX_SETTINGS`] is refused, by its size before it is read, or as
/// soon as that much was read from standard input.
pub(crate) fn read_settings(path: &Path) -> Result<(String, String), InputError> {
    read_at_most(path, MAX_SETTINGS)
}

/// What [`read_from`] reads at a time. At most [`MAX_LINE`]: a line inside
/// one chunk is then never too long, and only lines across chunks are
/// checked.
const CHUNK: usize = 1 << 20;
const _: () = assert!(CHUNK <= MAX_LINE);

/// Reads a whole file as UTF-8, or standard input for the path `-` (the Unix
/// convention); returns the name to use in messages ([`source_name`]) and
/// the text.
///
/// Memory: the file's size, reserved up front (fallibly: a file larger than
/// the process can hold is an [`InputError::Memory`], not an abort), and a
/// line longer than [`MAX_LINE`] is refused as soon as it is read.
pub(crate) fn read_text(path: &Path) -> Result<(String, String), InputError> {
    read_at_most(path, usize::MAX)
}

/// [`read_text`], refusing a file of more than `max` bytes.
fn read_at_most(path: &Path, max: usize) -> Result<(String, String), InputError> {
    let file = source_name(path);
    if path.as_os_str() == "-" {
        read_from(file, std::io::stdin().lock(), 0, max)
    } else {
        let f = std::fs::File::open(path).map_err(|e| InputError::io(&file, e))?;
        // The size is a hint (a file may grow or be a device): reading
        // still goes to the end.
        let size = f.metadata().map_or(0, |m| m.len());
        let size = usize::try_from(size).unwrap_or(usize::MAX);
        if size > max {
            return Err(too_large(&file, max));
        }
        read_from(file, f, size, max)
    }
}

/// The error for a file of more than `max` bytes (a settings file).
fn too_large(file: &str, max: usize) -> InputError {
    let message = format!(
        "larger than {} MiB: not a settings file of this toolkit (an arm or campaign file \
         holds a few kilobytes); check that this is the intended file",
        max >> 20
    );
    InputError::file_error(file, message)
}

/// Reads everything from `r` as UTF-8 text named `file`, with room for
/// `size` bytes reserved first; invalid UTF-8 is reported with its line,
/// and so is a line longer than [`MAX_LINE`]; more than `max` bytes are
/// refused as soon as they are read.
fn read_from(
    file: String,
    mut r: impl Read,
    size: usize,
    max: usize,
) -> Result<(String, String), InputError> {
    let mut bytes: Vec<u8> = Vec::new();
    // The whole file's room at once when it can be had (no copies while
    // growing); else room as it is read, so that a file too large to hold
    // is still refused for its first overlong line, if it has one, and
    // otherwise for its size once that much was read.
    _ = bytes.try_reserve_exact(size.saturating_add(1));
    // Bytes since the last line feed, before the chunk being read.
    let mut run = 0usize;
    loop {
        let start = bytes.len();
        if bytes.capacity() == start {
            crate::memory::try_grow(&mut bytes, "reading the file", CHUNK)
                .map_err(|e| InputError::memory(&file, e))?;
        }
        // Into the room there is (the end of a file reserved whole is
        // found without growing), a chunk at most.
        let room = (bytes.capacity() - start).min(CHUNK);
        // `read_to_end` retries an interrupted read itself; fewer bytes
        // than asked for means the end (a terminal's Ctrl-D is not asked
        // for twice).
        let n = (&mut r)
            .take(room as u64)
            .read_to_end(&mut bytes)
            .map_err(|e| InputError::io(&file, e))?;
        if bytes.len() > max {
            return Err(too_large(&file, max));
        }
        let chunk = &bytes[start..];
        run = match (
            chunk.iter().position(|&b| b == b'\n'),
            chunk.iter().rposition(|&b| b == b'\n'),
        ) {
            (Some(first), Some(last)) if run + first <= MAX_LINE => n - 1 - last,
            (None, _) if run + n <= MAX_LINE => run + n,
            _ => return Err(too_long(&file, &bytes[..start], chunk)),
        };
        if n < room {
            break;
        }
    }
    // Room grown by doubling (standard input, a file that grew) is given
    // back rather than held beside the rows the text becomes.
    if bytes.capacity() > bytes.len().saturating_add(CHUNK) {
        bytes.shrink_to_fit();
    }
    match String::from_utf8(bytes) {
        Ok(text) => Ok((file, text)),
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
            let message = "not valid UTF-8 text (save the file as UTF-8)";
            Err(InputError::line_error(file, line, message))
        }
    }
}

/// The error for a line longer than [`MAX_LINE`] that started in `before`
/// (the bytes read before `chunk`, where it grew too long): said to be
/// lines ended by a carriage return alone when it holds one, as
/// [`cr_only`] says of a shorter file.
fn too_long(file: &str, before: &[u8], chunk: &[u8]) -> InputError {
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    // The overlong line's part of the chunk; a carriage return before its
    // end (not the CR of a CRLF) ends lines alone.
    let part = &chunk[..chunk
        .iter()
        .position(|&b| b == b'\n')
        .unwrap_or(chunk.len())];
    if part
        .iter()
        .enumerate()
        .any(|(i, &b)| b == b'\r' && i + 1 < part.len())
    {
        return InputError::line_error(file, line, CR_ONLY);
    }
    let message = format!(
        "line longer than {} MiB: not a table or settings file of this toolkit (each \
         line is a header, a row or a setting); check that this is the intended file",
        MAX_LINE >> 20
    );
    InputError::line_error(file, line, message)
}

/// The 1-based line of a byte offset (offsets past the end give the last line).
pub(crate) fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    1 + text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// `text` parsed as a TOML document, a syntax error located by line in
/// `file`.
pub(crate) fn parse_toml<'a>(
    text: &'a str,
    file: &str,
) -> Result<toml::Spanned<toml::de::DeTable<'a>>, InputError> {
    toml::de::DeTable::parse(text).map_err(|e| {
        let message = format!("TOML syntax: {}", e.message());
        match e.span() {
            Some(span) => InputError::line_error(file, line_of(text, span.start), message),
            None => InputError::file_error(file, message),
        }
    })
}

/// The shortest decimal form of `x` that parses back to exactly `x`
/// (Rust's `{:?}`: `0.1`, `-90.0`, `1e-7`, `1e16`; `NaN`, `inf`, `-inf`).
pub(crate) fn fmt_f64(x: f64) -> String {
    format!("{x:?}")
}

/// `,` and [`fmt_f64`]'s form of `x` appended to `line`: a table's next
/// cell, without a string of its own.
pub(crate) fn push_f64(line: &mut String, x: f64) {
    use std::fmt::Write as _;
    line.push(',');
    // Writing to a String cannot fail.
    let _ = write!(line, "{x:?}");
}

/// One CSV record and its 1-based line.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Record {
    pub(crate) line: usize,
    pub(crate) fields: Vec<String>,
}

/// Reads a CSV table row by row: the header goes to `check_header`, each
/// data row (as wide as the header) to `row`, with the header, its line and
/// its fields, trimmed. Returns the header. `shape` and `rows_are` complete the message
/// of an empty file (`point,x,y,z`, `one row per point`).
///
/// The error is the one of reading every record first and checking them in
/// stages, whatever their order in the file: a malformed record (a blank line
/// before more data, a quote left open) wins over a header error, which wins
/// over an empty file or one without data rows, over the first row of the
/// wrong width, over the first error `row` returns (after which `row` is not
/// called again).
pub(crate) fn scan_table(
    text: &str,
    file: &str,
    shape: &str,
    rows_are: &str,
    check_header: impl FnOnce(&Record) -> Result<(), InputError>,
    mut row: impl FnMut(&Record, usize, &[&str]) -> Result<(), InputError>,
) -> Result<Record, InputError> {
    let mut check_header = Some(check_header);
    let mut header: Option<Record> = None;
    let (mut header_error, mut width_error, mut row_error) = (None, None, None);
    let mut rows = 0usize;
    each_record(text, file, |line, fields| {
        let Some(h) = &header else {
            let h = Record {
                line,
                fields: fields.iter().map(|f| f.to_string()).collect(),
            };
            header_error = check_header.take().and_then(|check| check(&h).err());
            header = Some(h);
            return;
        };
        rows += 1;
        if header_error.is_some() || width_error.is_some() {
            return;
        }
        if let Err(e) = check_row_width(line, fields.len(), file, &h.fields) {
            width_error = Some(e);
        } else if row_error.is_none() {
            row_error = row(h, line, fields).err();
        }
    })?;
    let Some(header) = header else {
        return Err(InputError::file_error(
            file,
            format!("empty file; expected the header `{shape}` and {rows_are}"),
        ));
    };
    if let Some(e) = header_error {
        return Err(e);
    }
    if rows == 0 {
        return Err(InputError::file_error(
            file,
            format!("no data rows after the header (line {})", header.line),
        ));
    }
    match width_error.or(row_error) {
        Some(e) => Err(e),
        None => Ok(header),
    }
}

/// Calls `f` with the line and the trimmed fields of every record of CSV
/// text, in order; the dialect's errors (see [`records`]) stop it.
///
/// Text without a double quote after the comments (every data file this
/// toolkit writes, and any without quoted labels) is split here, byte by
/// byte, into fields borrowed from the text: the `csv` crate's records for
/// such text are its lines, less the blank ones, cut at every comma. Other
/// text goes through [`records`].
pub(crate) fn each_record(
    text: &str,
    file: &str,
    f: impl FnMut(usize, &[&str]),
) -> Result<(), InputError> {
    let original = text;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let (body, blank) = preamble(text);
    // The first line, and the header's (past comments).
    cr_only(text, 0, file)?;
    cr_only(text, body, file)?;
    if text.as_bytes()[body..].contains(&b'"') {
        return each_quoted(original, file, f);
    }
    let blanks = records_in(text, (body, text.len()), (line_of(text, body), blank), f);
    blanks.check(text, file, (blank, false)).map(|_| ())
}

/// The blank lines about the records of a stretch of lines: where a record
/// follows one, the text has a blank line before more data (an error), and
/// only the stretches around it tell whether one does.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Blanks {
    /// The line of the first record, if any.
    first: Option<usize>,
    /// The first blank line (its byte) before the first record, or in a
    /// stretch without records.
    lead: Option<usize>,
    /// The first blank line (its byte) before a later record, and that
    /// record's line: the stretch was read up to it, not past.
    inner: Option<(usize, usize)>,
    /// The first blank line (its byte) after the last record.
    trail: Option<usize>,
}

impl Blanks {
    /// The first blank line before more data in this stretch of lines
    /// (`pending`: a blank line before it, if any; `any`: whether a record
    /// came before it), as the error of [`each_record`]; else the blank
    /// line pending after it and whether a record came before its end.
    /// Stretches that follow each other are checked in turn.
    pub(super) fn check(
        self,
        text: &str,
        file: &str,
        (pending, any): (Option<usize>, bool),
    ) -> Result<(Option<usize>, bool), InputError> {
        let Some(first) = self.first else {
            return Ok((pending.or(self.lead), any));
        };
        if let Some(blank) = pending.or(self.lead) {
            return Err(blank_line(text, file, blank, first, any));
        }
        if let Some((blank, line)) = self.inner {
            return Err(blank_line(text, file, blank, line, true));
        }
        Ok((self.trail, true))
    }
}

/// Calls `f` with the line and the trimmed fields of every record of the
/// lines of unquoted `text` in `from..to` (whole lines; the first is line
/// `line`; `pending`, a blank line before them), in order, up to the first
/// record after a blank line; returns the blank lines about them.
pub(super) fn records_in(
    text: &str,
    (from, to): (usize, usize),
    (mut line, pending): (usize, Option<usize>),
    mut f: impl FnMut(usize, &[&str]),
) -> Blanks {
    let bytes = text.as_bytes();
    let (mut out, mut blank) = (Blanks::default(), pending);
    let mut pos = from;
    let mut fields: Vec<&str> = Vec::with_capacity(16);
    while pos < to {
        // One pass over the line for its commas and its end.
        fields.clear();
        let (mut start, mut end) = (pos, pos);
        while end < bytes.len() && bytes[end] != b'\n' {
            if bytes[end] == b',' {
                fields.push(trim(&text[start..end]));
                start = end + 1;
            }
            end += 1;
        }
        if fields.is_empty() && is_blank(&text[pos..end]) {
            blank.get_or_insert(pos);
        } else {
            // A record after a blank line is an error, whatever came
            // before: read no further.
            match (out.first, blank.take()) {
                (None, Some(b)) => {
                    (out.first, out.lead) = (Some(line), Some(b));
                    return out;
                }
                (None, None) => out.first = Some(line),
                (Some(_), Some(b)) => {
                    out.inner = Some((b, line));
                    return out;
                }
                (Some(_), None) => {}
            }
            fields.push(trim(&text[start..end]));
            f(line, &fields);
        }
        pos = end + 1;
        line += 1;
    }
    if out.first.is_none() {
        out.lead = blank;
    } else {
        out.trail = blank;
    }
    out
}

/// The message for lines ended by a carriage return alone.
const CR_ONLY: &str = "the file's lines end with a carriage return alone (CR, classic Mac OS \
                       line endings), so it reads as one line; save it with LF or CRLF line \
                       endings";

/// Refuses text whose line starting at byte `body` holds a carriage
/// return before its end: lines ended by CR alone (classic Mac OS), which
/// would read as one long line whose fields run into each other.
pub(super) fn cr_only(text: &str, body: usize, file: &str) -> Result<(), InputError> {
    let rest = &text.as_bytes()[body..];
    let line = &rest[..rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len())];
    match line.iter().position(|&b| b == b'\r') {
        Some(at) if at + 1 < line.len() => {
            Err(InputError::line_error(file, line_of(text, body), CR_ONLY))
        }
        _ => Ok(()),
    }
}

/// Whether a line is blank (whitespace only).
#[inline]
fn is_blank(line: &str) -> bool {
    match line.as_bytes().first() {
        None => true,
        Some(b) if b.is_ascii_graphic() => false,
        Some(_) => line.trim().is_empty(),
    }
}

/// A field without surrounding whitespace (`str::trim`, as the `csv`
/// crate's `Trim::All`), quick when there is none.
#[inline]
fn trim(field: &str) -> &str {
    match field.as_bytes() {
        [first, .., last] if first.is_ascii_graphic() && last.is_ascii_graphic() => field,
        [only] if only.is_ascii_graphic() => field,
        _ => field.trim(),
    }
}

/// Where the first record starts (past the comments and blank lines before
/// the header, and byte-order marks starting the header), and the first
/// blank line before it, if any. Comments are not tokenized: a quote in one
/// would open a field.
pub(super) fn preamble(text: &str) -> (usize, Option<usize>) {
    let (mut body, mut blank) = (0, None);
    for l in text.split_inclusive('\n') {
        match l.trim() {
            "" => _ = blank.get_or_insert(body),
            t if t.starts_with('#') => {}
            _ => break,
        }
        body += l.len();
    }
    (
        text.len() - text[body..].trim_start_matches('\u{feff}').len(),
        blank,
    )
}

/// The error for a blank line (at byte `blank`) before the record on
/// `line`; `after_records` when a record came before it.
fn blank_line(
    text: &str,
    file: &str,
    blank: usize,
    line: usize,
    after_records: bool,
) -> InputError {
    let hint = if after_records {
        ""
    } else {
        ", or start it with `#` to make it a comment"
    };
    let message = format!(
        "blank line before more data (line {line}); only trailing blank lines are \
         allowed: delete it{hint}"
    );
    InputError::line_error(file, line_of(text, blank), message)
}

/// Every record of `text` (see [`each_quoted`]), collected.
#[cfg(test)]
pub(crate) fn records(text: &str, file: &str) -> Result<Vec<Record>, InputError> {
    let mut out = Vec::new();
    each_quoted(text, file, |line, fields| {
        out.push(Record {
            line,
            fields: fields.iter().map(|f| f.to_string()).collect(),
        })
    })?;
    Ok(out)
}

/// Splits CSV text into records: the reading of text with quotes (see
/// [`each_record`]). The `csv` crate tokenizes; this layer keeps
/// the rules of the dialect (see the `io` module docs) and the lines: each
/// record's line comes from its byte offset, which the crate gets right where
/// its line counter is not (after blank lines, with CRLF: rust-csv#208, #395).
///
/// Calls `f` with the line and the fields of each record, one record held
/// at a time (a quoted field that spans lines makes its record as long as
/// it is); lines are counted as the records advance, not indexed.
fn each_quoted(
    text: &str,
    file: &str,
    mut f: impl FnMut(usize, &[&str]),
) -> Result<(), InputError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // Lines counted as the records advance: `line` is that of byte `counted`.
    let (mut counted, mut line) = (0usize, 1usize);
    let mut line_of_start = |start: usize| {
        line += text.as_bytes()[counted..start]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        counted = start;
        line
    };
    // Blank lines before the header are remembered, as blank lines are
    // errors before more data.
    let (body, mut blank) = preamble(text);
    // A sentinel record after the text: a quote left open swallows it.
    let input = text.as_bytes()[body..].chain(&b"\n\0"[..]);
    let mut reader = ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(Trim::All)
        .terminator(Terminator::Any(b'\n'))
        .from_reader(input);
    let mut rec = StringRecord::new();
    // The last record's line and width, for an unterminated quote.
    let mut last: Option<(usize, usize)> = None;
    let unreadable = |e: csv::Error| InputError::file_error(file, e.to_string());
    while reader.read_record(&mut rec).map_err(unreadable)? {
        // The crate's offset is before the empty lines it skipped.
        let at = (body + rec.position().map_or(0, |p| p.byte() as usize)).min(text.len());
        let start = text.len() - text[at..].trim_start_matches('\n').len();
        if start == text.len() {
            return Ok(());
        }
        if start > at {
            blank.get_or_insert(at);
        }
        let end = (body + reader.position().byte() as usize).min(text.len());
        if text[start..end].trim().is_empty() {
            blank.get_or_insert(start);
            continue;
        }
        let line = line_of_start(start);
        if let Some(blank) = blank {
            return Err(blank_line(text, file, blank, line, last.is_some()));
        }
        let fields: Vec<&str> = rec.iter().collect();
        f(line, &fields);
        last = Some((line, fields.len()));
    }
    let (line, column) = last.unwrap_or((1, 1));
    let message = format!("unterminated quote in column {column}");
    Err(InputError::line_error(file, line, message))
}

/// A label as a CSV field to write, quoted where reading would otherwise
/// split or change it; an [`invalid`] error for surrounding whitespace,
/// which reading trims, quoted or not.
pub(crate) fn quote(label: &str) -> std::io::Result<Cow<'_, str>> {
    if label.trim() != label {
        let message = format!(
            "label {}: surrounding whitespace does not read back",
            quoted(label)
        );
        return Err(invalid(message));
    }
    Ok(
        if label.is_empty() || label.contains([',', '"', '\n', '\r']) {
            Cow::Owned(format!("\"{}\"", label.replace('"', "\"\"")))
        } else {
            Cow::Borrowed(label)
        },
    )
}

/// An [`std::io::ErrorKind::InvalidInput`] error: what a writer cannot write.
pub(crate) fn invalid(message: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, message)
}

/// Checks a header against the expected column names: the same names, in the
/// same order, none repeated. `shape` is shown in messages (e.g. `point,x,y,z`).
pub(crate) fn check_header(
    header: &Record,
    file: &str,
    expected: &[&str],
    shape: &str,
) -> Result<(), InputError> {
    let got = &header.fields;
    let mut seen: HashMap<&str, usize> = HashMap::new();
    for (i, name) in got.iter().enumerate() {
        if let Some(first) = seen.insert(name, i + 1) {
            let message = format!(
                "duplicate column (columns {first} and {}) in the header",
                i + 1
            );
            return Err(InputError::field(file, header.line, name.clone(), message));
        }
    }
    for i in 0..got.len().max(expected.len()) {
        let column = i + 1;
        let (field, what) = match (got.get(i), expected.get(i)) {
            (Some(g), Some(w)) if g == w => continue,
            (Some(g), Some(w)) => (
                g.as_str(),
                format!("unexpected column {column} in the header: expected `{w}`"),
            ),
            (None, Some(w)) => (*w, format!("missing column {column} in the header")),
            (Some(g), None) => (
                g.as_str(),
                format!("unexpected column {column} in the header"),
            ),
            (None, None) => continue,
        };
        let message = format!("{what}; the header must be `{shape}`");
        return Err(InputError::field(file, header.line, field, message));
    }
    Ok(())
}

/// Checks that the data row on `line`, of `got` fields, is as wide as the
/// header.
pub(crate) fn check_row_width(
    line: usize,
    got: usize,
    file: &str,
    columns: &[String],
) -> Result<(), InputError> {
    let want = columns.len();
    if got < want {
        return Err(InputError::field(
            file,
            line,
            columns[got].clone(),
            format!("missing: the row has {got} columns, the header {want}"),
        ));
    }
    if got > want {
        return Err(InputError::line_error(
            file,
            line,
            format!(
                "the row has {got} columns, the header {want} ({})",
                quoted(&columns.join(","))
            ),
        ));
    }
    Ok(())
}

/// Parses a finite number from a CSV field.
///
/// `fast_float2` reads what the standard parser reads as a finite number
/// (`[+-]digits[.digits][(e|E)[+-]digits]`), correctly rounded as it is, so
/// the bits are the same; anything else (and a value out of range) goes to
/// the standard parser for its verdict and the message.
#[inline]
pub(crate) fn parse_f64(s: &str, file: &str, line: usize, field: &str) -> Result<f64, InputError> {
    match fast_float2::parse::<f64, _>(s) {
        Ok(x) if x.is_finite() => Ok(x),
        _ => parse_f64_slow(s, file, line, field),
    }
}

/// [`parse_f64`] by the standard parser, with the message of each failure.
#[cold]
fn parse_f64_slow(s: &str, file: &str, line: usize, field: &str) -> Result<f64, InputError> {
    let problem = match s.parse::<f64>() {
        Ok(x) if x.is_finite() => return Ok(x),
        _ if s.is_empty() => "missing value".to_string(),
        Ok(x) if x.is_nan() || s.to_ascii_lowercase().contains("inf") => {
            format!("{} is not a finite number", quoted(s))
        }
        Ok(_) => format!("{} is out of range of finite numbers", quoted(s)),
        Err(_) => format!("{} is not a number", quoted(s)),
    };
    Err(InputError::field(file, line, field, problem))
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

    /// The fields of `line`, read as the second record (after a header).
    fn fields(line: &str) -> Vec<String> {
        records(&format!("h\n{line}"), "f")
            .unwrap()
            .remove(1)
            .fields
    }

    #[test]
    fn splitting() {
        assert_eq!(fields("a,b , c"), ["a", "b", "c"]);
        assert_eq!(fields("a,"), ["a", ""]);
        assert_eq!(fields("\"a,b\",\"x\"\"y\" ,\"\""), ["a,b", "x\"y", ""]);
        // The csv crate's dialect: quoted fields are trimmed too; a quote
        // opens a quoted field only as the field's first character (else it
        // is literal); text after a closing quote is appended; a quoted field
        // may span lines.
        assert_eq!(fields("\" s \",\"x\" "), ["s", "x"]);
        assert_eq!(fields("a, \"b\",c\"d"), ["a", "\"b\"", "c\"d"]);
        assert_eq!(fields("\"a\"b,c"), ["ab", "c"]);
        assert_eq!(fields("\"a\n\nb\",c"), ["a\n\nb", "c"]);
        let e = records("# 1\n# 2\n# 3\na,\"b\n", "f.csv").unwrap_err();
        assert_eq!(e.to_string(), "f.csv:4: unterminated quote in column 2");
        let e = records("h\n1\n\"2\n3\n", "f.csv").unwrap_err();
        assert_eq!(e.to_string(), "f.csv:3: unterminated quote in column 1");
    }

    #[test]
    fn quoting_round_trips() {
        for s in [
            "a",
            "",
            "#x",
            "a,b",
            "x\"y",
            "\"x",
            "S 1",
            "a\nb",
            "\u{feff}x",
        ] {
            let q = quote(s).unwrap();
            assert_eq!(fields(&q), [s], "{s:?} -> {q}");
        }
        assert_eq!(quote("S1").unwrap(), "S1");
        for s in [" a", "a ", "\ta", "a\r"] {
            let e = quote(s).unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput, "{s:?}");
        }
    }

    #[test]
    fn cr_only_line_endings_are_named() {
        for text in [
            "h1,h2\r1,2\r3,4\r",
            "# c\rh1,h2\r1,2\r",
            "# c\nh1,h2\r1,\"2\"\r",
        ] {
            let mut seen = 0;
            let e = each_record(text, "f.csv", |_, _| seen += 1).unwrap_err();
            assert!(e.to_string().contains("carriage return alone"), "{e}");
            assert_eq!(seen, 0);
        }
        // CRLF, and a CR ending the last line, are line ends as before.
        let mut rows = Vec::new();
        each_record("h1,h2\r\n1,2\r\n3,4\r", "f.csv", |l, f| {
            rows.push((l, f.len()))
        })
        .unwrap();
        assert_eq!(rows, [(1, 2), (2, 2), (3, 2)]);
    }

    /// A field echoed in a message is bounded and its control characters
    /// escaped: a huge or garbled token cannot make a huge or garbled
    /// message.
    #[test]
    fn echoed_fields_are_bounded_and_escaped() {
        let huge = "9".repeat(1000) + "x";
        let e = parse_f64(&huge, "f.csv", 2, "q1").unwrap_err().to_string();
        assert!(e.len() < 300, "{e}");
        assert!(e.contains("…` (1001 characters) is not a number"), "{e}");
        let e = parse_f64("1\r\n\0", "f.csv", 2, "q1")
            .unwrap_err()
            .to_string();
        assert!(e.ends_with("`1\\r\\n\\0` is not a number"), "{e}");
        let label = "L".repeat(50_000);
        let text = format!("point,x\n{label},1\n{label},1\n");
        let e = scan_table(
            &text,
            "f.csv",
            "point,x",
            "rows",
            |_| Ok(()),
            |_, line, f| {
                Err(InputError::field(
                    "f.csv",
                    line,
                    "point",
                    format!("duplicate label {}", quoted(f[0])),
                ))
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.len() < 200 && e.contains("(50000 characters)"), "{e}");
    }

    #[test]
    fn records_skip_comments_and_trailing_blanks() {
        // Comments only before the header: after it, `# c2` is a record.
        let t = "\u{feff}# c\nh1,h2\r\n  # c2\n1,2\n\n \n";
        let r = records(t, "f").unwrap();
        assert_eq!(r.len(), 3);
        assert_eq!(r[0].line, 2);
        assert_eq!(r[0].fields, ["h1", "h2"]);
        assert_eq!(
            (r[1].line, r[1].fields.as_slice()),
            (3, ["# c2".to_string()].as_slice())
        );
        assert_eq!(r[2].line, 4);
        // A comment after the header and a blank line is data after a blank line.
        let e = records("h\n1\n\n# end\n", "f.csv").unwrap_err();
        assert!(e.to_string().starts_with("f.csv:3: blank line"), "{e}");
        assert!(!e.to_string().contains("comment"), "{e}");
        let e = records("h\n\n1\n", "f.csv").unwrap_err();
        assert_eq!(e.line(), Some(2));
        assert!(e.to_string().starts_with("f.csv:2: blank line"), "{e}");
        assert!(records("", "f").unwrap().is_empty());
        assert!(records("\u{feff}# c\n\n", "f").unwrap().is_empty());
        // CRLF blank lines, and lines after a quoted field spanning lines.
        let e = records("h\r\n1\r\n\r\n2\r\n", "f.csv").unwrap_err();
        assert!(e.to_string().starts_with("f.csv:3: blank line"), "{e}");
        let e = records("h\n\n\n1\n", "f.csv").unwrap_err();
        assert!(e.to_string().starts_with("f.csv:2: blank line"), "{e}");
        assert!(e.to_string().contains("(line 4)"), "{e}");
        let r = records("h\n\"a\n\nb\",1\nc\n\n", "f").unwrap();
        let lines: Vec<usize> = r.iter().map(|r| r.line).collect();
        assert_eq!(lines, [1, 2, 5]);
        // Blank lines before the header are errors too, with a hint.
        let e = records("# c\n\n# d\nh\n", "f.csv").unwrap_err();
        assert!(e.to_string().starts_with("f.csv:2: blank line"), "{e}");
        assert!(e.to_string().contains("(line 4)"), "{e}");
        assert!(e.to_string().contains("comment"), "{e}");
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
    fn stdin_is_named_and_read_like_a_file() {
        assert_eq!(source_name(Path::new("-")), "<stdin>");
        assert_eq!(source_name(Path::new("./-")), "./-");
        let (name, text) = read_from(
            source_name(Path::new("-")),
            &b"point,q1\n"[..],
            0,
            usize::MAX,
        )
        .unwrap();
        assert_eq!((name.as_str(), text.as_str()), ("<stdin>", "point,q1\n"));
        let e = read_from("<stdin>".into(), &b"a\n\xff"[..], 0, usize::MAX).unwrap_err();
        assert!(
            e.to_string().starts_with("<stdin>:2: not valid UTF-8"),
            "{e}"
        );
    }

    /// A reader that counts what was taken from it.
    struct Counted<R> {
        inner: R,
        taken: usize,
    }

    impl<R: Read> Read for Counted<R> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = self.inner.read(buf)?;
            self.taken += n;
            Ok(n)
        }
    }

    #[test]
    fn an_endless_line_is_refused_as_soon_as_it_is_too_long() {
        // 1 GiB of `0` without a line feed: refused after about 1 MiB read.
        let mut endless = Counted {
            inner: std::io::repeat(b'0').take(1 << 30),
            taken: 0,
        };
        let e = read_from("big.csv".into(), &mut endless, 0, usize::MAX).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("big.csv:1: line longer than 1 MiB"),
            "{e}"
        );
        assert!(endless.taken <= MAX_LINE + CHUNK, "{}", endless.taken);
        // The long line's own number, after short ones.
        let mut text = b"point,q1\nA,1\n".to_vec();
        text.extend(std::iter::repeat_n(b'1', MAX_LINE + 1));
        let e = read_from("f.csv".into(), &text[..], 0, usize::MAX).unwrap_err();
        assert_eq!(e.line(), Some(3), "{e}");
        // Exactly the longest line allowed, ended or not, anywhere in a chunk.
        for pad in [0, 5, CHUNK - 1] {
            let mut ok = vec![b'\n'; pad];
            ok.extend(std::iter::repeat_n(b'x', MAX_LINE));
            ok.push(b'\n');
            ok.extend(std::iter::repeat_n(b'y', MAX_LINE));
            assert!(
                read_from("f".into(), &ok[..], ok.len(), usize::MAX).is_ok(),
                "pad {pad}"
            );
            ok.pop();
            ok.extend(b"yy\n");
            let e = read_from("f".into(), &ok[..], 0, usize::MAX).unwrap_err();
            assert_eq!(e.line(), Some(pad + 2), "pad {pad}: {e}");
        }
        // A settings file past its bound is refused once that much was read.
        let mut lines = Counted {
            inner: std::io::repeat(b'\n').take(1 << 30),
            taken: 0,
        };
        let e = read_from("arm.toml".into(), &mut lines, 0, MAX_SETTINGS).unwrap_err();
        assert!(
            e.to_string().starts_with("arm.toml: larger than 16 MiB"),
            "{e}"
        );
        assert!(lines.taken <= MAX_SETTINGS + CHUNK, "{}", lines.taken);
        // Lines ended by CR alone, however long, are named as such.
        let mac = b"point,q1\rA,1\r".repeat(MAX_LINE / 8);
        let e = read_from("mac.csv".into(), &mac[..], 0, usize::MAX).unwrap_err();
        assert!(e.to_string().contains("carriage return alone"), "{e}");
        // A CRLF file's overlong line is said to be one.
        let mut crlf = b"point,q1\r\nA,1\r\n".to_vec();
        crlf.extend(std::iter::repeat_n(b'1', MAX_LINE + 10));
        crlf.extend(b"\r\nA,2\r\n");
        let e = read_from("w.csv".into(), &crlf[..], 0, usize::MAX).unwrap_err();
        assert!(
            e.to_string().starts_with("w.csv:3: line longer than 1 MiB"),
            "{e}"
        );
    }

    /// Yields its parts one read at a time: an empty part is an end of
    /// file, as a terminal's Ctrl-D.
    struct Parts(Vec<&'static [u8]>);

    impl Read for Parts {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let Some(part) = self.0.first_mut() else {
                return Ok(0);
            };
            let n = part.len().min(buf.len());
            buf[..n].copy_from_slice(&part[..n]);
            *part = &part[n..];
            if n == 0 || part.is_empty() {
                self.0.remove(0);
            }
            Ok(n)
        }
    }

    #[test]
    fn the_first_end_of_file_ends_the_text() {
        let (_, text) =
            read_from("-".into(), Parts(vec![b"a\n", b"", b"b\n"]), 0, usize::MAX).unwrap();
        assert_eq!(text, "a\n");
    }

    #[test]
    fn quoted_records_are_counted_by_line_as_they_come() {
        let t = "# c\n\"a\",b\n1,\"x\ny\"\n\n";
        let r = records(t, "f").unwrap();
        assert_eq!(r.iter().map(|r| r.line).collect::<Vec<_>>(), [2, 3]);
        assert_eq!(r[1].fields, ["1", "x\ny"]);
    }

    #[test]
    fn lines() {
        let t = "a\nb\nc";
        assert_eq!(line_of(t, 0), 1);
        assert_eq!(line_of(t, 2), 2);
        assert_eq!(line_of(t, 100), 3);
    }
}
