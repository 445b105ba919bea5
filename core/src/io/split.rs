//! A large CSV table read on several threads: its data lines cut into
//! pieces of about [`PIECE`] bytes at line ends, each piece's rows read
//! into a table of its own, the tables appended in file order. The result
//! — rows, values, and which error is reported — is the one
//! [`scan_table`] gives reading the text from its start: the pieces only
//! change who reads a line, and every error is chosen as it would choose
//! it (a blank line before more data first, then the first row of the
//! wrong width, then the first row refused; see [`Merged`]).
//!
//! Text with a double quote past the comments, a blank line before the
//! header, a header the caller refuses, or too small to share is read by
//! [`scan_table`] itself.

use super::text::{
    Blanks, Record, check_row_width, cr_only, line_of, preamble, records_in, scan_table,
};
use crate::error::InputError;

/// Bytes of text a piece is cut at (then at the next line end): about
/// 4 000 rows of a poses file, a few hundred microseconds of reading.
pub(crate) const PIECE: usize = 1 << 18;

/// Pieces read between two appends: the rows read ahead of their table
/// are at most this many pieces' (some MB), not the whole file's.
const WAVE: usize = 32;

/// How a table's rows are read: a table with room for some rows (for the
/// header), and a row read into it.
pub(crate) struct TableReader<New, Row> {
    /// An empty table for the header with room for this many rows.
    pub new: New,
    /// Reads a data row (its line and fields) into a table.
    pub row: Row,
}

/// [`scan_table`] on up to `threads` threads, the rows read into tables of
/// `T` ([`TableReader`]) that `append` puts together in file order;
/// `rows_bound(header, (bytes, lines))`, the most rows text of so many
/// bytes and lines can hold (for the room). Returns the header and the table (`None` when no row was read).
///
/// # Errors
///
/// Those of [`scan_table`], the same one for the same text.
pub(crate) fn scan_table_on<T, New, Row>(
    text: &str,
    (file, shape, rows_are): (&str, &str, &str),
    check_header: impl Fn(&Record) -> Result<(), InputError>,
    reader: TableReader<New, Row>,
    (rows_bound, mut append): (
        impl Fn(&Record, (usize, usize)) -> usize + Sync,
        impl FnMut(&mut T, T) -> Result<(), InputError>,
    ),
    (threads, piece): (usize, usize),
) -> Result<(Record, Option<T>), InputError>
where
    T: Send,
    New: Fn(&Record, usize) -> Result<T, InputError> + Sync,
    Row: Fn(&mut T, &Record, usize, &[&str]) -> Result<(), InputError> + Sync,
{
    let Some((header, data)) = split_header(text, &check_header).filter(|(_, data)| {
        crate::parallel::threads_for((data.1 - data.0).div_ceil(piece), threads) > 1
    }) else {
        let mut table = None;
        let header = scan_table(
            text,
            file,
            shape,
            rows_are,
            check_header,
            |h, line, fields| {
                let t = match &mut table {
                    Some(t) => t,
                    None => {
                        let lines = 1 + text.bytes().filter(|&b| b == b'\n').count();
                        table.insert((reader.new)(h, rows_bound(h, (text.len(), lines)))?)
                    }
                };
                (reader.row)(t, h, line, fields)
            },
        )?;
        return Ok((header, table));
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let (pieces, last_line) = cut(text, data, (piece, threads));
    // The data lines' bytes and lines (the last may have no line end).
    let whole = (data.1 - data.0, last_line - header.line);
    let mut merged = Merged::new(header.line);
    let mut table: Option<T> = None;
    for wave in pieces.chunks(WAVE) {
        let read = crate::parallel::parallel_map(wave, threads, |&cut| {
            read_piece(text, cut, (file, &header), &reader, &rows_bound)
        });
        for p in read {
            merged.blanks(text, file, p.blanks)?;
            merged.rows += p.rows;
            if merged.width.is_none() {
                merged.width = p.width;
            }
            if merged.row.is_none() {
                merged.row = p.row;
            }
            let Some(t) = p
                .table
                .filter(|_| merged.width.is_none() && merged.row.is_none())
            else {
                continue;
            };
            let into = match &mut table {
                Some(into) => into,
                None => match (reader.new)(&header, rows_bound(&header, whole)) {
                    Ok(into) => table.insert(into),
                    // Where the reading from the start would have failed:
                    // at the first row.
                    Err(e) => {
                        merged.row = Some(e);
                        continue;
                    }
                },
            };
            if let Err(e) = append(into, t) {
                merged.row = Some(e);
            }
        }
    }
    merged.finish(file, header).map(|h| (h, table))
}

/// The header of `text` (its first record) if the rest can be read in
/// pieces — no quote past the comments, no blank line before the header,
/// a header `check_header` takes — and the byte range of the lines after
/// it; `None` otherwise (for [`scan_table`] to read, and to find what is
/// wrong).
fn split_header(
    text: &str,
    check_header: impl Fn(&Record) -> Result<(), InputError>,
) -> Option<(Record, (usize, usize))> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let (body, blank) = preamble(text);
    let bytes = text.as_bytes();
    if blank.is_some() || body >= text.len() || bytes[body..].contains(&b'"') {
        return None;
    }
    // Lines ended by a carriage return alone, which `scan_table` refuses
    // (the file is named there; here only whether it is refused counts).
    if cr_only(text, 0, "").is_err() || cr_only(text, body, "").is_err() {
        return None;
    }
    let end = (bytes[body..].iter().position(|&b| b == b'\n')).map_or(text.len(), |n| body + n);
    let mut header = None;
    records_in(text, (body, end), (line_of(text, body), None), |line, f| {
        header = Some(Record {
            line,
            fields: f.iter().map(|f| f.to_string()).collect(),
        })
    });
    header
        .filter(|h| check_header(h).is_ok())
        .map(|h| (h, ((end + 1).min(text.len()), text.len())))
}

/// A piece of text: its bytes, the line it starts on, and its lines at
/// most (its line ends, and one more for a last line without an end).
type Cut = ((usize, usize), usize, usize);

/// The pieces of the lines `from..to` of `text`: each about `piece` bytes,
/// ending at a line end (or the text's); and the line `to` is on. The line ends are counted a piece
/// at a time on up to `threads` threads.
fn cut(
    text: &str,
    (from, to): (usize, usize),
    (piece, threads): (usize, usize),
) -> (Vec<Cut>, usize) {
    let bytes = text.as_bytes();
    let mut ranges = Vec::with_capacity((to - from).div_ceil(piece.max(1)));
    let mut start = from;
    while start < to {
        let at = (start + piece.max(1)).min(to);
        let end = bytes[at..to]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(to, |n| at + n + 1);
        ranges.push((start, end));
        start = end;
    }
    let ends = crate::parallel::parallel_map(&ranges, threads, |&(start, end)| {
        bytes[start..end].iter().filter(|&&b| b == b'\n').count()
    });
    let mut line = line_of(text, from);
    let pieces = (ranges.into_iter().zip(ends))
        .map(|(range, ends)| {
            line += ends;
            (range, line - ends, ends + 1)
        })
        .collect();
    (pieces, line)
}

/// What one piece held.
struct Piece<T> {
    blanks: Blanks,
    rows: usize,
    width: Option<InputError>,
    row: Option<InputError>,
    table: Option<T>,
}

/// Reads the rows of the piece `range` (starting on `line`, at most
/// `lines` lines) as
/// [`scan_table`] reads rows: the first of the wrong width stops the rows
/// read, the first refused stops the table.
fn read_piece<T, New, Row>(
    text: &str,
    (range, line, lines): Cut,
    (file, header): (&str, &Record),
    reader: &TableReader<New, Row>,
    rows_bound: &impl Fn(&Record, (usize, usize)) -> usize,
) -> Piece<T>
where
    New: Fn(&Record, usize) -> Result<T, InputError>,
    Row: Fn(&mut T, &Record, usize, &[&str]) -> Result<(), InputError>,
{
    let (mut rows, mut width, mut row, mut table) = (0, None, None, None);
    let blanks = records_in(text, range, (line, None), |line, fields| {
        rows += 1;
        if width.is_some() {
            return;
        }
        if let Err(e) = check_row_width(line, fields.len(), file, &header.fields) {
            width = Some(e);
            return;
        }
        if row.is_some() {
            return;
        }
        let t = match &mut table {
            Some(t) => t,
            None => match (reader.new)(header, rows_bound(header, (range.1 - range.0, lines))) {
                Ok(t) => table.insert(t),
                Err(e) => {
                    row = Some(e);
                    return;
                }
            },
        };
        row = (reader.row)(t, header, line, fields).err();
    });
    Piece {
        blanks,
        rows,
        width,
        row,
        table,
    }
}

/// The pieces read so far, in file order.
struct Merged {
    /// A blank line since the last record, and whether a record came.
    pending: (Option<usize>, bool),
    rows: usize,
    width: Option<InputError>,
    row: Option<InputError>,
    header_line: usize,
}

impl Merged {
    fn new(header_line: usize) -> Merged {
        Merged {
            // The header is a record.
            pending: (None, true),
            rows: 0,
            width: None,
            row: None,
            header_line,
        }
    }

    /// The next piece's blank lines: a blank line before more data is the
    /// error, before anything a row says.
    fn blanks(&mut self, text: &str, file: &str, b: Blanks) -> Result<(), InputError> {
        self.pending = b.check(text, file, self.pending)?;
        Ok(())
    }

    /// The error [`scan_table`] reports for the whole text, if any, else
    /// the header.
    fn finish(self, file: &str, header: Record) -> Result<Record, InputError> {
        if self.rows == 0 {
            return Err(InputError::file_error(
                file,
                format!("no data rows after the header (line {})", self.header_line),
            ));
        }
        match self.width.or(self.row) {
            Some(e) => Err(e),
            None => Ok(header),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::io::AngleUnit;
    use crate::io::poses::parse_poses_on;
    use rand::{RngExt, SeedableRng};

    /// `text` read whole on one thread and in pieces of every size from a
    /// byte up: the same poses and warnings, or the same error.
    fn same_in_pieces(text: &str) {
        let read = |pieces| {
            parse_poses_on(text, ("p.csv", AngleUnit::Deg), Some(2).into(), pieces)
                .map_err(|e| e.to_string())
        };
        let whole = read((1, usize::MAX));
        for piece in [1, 2, 3, 5, 8, 13, 40, 100] {
            assert_eq!(read((2, piece)), whole, "pieces of {piece} bytes:\n{text}");
            assert_eq!(read((3, piece)), whole, "3 threads, {piece} bytes:\n{text}");
        }
    }

    #[test]
    fn the_files_read_in_pieces_are_those_read_whole() {
        let rows: String = (0..40)
            .map(|i| format!("P{},{}.5,{}\n", i % 7, i * 3, 90 - i))
            .collect();
        let h = "point,q1,q2\n";
        for text in [
            format!("{h}{rows}"),
            format!("# a comment\n#another\n\u{feff}{h}{rows}"),
            format!("\u{feff}{h}{rows}\n\n  \n"),
            format!("{h}{}", rows.replace('\n', "\r\n")),
            format!("{h}{}", rows.trim_end()),
            format!("{h}\n{rows}"),
            format!("{h}{rows}\n{rows}"),
            format!("{h}{rows} \t \n{rows}"),
            format!("\n{h}{rows}"),
            format!("{h}\n\n"),
            h.to_string(),
            format!("{h}{rows}A,1\n{rows}B,1,2,3\n{rows}"),
            format!("{h}{rows}A,x,1\n{rows}B,1\n{rows}"),
            format!("{h}{rows},1,2\n{rows}C,1,1e999\n"),
            format!("{h}{rows}A,x,1\n{rows}\n{rows}"),
            format!("{h}{rows}\"Q\",1,2\n"),
            format!("{h}{rows}A,1,2\rB,1,2\n"),
            format!("point,q1,q9\n{rows}\n\n{rows}"),
            format!("point,q1,q2,tool\n{}", rows.replace('\n', ",t\n")),
            format!(
                "point,q1,q2,temperature,time\n{}",
                rows.replace('\n', ",20.5,7\n")
            ),
            format!(
                "point,q1,q2,temperature\n{}A,1,2,900\n",
                rows.replace('\n', ",21\n")
            ),
            format!("point,q1,q2,approach\n{}", rows.replace('\n', ",+-\n")),
        ] {
            same_in_pieces(&text);
        }
    }

    #[test]
    fn random_files_with_defects_read_the_same_in_pieces() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(44);
        for _ in 0..60 {
            let tools = rng.random_bool(0.3);
            let mut text = String::from(if tools {
                "point,q1,q2,tool\n"
            } else {
                "point,q1,q2\n"
            });
            for _ in 0..rng.random_range(0..60) {
                let label = format!("S{}", rng.random_range(0..9));
                let (a, b) = (
                    rng.random_range(-180.0..180.0),
                    rng.random_range(-90.0..90.0),
                );
                let tool = if tools {
                    format!(",t{}", rng.random_range(0..3))
                } else {
                    String::new()
                };
                let line = match rng.random_range(0..40) {
                    0 => String::new(),
                    1 => format!("{label},{a}"),
                    2 => format!("{label},{a},nan{tool}"),
                    3 => format!(",{a},{b}{tool}"),
                    4 => format!("{label},{a},{b},9{tool}"),
                    _ => format!("{label},{a},{b}{tool}"),
                };
                text.push_str(&line);
                text.push('\n');
            }
            same_in_pieces(&text);
        }
    }
}
