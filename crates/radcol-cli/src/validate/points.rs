//! `--at FILE.csv`: the points to evaluate u_n and û_n at, read and checked
//! before anything is solved.
//!
//! A file with a header row takes its columns by name (`x`, `y`, `z`, and
//! optionally `nx`, `ny`, `nz` and `label` or `name`; other columns are
//! ignored), so a reference file such as the path tracer's
//! `cornell_points_mitsuba.csv` is read as it is. Without a header, every row
//! is `x,y,z` or `x,y,z,nx,ny,nz`. One point per line (fields may be
//! quoted); blank lines and lines starting with `#` are skipped. Errors name
//! the file, line and column.

use super::outputs::{only, OutputFile};
use crate::error::{bad_input, BadInput};
use glam::DVec3;
use radcol_core::prelude::QueryPoint;
use std::path::{Path, PathBuf};

/// The points of `--at`, with their labels and where to write the values.
#[derive(Clone, Debug)]
pub struct PointsSpec {
    /// The file read.
    pub source: PathBuf,
    /// The points, in the file's order.
    pub points: Vec<QueryPoint>,
    /// Per point: its label, when the file has a label column.
    pub labels: Option<Vec<String>>,
    /// Per point: its line in the file.
    pub lines: Vec<u64>,
    /// `--at-out`, when given.
    pub out: Option<OutputFile>,
}

/// Which column holds what.
struct Columns {
    xyz: [usize; 3],
    normal: Option<[usize; 3]>,
    label: Option<usize>,
    /// Fields per row, in a file without a header.
    count: Option<usize>,
}

/// The largest `--at` file read: about ten million points.
const MAX_POINTS_FILE_BYTES: u64 = 1 << 30;

/// Reads `--at path` and checks `--at-out`.
pub(super) fn points(path: &Path, out: Option<&Path>, force: bool) -> Result<PointsSpec, BadInput> {
    let out = out
        .map(|p| only("--at-out", "csv", p, force, "the point values are CSV"))
        .transpose()?;
    let shown = path.display();
    // A device or a pipe never ends; a file of points is not gigabytes.
    let meta = std::fs::metadata(path).map_err(|e| bad_input(format!("--at {shown}: {e}")))?;
    if !meta.is_file() {
        return Err(bad_input(format!(
            "--at {shown}: not a regular file (a device, a pipe or a directory)"
        )));
    }
    if meta.len() > MAX_POINTS_FILE_BYTES {
        return Err(bad_input(format!(
            "--at {shown}: {} MiB is more than the {} MiB a points file may hold",
            meta.len() >> 20,
            MAX_POINTS_FILE_BYTES >> 20
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| bad_input(format!("--at {shown}: {e}")))?;
    let text =
        String::from_utf8(bytes).map_err(|_| bad_input(format!("--at {shown}: not UTF-8 text")))?;
    let mut columns: Option<Columns> = None;
    let mut spec = PointsSpec {
        source: path.to_path_buf(),
        points: Vec::new(),
        labels: None,
        lines: Vec::new(),
        out,
    };
    // Line by line (a point per line), each parsed as one CSV record.
    for (i, raw) in text.lines().enumerate() {
        let line = i as u64 + 1;
        // A spreadsheet's byte-order mark before the header is not a column name.
        let trimmed = raw.trim_start_matches('\u{feff}').trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let at = |m: String| bad_input(format!("{shown}:{line}: {m}"));
        let record = csv::ReaderBuilder::new()
            .has_headers(false)
            .trim(csv::Trim::All)
            .from_reader(trimmed.as_bytes())
            .records()
            .next()
            .transpose()
            .map_err(|e| at(e.to_string()))?
            .unwrap_or_default();
        let cols = match &columns {
            Some(c) => c,
            None if record.iter().all(|f| f.parse::<f64>().is_ok()) => {
                let c = positional(record.len()).ok_or_else(|| {
                    at(format!(
                        "{} columns; a point is x,y,z or x,y,z,nx,ny,nz (or name the columns in a header row)",
                        record.len()
                    ))
                })?;
                columns.insert(c)
            }
            None => {
                columns = Some(named(&record).map_err(at)?);
                continue;
            }
        };
        let (point, label) = row(&record, cols).map_err(at)?;
        spec.points.push(point);
        spec.lines.push(line);
        if let Some(l) = label {
            spec.labels.get_or_insert_with(Vec::new).push(l);
        }
    }
    if spec.points.is_empty() {
        return Err(bad_input(format!("--at {shown}: no points in the file")));
    }
    Ok(spec)
}

/// The columns of a header-less file with `n` fields per row.
fn positional(n: usize) -> Option<Columns> {
    match n {
        3 => Some(Columns {
            xyz: [0, 1, 2],
            normal: None,
            label: None,
            count: Some(3),
        }),
        6 => Some(Columns {
            xyz: [0, 1, 2],
            normal: Some([3, 4, 5]),
            label: None,
            count: Some(6),
        }),
        _ => None,
    }
}

/// The columns named by a header row.
fn named(header: &csv::StringRecord) -> Result<Columns, String> {
    let find = |name: &str| header.iter().position(|h| h.eq_ignore_ascii_case(name));
    let names: Vec<&str> = header.iter().collect();
    // A column read is named once: which of two would be meant is a guess.
    for name in ["x", "y", "z", "nx", "ny", "nz", "label", "name"] {
        let at: Vec<usize> = (names.iter().enumerate())
            .filter(|(_, h)| h.eq_ignore_ascii_case(name))
            .map(|(i, _)| i + 1)
            .collect();
        if at.len() > 1 {
            let at: Vec<String> = at.iter().map(usize::to_string).collect();
            return Err(format!(
                "the header names '{name}' more than once (columns {})",
                at.join(" and ")
            ));
        }
    }
    let need = |name: &str| {
        find(name).ok_or_else(|| {
            format!(
                "the header names no column '{name}' (it has: {}); a point needs x, y and z",
                names.join(", ")
            )
        })
    };
    let xyz = [need("x")?, need("y")?, need("z")?];
    let normal = match (find("nx"), find("ny"), find("nz")) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        (None, None, None) => None,
        _ => return Err("the header names some of nx, ny, nz but not all three".into()),
    };
    Ok(Columns {
        xyz,
        normal,
        label: find("label").or_else(|| find("name")),
        count: None,
    })
}

/// One row's point and label.
fn row(record: &csv::StringRecord, cols: &Columns) -> Result<(QueryPoint, Option<String>), String> {
    if let Some(n) = cols.count.filter(|&n| n != record.len()) {
        return Err(format!(
            "{} columns where the first point has {n}",
            record.len()
        ));
    }
    let number = |i: usize, what: &str| -> Result<f64, String> {
        let field = record
            .get(i)
            .ok_or_else(|| format!("no value for {what} (the row has {} fields)", record.len()))?;
        match field.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!("{what} = '{field}' is not a finite number")),
        }
    };
    let [x, y, z] = cols.xyz;
    let position = DVec3::new(number(x, "x")?, number(y, "y")?, number(z, "z")?);
    let normal = match cols.normal {
        Some([a, b, c]) => {
            let n = DVec3::new(number(a, "nx")?, number(b, "ny")?, number(c, "nz")?);
            let len = n.length();
            if !(len > 0.0 && len.is_finite()) {
                return Err(format!(
                    "the normal ({}, {}, {}) has no direction",
                    n.x, n.y, n.z
                ));
            }
            Some(n / len)
        }
        None => None,
    };
    let label = cols.label.map(|i| record.get(i).unwrap_or("").to_string());
    Ok((QueryPoint { position, normal }, label))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<PointsSpec, BadInput> {
        let dir = std::env::temp_dir().join(format!("radcol-points-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path = dir.join(format!("p{n}.csv"));
        std::fs::write(&path, text).unwrap();
        let r = points(&path, None, false);
        std::fs::remove_file(&path).ok();
        r
    }

    #[test]
    fn positional_and_named_columns() {
        let e = read("# comment\n1,2,3\n\n4, 5, 6, 0, 0, 2\n")
            .unwrap_err()
            .0;
        assert!(
            e.ends_with(":4: 6 columns where the first point has 3"),
            "{e}"
        );
        let s = read("1,2,3\n4,5,6\n").unwrap();
        assert_eq!(s.points.len(), 2);
        assert_eq!(s.points[1].position, DVec3::new(4.0, 5.0, 6.0));
        assert_eq!(s.lines, vec![1, 2]);
        let s = read("0,0,0,0,0,2\n").unwrap();
        assert_eq!(s.points[0].normal, Some(DVec3::Z));
        let s = read("\u{feff}X,Y,Z\r\n1,2,3\r\n").unwrap();
        assert_eq!(s.points[0].position, DVec3::new(1.0, 2.0, 3.0));
        let s = read("label,x,y,z,nx,ny,nz,extra\n\"a, b\",1,2,3,0,1,0,9\n").unwrap();
        assert_eq!(s.labels.as_deref(), Some(&["a, b".to_string()][..]));
        assert_eq!(s.points[0].normal, Some(DVec3::Y));
    }

    #[test]
    fn errors_name_the_line_and_value() {
        let e = read("x,y,z\n1,2,3\n1,oops,3\n").unwrap_err().0;
        assert!(e.ends_with(":3: y = 'oops' is not a finite number"), "{e}");
        let e = read("a,b,c\n1,2,3\n").unwrap_err().0;
        assert!(e.contains(":1: the header names no column 'x'"), "{e}");
        let e = read("x,y,z,nx,ny,nz\n1,2,3,0,0,0\n").unwrap_err().0;
        assert!(
            e.contains(":2: the normal (0, 0, 0) has no direction"),
            "{e}"
        );
        let e = read("1,2\n").unwrap_err().0;
        assert!(e.contains(":1: 2 columns"), "{e}");
        let e = read("# nothing\n").unwrap_err().0;
        assert!(e.contains("no points"), "{e}");
        let e = read("1,2,inf\n").unwrap_err().0;
        assert!(e.ends_with(":1: z = 'inf' is not a finite number"), "{e}");
    }
}
