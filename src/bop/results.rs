//! A BOP results file: a CSV whose header is `scene_id,im_id,obj_id,score,R,t,time`, one pose
//! estimate a row, R 9 numbers row-major and t 3 numbers (mm), each space-separated: the
//! format methods publish for the BOP challenges. Rows keep their text, which the scores
//! file repeats.

use crate::error::{Error, Result};
use crate::limits::Ledger;
use crate::untrusted::quoted;
use glam::{DMat3, DMat4, DVec3};
use std::path::Path;

/// The header a results file starts with.
pub const RESULTS_HEADER: [&str; 7] = ["scene_id", "im_id", "obj_id", "score", "R", "t", "time"];

/// How far RᵀR may be from the identity, and det R from 1, for R to count as a rotation.
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// One row: its ids, the pose it estimates, and its fields as written.
#[derive(Debug, Clone, PartialEq)]
pub struct ResultRow {
    pub scene_id: u32,
    pub im_id: u32,
    pub obj_id: u32,
    /// Camera-from-model, mm.
    pub pose: DMat4,
    pub fields: Vec<String>,
}

/// The pose of a BOP R (9 numbers, row-major) and t (3 numbers): refused, with the reason,
/// where R is not a rotation within [`ROTATION_TOLERANCE`] or a number is not finite.
pub fn pose_from_bop(r: &[f64], t: &[f64]) -> std::result::Result<DMat4, String> {
    if r.len() != 9 || r.iter().any(|v| !v.is_finite()) {
        return Err(format!("R must be 9 finite numbers (row-major); it has {} numbers: {r:?}", r.len()));
    }
    if t.len() != 3 || t.iter().any(|v| !v.is_finite()) {
        return Err(format!("t must be 3 finite numbers; it has {} numbers: {t:?}", t.len()));
    }
    // Row-major in the file; glam's constructors take columns.
    let rotation = DMat3::from_cols_array(&[r[0], r[3], r[6], r[1], r[4], r[7], r[2], r[5], r[8]]);
    let off_identity =
        (rotation.transpose() * rotation - DMat3::IDENTITY).to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let det = rotation.determinant();
    if off_identity > ROTATION_TOLERANCE || (det - 1.0).abs() > ROTATION_TOLERANCE {
        return Err(format!(
            "R is not a rotation within {ROTATION_TOLERANCE:e}: RᵀR is {off_identity:e} from the identity and det R = {det}"
        ));
    }
    Ok(DMat4::from_mat3_translation(rotation, DVec3::new(t[0], t[1], t[2])))
}

/// Numbers separated by spaces.
fn numbers(text: &str) -> std::result::Result<Vec<f64>, String> {
    text.split_whitespace().map(|v| v.parse::<f64>().map_err(|_| format!("{} is not a number", quoted(v)))).collect()
}

/// Bytes a row keeps besides its fields' text: its ids, pose and list of fields.
const ROW_BYTES: u64 = (size_of::<ResultRow>() + RESULTS_HEADER.len() * size_of::<String>()) as u64;

/// Reads a results file's text: its rows in order, each refused with the file, the row (from
/// 1, the header not counted), its ids where they were read, and the field. Charged to
/// `ledger` as it reads: what the CSV reader holds of a row while it reads it (as long as the
/// longest line) for the parse, then each row's `ROW_BYTES` and fields before it is kept.
/// A score or time must be a finite number (BOP writes -1 for a time not measured).
pub fn parse_results(path: &Path, text: &str, ledger: &Ledger) -> Result<Vec<ResultRow>> {
    let longest_line = text.split('\n').map(str::len).max().unwrap_or(0) as u64;
    let _reading = ledger.hold(format_args!("reading the rows of {}", path.display()), longest_line)?;
    let mut reader = csv::ReaderBuilder::new().has_headers(true).flexible(false).from_reader(text.as_bytes());
    let header = reader.headers().map_err(|e| Error::file(path, format!("unreadable header: {e}")))?;
    if header.iter().map(str::trim).ne(RESULTS_HEADER) {
        return Err(Error::file(
            path,
            format!(
                "the header must be exactly {}; it is {:?}",
                RESULTS_HEADER.join(","),
                header.iter().collect::<Vec<_>>()
            ),
        ));
    }
    let mut rows = Vec::new();
    for (n, record) in reader.records().enumerate() {
        let row = n + 1;
        let record = record.map_err(|e| Error::file(path, format!("row {row}: {e}")))?;
        let field = |i: usize| record.get(i).unwrap_or("").trim();
        let id = |i: usize| -> Result<u32> {
            field(i).parse().map_err(|_| {
                Error::file(
                    path,
                    format!("row {row}: {} = {} is not a whole number", RESULTS_HEADER[i], quoted(field(i))),
                )
            })
        };
        let (scene_id, im_id, obj_id) = (id(0)?, id(1)?, id(2)?);
        let at = |reason: String| {
            Error::file(path, format!("row {row} (scene {scene_id}, image {im_id}, object {obj_id}): {reason}"))
        };
        for i in [3, 6] {
            if !field(i).parse::<f64>().is_ok_and(f64::is_finite) {
                return Err(at(format!("{} = {} is not a finite number", RESULTS_HEADER[i], quoted(field(i)))));
            }
        }
        let r = numbers(field(4)).map_err(|e| at(format!("R: {e}")))?;
        let t = numbers(field(5)).map_err(|e| at(format!("t: {e}")))?;
        let pose = pose_from_bop(&r, &t).map_err(at)?;
        let fields_bytes = record.iter().map(str::len).sum::<usize>() as u64;
        ledger.charge(format_args!("the rows of {}", path.display()), ROW_BYTES + fields_bytes)?;
        rows.push(ResultRow { scene_id, im_id, obj_id, pose, fields: record.iter().map(str::to_string).collect() });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "scene_id,im_id,obj_id,score,R,t,time\n";

    #[test]
    fn a_row_reads_as_its_pose_and_keeps_its_fields() {
        let text = format!("{HEADER}1,3,5,0.9,0 -1 0 1 0 0 0 0 1,10 20 30,0.25\n");
        let rows = parse_results(Path::new("r.csv"), &text, &Ledger::default()).unwrap();
        assert_eq!(rows.len(), 1);
        let row = &rows[0];
        assert_eq!((row.scene_id, row.im_id, row.obj_id), (1, 3, 5));
        // R maps x to y: the second row of R is (1, 0, 0).
        assert!((row.pose.transform_point3(DVec3::X) - DVec3::new(10.0, 21.0, 30.0)).length() < 1e-12);
        assert_eq!(row.fields[4], "0 -1 0 1 0 0 0 0 1");
    }

    /// The parse is charged as it reads: the CSV reader's record, as long as the longest line,
    /// and each row kept (its fields and [`ROW_BYTES`]); a budget one byte short refuses it.
    #[test]
    fn reading_the_rows_is_charged_as_it_goes() {
        let text = format!("{HEADER}1,3,5,0.9,1 0 0 0 1 0 0 0 1,10 20 30,-1\n");
        let fields = "1350.91 0 0 0 1 0 0 0 110 20 30-1".len() as u64;
        let longest = text.lines().map(str::len).max().unwrap() as u64;
        let needed = longest + ROW_BYTES + fields;
        let ledger = Ledger::new(crate::limits::MemoryBudget::new(needed));
        parse_results(Path::new("r.csv"), &text, &ledger).unwrap();
        assert_eq!(ledger.held(), ROW_BYTES + fields, "the reader's record is given back, the rows kept");
        let ledger = Ledger::new(crate::limits::MemoryBudget::new(needed - 1));
        let e = parse_results(Path::new("r.csv"), &text, &ledger).unwrap_err().to_string();
        assert!(e.starts_with("the rows of r.csv needs about"), "{e}");
    }

    #[test]
    fn bad_rows_are_refused_naming_the_row_and_field() {
        let cases = [
            ("scene,im_id,obj_id,score,R,t,time\n", "the header must be exactly"),
            ("1,2,3,0.5,1 0 0 0 1 0 0 0 2,0 0 0,1\n", "row 1 (scene 1, image 2, object 3): R is not a rotation"),
            ("1,2,3,0.5,1 0 0 0 1 0 0 0,0 0 0,1\n", "R must be 9 finite numbers"),
            ("1,2,3,0.5,1 0 0 0 1 0 0 0 1,0 0,1\n", "t must be 3 finite numbers"),
            ("1,x,3,0.5,1 0 0 0 1 0 0 0 1,0 0 0,1\n", "row 1: im_id = \"x\""),
            ("1,2,3,high,1 0 0 0 1 0 0 0 1,0 0 0,1\n", "score = \"high\""),
            ("1,2,3,NaN,1 0 0 0 1 0 0 0 1,0 0 0,1\n", "score = \"NaN\" is not a finite number"),
            ("1,2,3,inf,1 0 0 0 1 0 0 0 1,0 0 0,1\n", "score = \"inf\" is not a finite number"),
            ("1,2,3,0.5,1 0 0 0 1 0 0 0 1,0 0 0,nan\n", "time = \"nan\" is not a finite number"),
            ("1,2,3,0.5,1 0 0 0 1 0 0 0 1,0 0 0,1e999\n", "time = \"1e999\" is not a finite number"),
            ("1,2,3,0.5,1 0 0 0 1 0 0 0 1,0 0 NaN,1\n", "t must be 3 finite numbers"),
            ("1,2,3,0.5,1 0 0 0 -1 0 0 0 -1,0 0 0,1\n1,2,3\n", "row 2"),
        ];
        let long = format!("1,2,3,0.5,1 0 0 0 1 0 0 0 1,0 0 0,{}\n", "\u{1b}".repeat(100_000));
        let cases = cases.into_iter().chain([(long.as_str(), "time = \"\\u{1b}")]);
        for (body, expected) in cases {
            let text = if body.starts_with("scene,") { body.to_string() } else { format!("{HEADER}{body}") };
            let e = parse_results(Path::new("r.csv"), &text, &Ledger::default()).unwrap_err().to_string();
            assert!(e.contains(expected) && e.contains("r.csv"), "{body:?}: expected {expected:?} in {e}");
            assert!(e.len() < 1000, "{} bytes of message", e.len());
        }
    }
}
