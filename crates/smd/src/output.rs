//! CSV files with a header line, written atomically (a temporary name, then a rename), so that
//! a crash never leaves half a result behind.

use std::path::Path;

use crate::SmdError;

/// Writes `rows` under `header` to `path` (`{:.10e}` per value).
///
/// # Errors
/// [`SmdError::Output`] naming the file.
pub fn write_csv(path: &Path, header: &[&str], rows: &[Vec<f64>]) -> Result<(), SmdError> {
    let mut text = header.join(",");
    text.push('\n');
    for row in rows {
        let cells: Vec<String> = row.iter().map(|x| format!("{x:.10e}")).collect();
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    let err = |p: &Path, e: std::io::Error| SmdError::Output {
        path: p.to_owned(),
        message: e.to_string(),
    };
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    let tmp = path.with_file_name(name);
    std::fs::write(&tmp, text).map_err(|e| err(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| err(path, e))
}
