//! Trackers: SORT, ByteTrack and OC-SORT stepped frame by frame (`BoxTracker.update`), and
//! every detection-file tracker of the `mot` crate on arrays (`track`) or a file
//! (`track_file`), as `cargo xtask track` runs them.

use std::path::PathBuf;

use box_trackers::{
    BoxTracker as Stepper, ByteTrackConfig, ByteTrackTracker, OcSortConfig, OcSortTracker,
    SortConfig, SortTracker,
};
use mot::track::{TrackConfig, TrackerKind, track_detections};
use numpy::PyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tracker_model::{BoundingBox, Detection, Frame, MotRow, TrackSet};

use crate::arrays::{Table, table, to_numpy};
use crate::errors::{IntoPy, invalid};

/// The columns of a detection array.
const DETS: &str = "(N, 6): x1, y1, x2, y2, score, class";
/// The columns `BoxTracker.update` returns.
pub(crate) const OUT_COLS: usize = 8;

/// One of the three box trackers.
enum Kind {
    Sort(SortTracker),
    ByteTrack(ByteTrackTracker),
    OcSort(OcSortTracker),
}

/// Settings from keyword arguments: every key must be a field of `T` (serde's message
/// names the unknown one and lists the fields).
pub(crate) fn settings<T: serde::de::DeserializeOwned + Default>(
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<T> {
    match params {
        Some(dict) if !dict.is_empty() => pythonize::depythonize(dict.as_any()).or_raise(),
        _ => Ok(T::default()),
    }
}

/// A box tracker stepped once per frame: `update(dets)` with a frame's detections gives the
/// confirmed tracks' boxes.
#[pyclass(module = "tracking_toolkit._native")]
pub struct BoxTracker {
    tracker: Kind,
    frame: Frame,
}

/// A coasted track: id and corners.
type Coasted = (u64, [f64; 4]);
/// A step's output: (track id, detection index) of each assigned track, then the coasted.
type StepOutput = (Vec<(u64, usize)>, Vec<Coasted>);

impl BoxTracker {
    fn step(&mut self, frame: Frame, detections: &[Detection]) -> PyResult<StepOutput> {
        fn run<A: box_trackers::Association>(
            t: &mut Stepper<A>,
            frame: Frame,
            detections: &[Detection],
        ) -> box_trackers::Result<StepOutput> {
            let assigned = t.update(frame, detections)?;
            let coasted = t
                .coasted()
                .into_iter()
                .map(|(id, b)| (id.0, [b.left, b.top, b.right(), b.bottom()]))
                .collect();
            Ok((
                assigned.iter().map(|a| (a.track.0, a.index)).collect(),
                coasted,
            ))
        }
        match &mut self.tracker {
            Kind::Sort(t) => run(t, frame, detections),
            Kind::ByteTrack(t) => run(t, frame, detections),
            Kind::OcSort(t) => run(t, frame, detections),
        }
        .or_raise()
    }
}

#[pymethods]
impl BoxTracker {
    /// `kind` is "sort", "bytetrack" or "ocsort"; `params` the settings.
    #[new]
    #[pyo3(signature = (kind, params=None))]
    fn new(kind: &str, params: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        // No history: `update` returns all a caller reads, so memory stays with the live tracks.
        let tracker = match kind {
            "sort" => Kind::Sort(
                settings::<SortConfig>(params)?
                    .build()
                    .or_raise()?
                    .without_history(),
            ),
            "bytetrack" => Kind::ByteTrack(
                settings::<ByteTrackConfig>(params)?
                    .build()
                    .or_raise()?
                    .without_history(),
            ),
            "ocsort" => Kind::OcSort(
                settings::<OcSortConfig>(params)?
                    .build()
                    .or_raise()?
                    .without_history(),
            ),
            other => {
                return Err(invalid(format!(
                    "unknown box tracker {other:?}; expected sort, bytetrack or ocsort"
                )));
            }
        };
        Ok(Self { tracker, frame: 0 })
    }

    /// One frame's detections (N, 6) → the confirmed tracks (M, 8): x1, y1, x2, y2, id,
    /// score, class, detection index (−1, with NaN score and class −1, for a coasted track).
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        dets: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (dets, boxes) = read_dets(dets)?;
        let next = self.frame.checked_add(1).ok_or_else(|| {
            PyValueError::new_err("the tracker has stepped u32::MAX frames; start a new one")
        })?;
        let detections: Vec<Detection> = boxes
            .into_iter()
            .enumerate()
            .map(|(i, b)| Detection::boxed(i as u64, next, b).with_score(dets.row(i)[4]))
            .collect();
        // Advanced first: a step that failed half-way has still used its frame number.
        self.frame = next;
        let (assigned, coasted) = py.detach(|| self.step(next, &detections))?;
        let mut out = Vec::with_capacity((assigned.len() + coasted.len()) * OUT_COLS);
        for (id, index) in assigned {
            let d = dets.row(index);
            out.extend_from_slice(&[d[0], d[1], d[2], d[3], id as f64, d[4], d[5], index as f64]);
        }
        for (id, c) in coasted {
            out.extend_from_slice(&[c[0], c[1], c[2], c[3], id as f64, f64::NAN, -1.0, -1.0]);
        }
        to_numpy(py, out, OUT_COLS)
    }

    /// Frames stepped so far.
    #[getter]
    fn frame_count(&self) -> u32 {
        self.frame
    }
}

/// A frame's detections (N, 6) and their boxes.
pub(crate) fn read_dets(obj: &Bound<'_, PyAny>) -> PyResult<(Table, Vec<BoundingBox>)> {
    let dets = table(obj, "dets", (6, 6), DETS)?;
    let boxes = dets
        .iter()
        .enumerate()
        .map(|(i, d)| corners_box(d, i))
        .collect::<PyResult<Vec<_>>>()?;
    Ok((dets, boxes))
}

/// Row `i`'s x1, y1, x2, y2 as a box (finite, x2 ≥ x1, y2 ≥ y1).
pub(crate) fn corners_box(d: &[f64], i: usize) -> PyResult<BoundingBox> {
    if !d[..5].iter().all(|v| v.is_finite()) {
        return Err(invalid(format!(
            "dets row {i} has a value that is not finite: {:?}",
            &d[..5]
        )));
    }
    BoundingBox::new(d[0], d[1], d[2] - d[0], d[3] - d[1])
        .map_err(|e| invalid(format!("dets row {i}: {e}")))
}

/// The detection-file trackers' names (`track`'s and `track_file`'s `tracker`).
#[pyfunction]
pub fn tracker_names() -> Vec<&'static str> {
    TrackerKind::ALL.iter().map(|k| k.name()).collect()
}

fn kind_of(name: &str) -> PyResult<TrackerKind> {
    name.parse::<TrackerKind>().or_raise()
}

/// The configuration: a dict of the TOML tables (`{"gnn": {"max_gap": 5}}`), a path to a
/// TOML file, or nothing.
fn track_config(config: Option<&Bound<'_, PyAny>>) -> PyResult<TrackConfig> {
    let Some(config) = config.filter(|c| !c.is_none()) else {
        return Ok(TrackConfig::default());
    };
    if let Ok(path) = config.extract::<PathBuf>() {
        let text = std::fs::read_to_string(&path)
            .map_err(|e| invalid(format!("cannot read {}: {e}", path.display())))?;
        return toml::from_str(&text).map_err(|e| invalid(format!("in {}: {e}", path.display())));
    }
    // Through TOML text, so a mistake is reported as in a configuration file: with the
    // table and key around it.
    let table: toml::Table = pythonize::depythonize(config).or_raise()?;
    let text = toml::to_string(&table).map_err(|e| invalid(format!("config: {e}")))?;
    toml::from_str(&text).map_err(|e| invalid(format!("config: {e}")))
}

/// A track set as MOTChallenge rows (K, 6): frame, id, left, top, width, height, by frame
/// (`evaluate` reads them as they are).
fn track_rows<'py>(py: Python<'py>, set: &TrackSet) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let mut out = Vec::with_capacity(set.n_points() * 6);
    for row in set.to_mot_rows(0.0) {
        let b = row.bbox;
        out.extend_from_slice(&[
            f64::from(row.frame),
            row.id as f64,
            b.left,
            b.top,
            b.width,
            b.height,
        ]);
    }
    to_numpy(py, out, 6)
}

/// Runs `tracker` on `rows` with the GIL released.
fn run(
    py: Python<'_>,
    tracker: &str,
    rows: &[MotRow],
    config: Option<&Bound<'_, PyAny>>,
    seed: u64,
) -> PyResult<TrackSet> {
    let kind = kind_of(tracker)?;
    let config = track_config(config)?;
    py.detach(|| track_detections(kind, rows, &config, seed))
        .or_raise()
}

/// Tracks a sequence of frames' detections (frame i + 1 is `dets_by_frame[i]`, each (N, 6)).
#[pyfunction]
#[pyo3(signature = (dets_by_frame, tracker="mcmcda", config=None, seed=0))]
pub fn track<'py>(
    py: Python<'py>,
    dets_by_frame: &Bound<'py, PyAny>,
    tracker: &str,
    config: Option<&Bound<'py, PyAny>>,
    seed: u64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let mut rows = Vec::new();
    for (i, frame) in dets_by_frame.try_iter()?.enumerate() {
        let dets = table(&frame?, &format!("dets_by_frame[{i}]"), (6, 6), DETS)?;
        let frame = Frame::try_from(i + 1).map_err(|_| invalid("more than u32::MAX frames"))?;
        for (j, d) in dets.iter().enumerate() {
            rows.push(MotRow {
                frame,
                id: -1,
                bbox: corners_box(d, j).map_err(|e| invalid(format!("dets_by_frame[{i}]: {e}")))?,
                confidence: d[4],
                world: [-1.0; 3],
            });
        }
    }
    let set = run(py, tracker, &rows, config, seed)?;
    track_rows(py, &set)
}

/// Tracks a MOTChallenge detection file as `cargo xtask track` does; writes the tracks to
/// `out` when given (the same text) and returns them as `track` does.
#[pyfunction]
#[pyo3(signature = (path, tracker="mcmcda", config=None, seed=0, out=None))]
pub fn track_file<'py>(
    py: Python<'py>,
    path: PathBuf,
    tracker: &str,
    config: Option<&Bound<'py, PyAny>>,
    seed: u64,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let text = std::fs::read_to_string(&path)
        .map_err(|e| invalid(format!("cannot read {}: {e}", path.display())))?;
    let (rows, _notes) =
        mot::text::read_detections(&text, &path.display().to_string()).or_raise()?;
    let set = run(py, tracker, &rows, config, seed)?;
    if let Some(out) = out {
        std::fs::write(&out, mot::text::format_tracks(&set))
            .map_err(|e| invalid(format!("cannot write {}: {e}", out.display())))?;
    }
    track_rows(py, &set)
}
