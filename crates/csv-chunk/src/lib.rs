//! Numeric CSV chunks parsed into float64 columns, on every core, or refused.
//!
//! A *chunk* is whole lines of a CSV file below its header row: bytes, lines ending at `\n`,
//! `\r\n` or `\r` (empty lines skipped), cells separated by `,`. [`parse`] returns the cells of
//! the wanted columns as numbers when every line is *simple*, and `None` otherwise, so that a
//! row-by-row reader (Python's `csv` module and `float`, in `uasnav.io._text`) judges the
//! chunk and names the first bad cell. Simple means:
//!
//! - the chunk is printable ASCII (tab allowed): no `"` (quoting), no NUL or other control
//!   byte, no byte ≥ 0x80 (UTF-8 is checked by the row-by-row reader);
//! - no line is longer than [`MAX_LINE`] bytes (so no cell reaches the `csv` module's field
//!   limit of 128 KiB) and no line is blank (spaces, tabs and commas only);
//! - a row has exactly [`Layout::width`] cells if [`Layout::exact_width`], else at least one
//!   more than the largest wanted column;
//! - every wanted cell, stripped of spaces and tabs, is a plain decimal number
//!   (`[+-]? (d+ [. d*] | . d+) ([eE] [+-]? d+)?`, see [`number`]) whose value is finite, or
//!   with [`Layout::nan_ok`] a NaN spelled as Python's `float` spells it (`nan`, any case,
//!   signed).
//!
//! On simple input the result equals the row-by-row reader's bit for bit: both readers skip the
//! same lines, split the same cells, and both `f64::from_str` and Python's `float` round
//! correctly (IEEE 754 round-half-even of the exact decimal value), so they agree on every
//! number, subnormals and signed zeros included; `float("-nan")` is the quiet NaN with the sign
//! bit set, as here. Cells of columns not wanted are not parsed (the row-by-row reader does not
//! parse them either).
//!
//! The chunk is cut at line breaks into one part per core ([`parse`] with `parts`), each part
//! parsed into its own column buffers on a scoped thread, and the parts' columns joined into one
//! column-major (Fortran-order) buffer.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

use std::num::NonZeroUsize;
use std::thread;

/// Longest line (bytes, without its line break) parsed here; a longer line may hold a cell
/// beyond the `csv` module's field limit (128 KiB), which only the row-by-row reader reports.
pub const MAX_LINE: usize = 64 * 1024;

/// Smallest part (bytes) given a thread of its own: smaller chunks are parsed on the calling
/// thread, where spawning would cost more than it saves.
pub const MIN_PART: usize = 256 * 1024;

/// Which cells of a row are read, and what a row must look like.
#[derive(Clone, Copy, Debug)]
pub struct Layout<'a> {
    /// Cells in the header row.
    pub width: usize,
    /// The wanted columns, 0-based positions in the header row, in output order.
    pub columns: &'a [usize],
    /// Refuse a row whose cell count differs from `width` (else only a row too short for a
    /// wanted column is refused).
    pub exact_width: bool,
    /// Accept NaN (a missing value); ±inf is always refused.
    pub nan_ok: bool,
}

/// The numbers of a chunk: `rows` × `columns.len()` values, column after column.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// Data rows (non-empty lines) parsed.
    pub rows: usize,
    /// Column-major (Fortran-order) values: column `j` is `values[j * rows..(j + 1) * rows]`.
    pub values: Vec<f64>,
}

/// The cores to parse on (`std::thread::available_parallelism`, 1 if unknown).
pub fn cores() -> usize {
    thread::available_parallelism().map_or(1, NonZeroUsize::get)
}

/// Parse `chunk` (see the crate docs) on up to `parts` threads; `None`: not simple input.
pub fn parse(chunk: &[u8], layout: &Layout<'_>, parts: usize) -> Option<Table> {
    // UTF-8 checked once (non-ASCII bytes are then refused by `printable`), cells sliced as str
    let chunk = std::str::from_utf8(chunk).ok()?;
    let parts = parts.clamp(1, (chunk.len() / MIN_PART).max(1));
    let pieces = split(chunk, parts);
    let done: Vec<Part> = if pieces.len() == 1 {
        vec![parse_part(chunk, layout)?]
    } else {
        thread::scope(|s| {
            let handles: Vec<_> = pieces
                .iter()
                .map(|p| s.spawn(move || parse_part(p, layout)))
                .collect();
            // a part that panicked (none can: no unwrap, no slicing out of bounds) refuses
            handles
                .into_iter()
                .map(|h| h.join().ok().flatten())
                .collect::<Option<Vec<_>>>()
        })?
    };
    let rows = done.iter().map(|p| p.rows).sum();
    let mut values = Vec::with_capacity(rows * layout.columns.len());
    for j in 0..layout.columns.len() {
        for part in &done {
            values.extend_from_slice(part.cols.get(j).map_or(&[][..], Vec::as_slice));
        }
    }
    Some(Table { rows, values })
}

/// The rows of one piece: one buffer per wanted column.
struct Part {
    rows: usize,
    cols: Vec<Vec<f64>>,
}

/// Line breaks in `text` (`\n`, `\r\n` or `\r`, a `\r\n` counted once): the lines a chunk
/// moves a reader on by. A second pass only if there is a `\r`.
pub fn line_breaks(text: &[u8]) -> usize {
    let lf = count_bytes(text, b'\n');
    if !text.contains(&b'\r') {
        return lf;
    }
    let crlf = text.windows(2).filter(|w| *w == b"\r\n").count();
    lf + count_bytes(text, b'\r') - crlf
}

/// Bytes equal to `byte`, counted in one-byte lanes over blocks of 255 (so the compiler
/// vectorises the count 16 or 32 bytes at a time; a `usize` count per byte is not).
fn count_bytes(text: &[u8], byte: u8) -> usize {
    text.chunks(255)
        .map(|block| {
            let n = block
                .iter()
                .fold(0u8, |n, &b| n.wrapping_add(u8::from(b == byte)));
            usize::from(n)
        })
        .sum()
}

/// `chunk` cut into at most `parts` pieces of whole lines, about equally long.
fn split(chunk: &str, parts: usize) -> Vec<&str> {
    let mut out = Vec::with_capacity(parts);
    let mut start = 0;
    for p in 1..parts {
        let target = (chunk.len() * p / parts).max(start);
        let Some(rest) = chunk.as_bytes().get(target..) else {
            break;
        };
        let Some(k) = rest.iter().position(|&b| b == b'\n' || b == b'\r') else {
            break;
        };
        let mut end = target + k + 1;
        if rest.get(k..k + 2) == Some(b"\r\n") {
            end += 1; // never between the halves of \r\n
        }
        // line breaks are ASCII: the cuts fall between characters
        let Some(piece) = chunk.get(start..end) else {
            break;
        };
        out.push(piece);
        start = end;
    }
    out.push(chunk.get(start..).unwrap_or_default());
    out
}

/// One piece of whole lines parsed into one buffer per wanted column; `None`: not simple.
fn parse_part(text: &str, layout: &Layout<'_>) -> Option<Part> {
    if !printable(text.as_bytes()) {
        return None;
    }
    let guess = text.len() / (8 * layout.width.max(1)) + 1;
    let mut cols: Vec<Vec<f64>> = (0..layout.columns.len())
        .map(|_| Vec::with_capacity(guess))
        .collect();
    // the wanted cells of one row, by their position in the row
    let span = layout.columns.iter().max().map_or(0, |&j| j + 1);
    let mut wanted = vec![false; span];
    for &j in layout.columns {
        *wanted.get_mut(j)? = true;
    }
    let mut row = vec![0.0; span];
    let mut rows = 0;
    // empty lines are skipped, so \r\n may count as two breaks around an empty line
    let lines: &mut dyn Iterator<Item = &str> = if text.contains('\r') {
        &mut text.split(['\n', '\r'])
    } else {
        &mut text.split('\n')
    };
    for line in lines {
        if line.is_empty() {
            continue;
        }
        if line.len() > MAX_LINE
            || (span == 0 && line.bytes().all(|b| matches!(b, b' ' | b'\t' | b',')))
        {
            return None; // too long for the csv module, or blank (skipped by the row-by-row reader)
        }
        let mut cells = 0;
        for (cell, &want) in cells_of(line).zip(wanted.iter().chain(std::iter::repeat(&false))) {
            if want {
                *row.get_mut(cells)? = number(cell, layout.nan_ok)?;
            }
            cells += 1;
        }
        if (layout.exact_width && cells != layout.width) || cells < span {
            return None;
        }
        for (out, &j) in cols.iter_mut().zip(layout.columns) {
            out.push(*row.get(j)?);
        }
        rows += 1;
    }
    Some(Part { rows, cols })
}

/// The cells of `line`: `str::split(',')` without its `memchr` set-up per cell, which costs
/// more than the search on cells of a few bytes.
fn cells_of(line: &str) -> impl Iterator<Item = &str> {
    let mut rest = Some(line);
    std::iter::from_fn(move || {
        let s = rest?;
        match s.bytes().position(|b| b == b',') {
            Some(k) => {
                rest = s.get(k + 1..);
                s.get(..k)
            }
            None => rest.take(),
        }
    })
}

/// Every byte printable ASCII, a tab or a line break, none a `"` (one pass without branches).
fn printable(text: &[u8]) -> bool {
    text.iter().fold(true, |ok, &b| {
        ok & (((0x20..0x7f).contains(&b) && b != b'"') || b == b'\t' || b == b'\n' || b == b'\r')
    })
}

/// One cell (spaces and tabs around it ignored) as a number, if plain decimal syntax and
/// finite, or a NaN where `nan_ok` (see the crate docs).
///
/// `f64::from_str` reads `[+-]? (d+ [. d*] | . d+) ([eE] [+-]? d+)?` and the spellings `inf`,
/// `infinity` and `nan` (any case, signed), nothing else: its decimal numbers are a subset of
/// Python's `float` syntax (which adds `_` between digits and Unicode digits), so a finite
/// result is always a cell `float` reads, with the same value (both round correctly). The
/// spellings give ±inf (refused) or NaN, spelled as `float` spells it, its sign kept.
pub fn number(cell: &str, nan_ok: bool) -> Option<f64> {
    let v: f64 = trim(cell).parse().ok()?;
    (v.is_finite() || (nan_ok && v.is_nan())).then_some(v)
}

/// `s` without the spaces and tabs around it.
fn trim(s: &str) -> &str {
    let b = s.as_bytes();
    let blank = |c: Option<&u8>| matches!(c, Some(b' ' | b'\t'));
    if blank(b.first()) || blank(b.last()) {
        s.trim_matches([' ', '\t'])
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(width: usize) -> Vec<usize> {
        (0..width).collect()
    }

    fn run(
        text: &str,
        columns: &[usize],
        width: usize,
        exact: bool,
        nan_ok: bool,
    ) -> Option<Table> {
        let layout = Layout {
            width,
            columns,
            exact_width: exact,
            nan_ok,
        };
        parse(text.as_bytes(), &layout, 1)
    }

    #[test]
    fn columns_come_out_column_major() {
        let t = run("1,2,3\n4,5,6\n", &[2, 0], 3, true, false);
        assert_eq!(
            t,
            Some(Table {
                rows: 2,
                values: vec![3.0, 6.0, 1.0, 4.0]
            })
        );
    }

    #[test]
    fn line_breaks_and_empty_lines() {
        for text in [
            "1,2\n3,4\n",
            "1,2\r\n3,4\r\n",
            "1,2\r3,4\r",
            "1,2\n\n\r\n3,4",
            "\r\n1,2\r\r3,4\n",
        ] {
            let t = run(text, &all(2), 2, true, false);
            assert_eq!(
                t.map(|t| t.values),
                Some(vec![1.0, 3.0, 2.0, 4.0]),
                "{text:?}"
            );
        }
        assert_eq!(run("", &all(2), 2, true, false).map(|t| t.rows), Some(0));
    }

    #[test]
    fn numbers_as_python_float_reads_them() {
        let cases: [(&str, f64); 14] = [
            ("+1", 1.0),
            (".5", 0.5),
            ("5.", 5.0),
            ("-0", -0.0),
            ("  2.5\t", 2.5),
            ("1e5", 1e5),
            ("1E+05", 1e5),
            ("2.5e-3", 2.5e-3),
            ("4.9406564584124654e-324", 5e-324),
            ("2.2250738585072011e-308", 2.225_073_858_507_201e-308),
            ("0.1", 0.1),
            ("1e-400", 0.0),
            ("0e999999999999", 0.0),
            ("1.7976931348623157e308", f64::MAX),
        ];
        for (cell, want) in cases {
            let got = number(cell, false);
            assert_eq!(got.map(f64::to_bits), Some(want.to_bits()), "{cell}");
        }
        // a 17-digit round trip of many doubles
        let mut x = 1.234_567_890_123_456_7e-300_f64;
        while x < 1e300 {
            let s = format!("{x:.16e}");
            assert_eq!(
                number(&s, false).map(f64::to_bits),
                Some(x.to_bits()),
                "{s}"
            );
            x *= 1.618_033_988_7e7;
        }
    }

    #[test]
    fn cells_it_refuses() {
        for cell in [
            "", " ", ".", "e5", "1e", "1e+", "+", "-", "1_0", "0x10", "1.5.2", "1 2", "inf",
            "-inf", "infinity", "nan", "1e400", "-1e400", "1,5", "1d5", "٣",
        ] {
            assert_eq!(number(cell, false), None, "{cell:?}");
        }
    }

    #[test]
    fn nan_where_it_is_a_missing_value() {
        for (cell, neg) in [
            ("nan", false),
            ("NaN", false),
            ("+nan", false),
            ("-NAN", true),
            (" nan ", false),
        ] {
            let v = number(cell, true);
            assert!(
                v.is_some_and(|v| v.is_nan() && v.is_sign_negative() == neg),
                "{cell}"
            );
            assert_eq!(
                v.map(f64::to_bits),
                Some(if neg { -f64::NAN } else { f64::NAN }.to_bits())
            );
        }
        for cell in ["inf", "-inf", "Infinity", "nan1", "nann", "n"] {
            assert_eq!(number(cell, true), None, "{cell}");
        }
    }

    #[test]
    fn chunks_it_hands_to_the_row_by_row_reader() {
        let three = all(3);
        for text in [
            "1,2,3\n\"4\",5,6\n", // quoting
            "1,2,3\n4,5,6\0\n",   // NUL
            "1,2,3\n4,5,6\x0c\n", // another control byte
            "1,2,3\n4,5,é\n",
            "1,2,3\n   \n4,5,6\n", // a line of spaces
            "1,2,3\n,,\n",         // blank cells only
            "1,2,3\n4,5\n",        // too short
            "1,2,3\n4,5,6,7\n",    // too long for an exact width
            "1,2,3\n4,,6\n",       // an empty cell
            "1,2,3\n4,x,6\n",
        ] {
            assert_eq!(run(text, &three, 3, true, false), None, "{text:?}");
        }
        // a row longer than the header is fine without exact width, a short one is not
        assert_eq!(
            run("1,2,3,x\n", &[0, 2], 3, false, false).map(|t| t.values),
            Some(vec![1.0, 3.0])
        );
        assert_eq!(run("1,2\n", &[0, 2], 3, false, false), None);
        // cells not wanted are not parsed
        assert_eq!(
            run("1,x,3\n", &[0, 2], 3, true, false).map(|t| t.rows),
            Some(1)
        );
        let long = format!("1,{}\n", "2".repeat(MAX_LINE));
        assert_eq!(run(&long, &all(2), 2, true, false), None);
    }

    #[test]
    fn parts_join_into_the_single_thread_result() {
        let mut text = String::new();
        for k in 0..200_000 {
            let nl = ["\n", "\r\n", "\r", "\n\n"][k % 4];
            text.push_str(&format!("{},{:e},-{}.5{nl}", k, k as f64 * 0.1, k % 97));
        }
        let cols = [2, 0, 1];
        let layout = Layout {
            width: 3,
            columns: &cols,
            exact_width: true,
            nan_ok: false,
        };
        let one = parse(text.as_bytes(), &layout, 1);
        assert_eq!(one.as_ref().map(|t| t.rows), Some(200_000));
        for parts in [2, 3, 7] {
            assert_eq!(parse(text.as_bytes(), &layout, parts), one, "{parts} parts");
        }
        // a bad cell in the last part refuses the whole chunk
        text.push_str("1,2,x\n");
        assert_eq!(parse(text.as_bytes(), &layout, 4), None);
    }

    #[test]
    fn line_breaks_as_split_lines_counts_them() {
        for (text, n) in [
            ("", 0),
            ("1,2", 0),
            ("1\n2\n", 2),
            ("1\r\n2\r\n", 2),
            ("1\r2\r", 2),
            ("\r\n\n\r\r\n\r", 5),
            ("1\r", 1),
        ] {
            assert_eq!(line_breaks(text.as_bytes()), n, "{text:?}");
        }
    }

    #[test]
    fn split_keeps_crlf_whole() {
        let text = "1\r\n2\r\n3\r\n4\r\n";
        for parts in 1..6 {
            let pieces = split(text, parts);
            assert_eq!(pieces.concat(), text);
            assert!(pieces.iter().all(|p| !p.starts_with('\n')), "{parts}");
        }
    }

    proptest::proptest! {
        /// Any cut into parts (at line breaks, \r\n kept whole) parses into the rows of the
        /// whole, in order, and counts the same line breaks.
        #[test]
        fn any_cut_joins_into_the_whole(
            rows in proptest::collection::vec(
                (proptest::collection::vec(-1e6f64..1e6, 3), 0usize..5), 0..60),
            parts in 1usize..6,
        ) {
            let breaks = ["\n", "\r\n", "\r", "\n\n", "\r\n\r\n"];
            let text: String = rows
                .iter()
                .map(|(r, nl)| format!("{},{:e},{:.3}{}", r[0], r[1], r[2], breaks[*nl]))
                .collect();
            let cols = [1, 2, 0];
            let layout = Layout { width: 3, columns: &cols, exact_width: true, nan_ok: false };
            let whole = parse_part(&text, &layout).map(|p| (p.rows, p.cols));
            proptest::prop_assert_eq!(whole.as_ref().map(|w| w.0), Some(rows.len()));
            let pieces = split(&text, parts);
            proptest::prop_assert_eq!(pieces.concat(), text.clone());
            let mut joined = vec![Vec::new(); 3];
            let mut n = 0;
            for piece in &pieces {
                let p = parse_part(piece, &layout);
                proptest::prop_assert!(p.is_some());
                let p = p.unwrap_or(Part { rows: 0, cols: vec![] });
                n += p.rows;
                for (j, c) in p.cols.into_iter().enumerate() {
                    joined[j].extend(c);
                }
            }
            proptest::prop_assert_eq!(Some((n, joined)), whole);
            let lines: usize = pieces.iter().map(|p| line_breaks(p.as_bytes())).sum();
            proptest::prop_assert_eq!(lines, line_breaks(text.as_bytes()));
        }
    }

    #[test]
    fn no_columns_still_counts_and_checks_rows() {
        assert_eq!(
            run("1,2\n\n3,4\n", &[], 2, true, false).map(|t| t.rows),
            Some(2)
        );
        assert_eq!(run("1,2\n3\n", &[], 2, true, false), None);
    }
}
