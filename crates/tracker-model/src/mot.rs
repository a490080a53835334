//! MOTChallenge text rows: `frame,id,left,top,width,height,conf,x,y,z`.
//!
//! Ground-truth and result files of MOT15-MOT20 have 6 to 10 comma-separated columns; the
//! missing trailing ones take the MOTChallenge defaults (conf = 1, x = y = z = −1). MOT16/17
//! ground truth reuses columns 8 and 9 for class and visibility; they are kept as `world`
//! values and left to the caller to interpret.
//!
//! Bad input: a malformed row is an [`Error::Parse`] naming its line; a box of zero width or
//! height is an [`Error::ZeroAreaBox`] (its IoU is 0/0, so it could never match, not even
//! itself). A header line (the first non-blank line when none of its fields is a number, e.g.
//! `frame,id,bb_left,...`) is skipped and returned in [`MotFile::header`] so that the caller can
//! say so.

use std::collections::BTreeMap;
use std::fmt;
use std::io::BufRead;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geometry::BoundingBox;
use crate::track::{Frame, Location, Track, TrackId, TrackPoint, TrackSet};

/// One row of a MOTChallenge file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotRow {
    /// Frame number (1-based in MOTChallenge files).
    pub frame: Frame,
    /// Object id; −1 in detection files.
    pub id: i64,
    /// The box.
    pub bbox: BoundingBox,
    /// Confidence (ground truth: 1 = consider, 0 = ignore).
    pub confidence: f64,
    /// World coordinates x, y, z (−1 when unused).
    pub world: [f64; 3],
}

impl fmt::Display for MotRow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{},{},{},{},{},{},{},{},{},{}",
            self.frame,
            self.id,
            self.bbox.left,
            self.bbox.top,
            self.bbox.width,
            self.bbox.height,
            self.confidence,
            self.world[0],
            self.world[1],
            self.world[2]
        )
    }
}

/// What [`read_mot`] found: the rows and the header line it skipped, if any.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MotFile {
    /// Every row, in file order.
    pub rows: Vec<MotRow>,
    /// The skipped header: its 1-based line number and text.
    pub header: Option<(usize, String)>,
}

/// Parses every row of a MOTChallenge file. Blank lines are skipped, and so is a header (the
/// first non-blank line, when none of its comma-separated fields is a number), which is
/// returned; anything else that is not a valid row is an error naming its 1-based line number
/// and the problem.
pub fn read_mot<R: BufRead>(reader: R) -> Result<MotFile> {
    let mut file = MotFile::default();
    let mut first = true;
    for (idx, line) in reader.lines().enumerate() {
        let line_no = idx + 1;
        let line = line.map_err(|e| Error::Io(format!("line {line_no}: {e}")))?;
        let text = line.trim();
        if text.is_empty() {
            continue;
        }
        if std::mem::take(&mut first) && is_header(text) {
            file.header = Some((line_no, text.to_string()));
            continue;
        }
        let row = parse_row(text).map_err(|reason| Error::Parse {
            line: line_no,
            reason,
        })?;
        if row.bbox.width == 0.0 || row.bbox.height == 0.0 {
            return Err(Error::ZeroAreaBox {
                line: line_no,
                width: row.bbox.width,
                height: row.bbox.height,
            });
        }
        let b = &row.bbox;
        let lost = |start: f64, size: f64| ((start + size) - start - size).abs() > 1e-6 * size;
        if lost(b.left, b.width) || lost(b.top, b.height) {
            return Err(Error::BoxBeyondPrecision {
                line: line_no,
                left: b.left,
                top: b.top,
                width: b.width,
                height: b.height,
            });
        }
        file.rows.push(row);
    }
    Ok(file)
}

/// A header names the columns: as many fields as a row, none of them a number.
fn is_header(text: &str) -> bool {
    let fields: Vec<&str> = text.split(',').collect();
    (6..=10).contains(&fields.len()) && fields.iter().all(|f| f.trim().parse::<f64>().is_err())
}

/// The rows of [`read_mot`], without the header it may have skipped.
pub fn parse_mot<R: BufRead>(reader: R) -> Result<Vec<MotRow>> {
    read_mot(reader).map(|file| file.rows)
}

fn parse_row(text: &str) -> std::result::Result<MotRow, String> {
    const NAMES: [&str; 10] = [
        "frame", "id", "left", "top", "width", "height", "conf", "x", "y", "z",
    ];
    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
    if !(6..=10).contains(&fields.len()) {
        return Err(format!(
            "expected 6 to 10 comma-separated columns (frame,id,left,top,width,height,conf,x,y,z), found {}",
            fields.len()
        ));
    }
    let mut values = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, -1.0, -1.0, -1.0];
    for (col, field) in fields.iter().enumerate() {
        let v: f64 = field.parse().map_err(|_| {
            format!(
                "column {} ({}) is not a number: {field:?}",
                col + 1,
                NAMES[col]
            )
        })?;
        if !v.is_finite() {
            return Err(format!(
                "column {} ({}) is not finite: {field:?}",
                col + 1,
                NAMES[col]
            ));
        }
        values[col] = v;
    }
    let frame = values[0];
    if frame.fract() != 0.0 || frame < 0.0 || frame > f64::from(u32::MAX) {
        return Err(format!(
            "frame must be a non-negative integer, found {}",
            fields[0]
        ));
    }
    let id = values[1];
    if id.fract() != 0.0 || id.abs() > 9.0e15 {
        return Err(format!("id must be an integer, found {}", fields[1]));
    }
    let bbox =
        BoundingBox::new(values[2], values[3], values[4], values[5]).map_err(|e| e.to_string())?;
    Ok(MotRow {
        frame: frame as Frame,
        id: id as i64,
        bbox,
        confidence: values[6],
        world: [values[7], values[8], values[9]],
    })
}

/// Formats rows as MOTChallenge text, one line per row, each ending in a newline.
pub fn format_mot(rows: &[MotRow]) -> String {
    rows.iter().map(|r| format!("{r}\n")).collect()
}

impl TrackSet {
    /// Groups MOTChallenge rows into box tracks by id. A repeated (frame, id) is an error; ids
    /// must be non-negative (detection files with id −1 are not tracks).
    pub fn from_mot_rows(rows: &[MotRow]) -> Result<TrackSet> {
        let mut by_id: BTreeMap<i64, Vec<TrackPoint>> = BTreeMap::new();
        for row in rows {
            if row.id < 0 {
                return Err(Error::InvalidParameter {
                    name: "track id",
                    reason: format!(
                        "frame {}: id {} is negative; tracks need ids >= 0",
                        row.frame, row.id
                    ),
                });
            }
            by_id
                .entry(row.id)
                .or_default()
                .push(TrackPoint::boxed(row.frame, row.bbox));
        }
        let mut set = TrackSet::new();
        for (id, mut points) in by_id {
            points.sort_by_key(|p| p.frame);
            if let Some(w) = points.windows(2).find(|w| w[0].frame == w[1].frame) {
                return Err(Error::InvalidParameter {
                    name: "track point frame",
                    reason: format!("id {id} has two rows at frame {}", w[0].frame),
                });
            }
            set.push(Track::from_points(TrackId(id as u64), points)?)?;
        }
        Ok(set)
    }

    /// MOTChallenge rows of every track point, sorted by frame then id. Point locations become
    /// boxes of size `point_box_size` centred on the point.
    pub fn to_mot_rows(&self, point_box_size: f64) -> Vec<MotRow> {
        let mut rows = Vec::with_capacity(self.n_points());
        for (frame, points) in self.by_frame() {
            for (id, p) in points {
                let bbox = match p.location {
                    Location::Box(b) => b,
                    Location::Point(c) => BoundingBox {
                        left: c.x - point_box_size / 2.0,
                        top: c.y - point_box_size / 2.0,
                        width: point_box_size,
                        height: point_box_size,
                    },
                };
                rows.push(MotRow {
                    frame,
                    id: id.0 as i64,
                    bbox,
                    confidence: 1.0,
                    world: [-1.0; 3],
                });
            }
        }
        rows
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_whose_size_is_lost_to_rounding_are_refused() {
        // Found by the eval fuzzer: at left = 3.3e17 the f64 grid is 64 apart, so a 20-wide
        // box did not match itself (IoU 0). Far-out but representable boxes still load.
        let far = "2,1,333333333333333311,20,20,40,1,-1,-1,-1\n";
        assert!(matches!(
            read_mot(far.as_bytes()),
            Err(Error::BoxBeyondPrecision { line: 1, .. })
        ));
        let tall = "2,1,0,1e300,20,40,1,-1,-1,-1\n";
        assert!(matches!(
            read_mot(tall.as_bytes()),
            Err(Error::BoxBeyondPrecision { .. })
        ));
        let utm = "2,1,4500000.25,600000.5,0.75,1.5,1,-1,-1,-1\n";
        let rows = read_mot(utm.as_bytes()).map(|f| f.rows).unwrap_or_default();
        assert_eq!(rows.len(), 1);
        assert!((rows[0].bbox.iou(&rows[0].bbox) - 1.0).abs() < 1e-9);
    }
}
