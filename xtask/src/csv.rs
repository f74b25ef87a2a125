//! CSV series as xtask's commands read them.

use std::path::Path;

/// Rows of a CSV (comment lines skipped) as header → values.
pub(crate) fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for l in lines {
        for (k, v) in l.split(',').enumerate().take(header.len()) {
            cols[k].push(
                v.trim()
                    .parse::<f64>()
                    .map_err(|e| format!("{}: {e}", path.display()))?,
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
