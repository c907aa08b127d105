//! A small CSV reader and writer for `uplift eval`: a header row of column names, then rows of
//! plain numbers. No quoting: names and numbers never contain commas. Cells are trimmed; blank
//! lines (and a trailing newline) are skipped; `\r\n` line ends are accepted. Every error names
//! the file, the 1-based line and the column, never panics.

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
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_end_matches('\r'))).filter(|(_, l)| !l.trim().is_empty());
    let Some((header_line, header_text)) = lines.next() else {
        return Err(format!("{file}: empty file: expected a header row of column names"));
    };
    let header: Vec<String> = header_text.split(',').map(|c| c.trim().to_string()).collect();
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
    for (line, text) in lines {
        let cells: Vec<&str> = text.split(',').map(str::trim).collect();
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
                cells[header.len()],
                header[header.len() - 1]
            ));
        }
        let mut row = Vec::with_capacity(cells.len());
        for (cell, name) in cells.iter().zip(&header) {
            if cell.is_empty() {
                return Err(format!("{file}:{line}: column `{name}`: empty cell (expected a number)"));
            }
            match cell.parse::<f32>() {
                Ok(v) => row.push(v),
                Err(_) => return Err(format!("{file}:{line}: column `{name}`: `{cell}` is not a number")),
            }
        }
        rows.push(row);
        row_lines.push(line);
    }
    Ok(Table { header, header_line, rows, lines: row_lines })
}

/// Writes a header and `values` (row-major, `header.len()` per row) as CSV text. Numbers are
/// written in Rust's shortest round-trip form, so reading them back gives the same `f32`s.
pub fn write(header: &[String], values: &[f32]) -> String {
    let mut s = header.join(",");
    s.push('\n');
    if header.is_empty() {
        return s;
    }
    for row in values.chunks(header.len()) {
        for (k, v) in row.iter().enumerate() {
            if k > 0 {
                s.push(',');
            }
            s.push_str(&v.to_string());
        }
        s.push('\n');
    }
    s
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
    fn errors_name_file_line_and_column() {
        assert_eq!(parse("t.csv", "a,b\n1,x\n").unwrap_err(), "t.csv:2: column `b`: `x` is not a number");
        assert!(parse("t.csv", "a,b\n1\n").unwrap_err().starts_with("t.csv:2: 1 fields, but the header has 2 columns: column `b`"));
        assert!(parse("t.csv", "a,b\n1,2\n1,2,3\n").unwrap_err().contains("t.csv:3:"));
        assert!(parse("t.csv", "a,a\n").unwrap_err().contains("`a` appears twice"));
        assert!(parse("t.csv", "\n").unwrap_err().contains("empty file"));
    }

    #[test]
    fn writes_round_trip_numbers() {
        let text = write(&["x".into(), "y".into()], &[0.1, 1.0 / 3.0, -2.0, 1e-20]);
        assert_eq!(text, "x,y\n0.1,0.33333334\n-2,0.00000000000000000001\n");
        let back = parse("t", &text).unwrap();
        assert_eq!(back.rows, vec![vec![0.1, 1.0 / 3.0], vec![-2.0, 1e-20]]);
    }
}
