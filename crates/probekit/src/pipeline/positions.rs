//! Probe positions from a CSV file (manual placement).

use super::PipelineError;
use glam::Vec3;

/// Reads `x,y,z` rows (metres) from the CSV file at `path`: a header line
/// and blank or `#` lines are skipped; a row of another width or with a
/// NaN or infinite value is an error naming the file and line.
pub fn read_positions(path: &str) -> Result<Vec<Vec3>, PipelineError> {
    let fail = |message: String| PipelineError::Positions {
        path: path.to_string(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| fail(e.to_string()))?;
    parse_positions(&text).map_err(fail)
}

/// [`read_positions`] on the text of a file; the error says which line.
pub fn parse_positions(text: &str) -> Result<Vec<Vec3>, String> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Result<Vec<f32>, _> =
            line.split(',').map(|f| f.trim().parse::<f32>()).collect();
        let row = match fields {
            Ok(r) => r,
            Err(_) if out.is_empty() && i == 0 => continue, // a header
            Err(_) => return Err(format!("line {}: expected 3 numbers x,y,z", i + 1)),
        };
        if row.len() != 3 {
            return Err(format!(
                "line {}: expected 3 numbers x,y,z, found {}",
                i + 1,
                row.len()
            ));
        }
        if row.iter().any(|v| !v.is_finite()) {
            return Err(format!("line {}: NaN or infinite value", i + 1));
        }
        out.push(Vec3::new(row[0], row[1], row[2]));
    }
    if out.is_empty() {
        return Err("no positions".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_headers_comments_and_errors() {
        let p = parse_positions("x,y,z\n# a comment\n1,2,3\n\n 4 , 5 , 6\n").unwrap();
        assert_eq!(p, vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)]);
        assert_eq!(
            parse_positions("1,2\n").unwrap_err(),
            "line 1: expected 3 numbers x,y,z, found 2"
        );
        assert_eq!(
            parse_positions("1,2,3\n1,a,3\n").unwrap_err(),
            "line 2: expected 3 numbers x,y,z"
        );
        assert_eq!(
            parse_positions("1,2,nan\n").unwrap_err(),
            "line 1: NaN or infinite value"
        );
        assert_eq!(parse_positions("x,y,z\n").unwrap_err(), "no positions");
    }
}
