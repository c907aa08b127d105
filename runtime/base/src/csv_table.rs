//! `uplift eval`'s tables, read and written through the `csv` crate: a header row of column
//! names, then rows of numbers. Cells are trimmed; blank lines (and a trailing newline) are
//! skipped; `\r\n` line ends and quoted cells are accepted. Every error names the file, the
//! 1-based line and the column, never panics. Cells are finite numbers (`nan`, `inf`, `1e39`
//! are errors, as in documents).

/// A parsed table: column names and rows of numbers, each with the line it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub header: Vec<String>,
    /// The 1-based line of the header.
    pub header_line: usize,
    /// One entry per data row, `header.len()` numbers each.
    pub rows: Vec<Vec<f32>>,
    /// The 1-based line of each row in `rows`.
    pub lines: Vec<usize>,
}

/// Parses `text`; `file` names the source in error messages (`file:line: …`).
pub fn parse(file: &str, text: &str) -> Result<Table, String> {
    let mut reader = csv::ReaderBuilder::new().has_headers(false).flexible(true).trim(csv::Trim::All).from_reader(text.as_bytes());
    let mut records = reader.records().filter_map(|r| match r {
        // A line of blanks is a record of one empty field: skipped like an empty line.
        Ok(rec) if rec.iter().all(str::is_empty) => None,
        Ok(rec) => {
            let line = rec.position().map_or(0, |p| line_at(text, p.byte() as usize));
            Some(Ok((line, rec)))
        }
        Err(e) => Some(Err(match e.position() {
            Some(p) => format!("{file}:{}: {e}", line_at(text, p.byte() as usize)),
            None => format!("{file}: {e}"),
        })),
    });
    let Some(first) = records.next() else {
        return Err(format!("{file}: empty file: expected a header row of column names"));
    };
    let (header_line, header_record) = first?;
    let header: Vec<String> = header_record.iter().map(str::to_string).collect();
    for (k, name) in header.iter().enumerate() {
        if name.is_empty() {
            return Err(format!("{file}:{header_line}: column {} of the header has no name", k + 1));
        }
        if header[..k].contains(name) {
            return Err(format!("{file}:{header_line}: column `{name}` appears twice in the header"));
        }
    }
    let mut rows = Vec::new();
    let mut row_lines = Vec::new();
    for record in records {
        let (line, cells) = record?;
        if cells.len() < header.len() {
            return Err(format!(
                "{file}:{line}: {} fields, but the header has {} columns: column `{}` has no value",
                cells.len(),
                header.len(),
                header[cells.len()]
            ));
        }
        if cells.len() > header.len() {
            return Err(format!(
                "{file}:{line}: {} fields, but the header has {} columns: an extra field `{}` after column `{}`",
                cells.len(),
                header.len(),
                &cells[header.len()],
                header[header.len() - 1]
            ));
        }
        let mut row = Vec::with_capacity(cells.len());
        for (cell, name) in cells.iter().zip(&header) {
            if cell.is_empty() {
                return Err(format!("{file}:{line}: column `{name}`: empty cell (expected a number)"));
            }
            // Finite numbers only, as documents take them: `nan`, `inf` and values past f32's
            // range (`1e39` parses to inf) are refused where they enter.
            match cell.parse::<f32>() {
                Ok(v) if v.is_finite() => row.push(v),
                Ok(_) => return Err(format!("{file}:{line}: column `{name}`: `{cell}` is not a finite number (|x| ≤ 3.4e38)")),
                Err(_) => return Err(format!("{file}:{line}: column `{name}`: `{cell}` is not a number")),
            }
        }
        rows.push(row);
        row_lines.push(line);
    }
    Ok(Table { header, header_line, rows, lines: row_lines })
}

/// The 1-based line of the record starting at byte `at` (the csv crate places a record's start
/// before the line ends that precede it).
fn line_at(text: &str, at: usize) -> usize {
    let bytes = text.as_bytes();
    let mut at = at.min(bytes.len());
    while at < bytes.len() && matches!(bytes[at], b'\n' | b'\r') {
        at += 1;
    }
    1 + bytes[..at].iter().filter(|&&c| c == b'\n').count()
}

/// Writes a header and `values` (row-major, `header.len()` per row) as CSV text. Numbers are
/// written in Rust's shortest round-trip form, so reading them back gives the same `f32`s.
pub fn write(header: &[String], values: &[f32]) -> String {
    let mut w = csv::WriterBuilder::new().terminator(csv::Terminator::Any(b'\n')).flexible(true).from_writer(Vec::new());
    // Writing into memory cannot fail.
    let _ = w.write_record(header);
    if !header.is_empty() {
        for row in values.chunks(header.len()) {
            let _ = w.write_record(row.iter().map(|v| v.to_string()));
        }
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_trimmed_cells_and_skips_blank_lines() {
        let t = parse("t.csv", " a , b\r\n1, 2.5\n\n-3e-1,4\n").unwrap();
        assert_eq!(t.header, ["a", "b"]);
        assert_eq!(t.rows, vec![vec![1.0, 2.5], vec![-0.3, 4.0]]);
        assert_eq!(t.lines, [2, 4]);
    }

    #[test]
    fn non_finite_cells_are_refused_with_their_line_and_column() {
        for cell in ["nan", "NaN", "inf", "-inf", "1e39", "-3.5e38"] {
            let e = parse("t.csv", &format!("a,b\n1,2\n3,{cell}\n")).unwrap_err();
            assert_eq!(e, format!("t.csv:3: column `b`: `{cell}` is not a finite number (|x| ≤ 3.4e38)"));
        }
        assert_eq!(parse("t.csv", "a\n3.4e38\n").unwrap().rows, vec![vec![3.4e38f32]]);
    }

    #[test]
    fn errors_name_file_line_and_column() {
        assert_eq!(parse("t.csv", "a,b\n1,x\n").unwrap_err(), "t.csv:2: column `b`: `x` is not a number");
        assert!(parse("t.csv", "a,b\n1\n").unwrap_err().starts_with("t.csv:2: 1 fields, but the header has 2 columns: column `b`"));
        assert!(parse("t.csv", "a,b\n1,2\n1,2,3\n").unwrap_err().contains("t.csv:3:"));
        assert!(parse("t.csv", "a,a\n").unwrap_err().contains("`a` appears twice"));
        assert!(parse("t.csv", "\n").unwrap_err().contains("empty file"));
    }

    #[test]
    fn quoted_cells_and_quoted_names_are_read() {
        let t = parse("t.csv", "\"a\",b\n\"1.5\", 2\n").unwrap();
        assert_eq!((t.header.clone(), t.rows.clone()), (vec!["a".to_string(), "b".to_string()], vec![vec![1.5, 2.0]]));
        assert!(parse("t.csv", "a,b\n\"1,2\n").is_err(), "an unterminated quote is an error");
    }

    #[test]
    fn writes_round_trip_numbers() {
        let text = write(&["x".into(), "y".into()], &[0.1, 1.0 / 3.0, -2.0, 1e-20]);
        assert_eq!(text, "x,y\n0.1,0.33333334\n-2,0.00000000000000000001\n");
        let back = parse("t", &text).unwrap();
        assert_eq!(back.rows, vec![vec![0.1, 1.0 / 3.0], vec![-2.0, 1e-20]]);
    }
}
