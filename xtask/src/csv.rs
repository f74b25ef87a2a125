//! CSV series as xtask's commands read them, through the `csv` crate: a header row, then rows
//! of numbers; lines starting with `#` are comments.

use std::path::Path;

/// The columns of the CSV at `path` as (header, one vector of values per column). A row
/// shorter or longer than the header, or a value that is not a number, is an error naming the
/// file, the line and the column.
pub(crate) fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let at = |e: ::csv::Error| format!("{}: {e}", path.display());
    let mut reader = ::csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(::csv::Trim::All)
        .from_path(path)
        .map_err(at)?;
    let header: Vec<String> = reader
        .headers()
        .map_err(at)?
        .iter()
        .map(str::to_string)
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for row in reader.records() {
        let row = row.map_err(at)?;
        let line = row.position().map_or(0, |p| p.line());
        for ((name, col), v) in header.iter().zip(&mut cols).zip(row.iter()) {
            col.push(
                v.parse::<f64>().map_err(|e| {
                    format!("{}:{line}: column `{name}`: `{v}`: {e}", path.display())
                })?,
            );
        }
    }
    Ok((header, cols))
}

/// The column `name` of a CSV read by [`read_csv`] from `path` (named in the error).
pub(crate) fn column<'a>(
    h: &[String],
    c: &'a [Vec<f64>],
    name: &str,
    path: &Path,
) -> Result<&'a [f64], String> {
    h.iter()
        .position(|n| n == name)
        .map(|k| c[k].as_slice())
        .ok_or_else(|| {
            format!(
                "{}: no column `{name}`; the columns are: {}",
                path.display(),
                h.join(", ")
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(name: &str, text: &str) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
        let dir = std::env::temp_dir().join(format!("xtask-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let r = read_csv(&path);
        std::fs::remove_file(&path).unwrap();
        r
    }

    #[test]
    fn columns_are_read_past_comments_and_blanks() {
        let (h, c) = read(
            "ok.csv",
            "# efsi probes\ntime, solid_y\n0,1.5\n\n0.5, -2e-3\n",
        )
        .unwrap();
        assert_eq!(h, ["time", "solid_y"]);
        assert_eq!(c, [vec![0.0, 0.5], vec![1.5, -2e-3]]);
        let p = Path::new("ok.csv");
        assert_eq!(column(&h, &c, "solid_y", p).unwrap(), [1.5, -2e-3]);
        assert_eq!(
            column(&h, &c, "u", p).unwrap_err(),
            "ok.csv: no column `u`; the columns are: time, solid_y"
        );
    }

    #[test]
    fn a_bad_value_or_row_is_refused_naming_where() {
        let e = read("bad.csv", "t,x\n0,1\n1,one\n").unwrap_err();
        assert!(
            e.ends_with("bad.csv:3: column `x`: `one`: invalid float literal"),
            "{e}"
        );
        let e = read("short.csv", "t,x\n0,1\n1\n").unwrap_err();
        assert!(
            e.ends_with(
                "short.csv: CSV error: record 2 (line: 3, byte: 8): found record with 1 fields, \
                 but the previous record has 2 fields"
            ),
            "{e}"
        );
    }
}
