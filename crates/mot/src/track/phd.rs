//! The SMC-PHD filter on boxes with its label-based track manager (`[phd_labels]`).

use phd_filter::Estimate;

use super::*;

/// Track management on top of the SMC-PHD filter's per-frame estimates (the labelled-PHD
/// practice of track-before-confirm, then a persistent id):
/// - an estimate continues the track that holds its PHD label, else the unmatched live track
///   whose last box it overlaps most (IoU ≥ `[phd_labels] min_iou`), else it starts a
///   tentative track;
/// - a tentative track is confirmed, and gets its id, at `confirm_hits` estimates within its
///   first `confirm_window` frames (its earlier boxes are output too), or is dropped;
/// - a confirmed track without an estimate keeps its id while the PHD mass of its label stays
///   at or above `min_mass` times what a missed target keeps ((p_S (1 − p_D)) per missed frame)
///   and for at most `max_misses` frames, and is output from its own constant-velocity
///   prediction (its last estimate moved on at the velocity between its last two estimates,
///   with the last estimate's size);
/// - frame numbers that no row names are frames without detections: the filter jumps them in
///   one prediction and the labeller coasts through them in closed form (`coast_through_gap`);
/// - a track that ends drops the coasted frames after its last estimate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PhdLabelConfig {
    /// Estimates a tentative track needs to be confirmed.
    pub confirm_hits: u32,
    /// Frames within which it needs them.
    pub confirm_window: u32,
    /// Overlap an estimate needs with a track's last box to continue it.
    pub min_iou: f64,
    /// Share of the mass a missed target keeps, (p_S (1 − p_D))^misses, that its label's PHD
    /// mass must hold for the track to keep its id.
    pub min_mass: f64,
    /// The most frames a confirmed track is output from the prediction (at most 10 000: a gap
    /// in the frame numbers costs at most this many boxes per track).
    pub max_misses: u32,
    /// A tentative track is dropped instead of confirmed when a confirmed track's predicted
    /// box covers at least this share of its own box: a second label on a target already
    /// followed (unset: never dropped for that; the fused tracker of [`crate::frames`] sets
    /// it).
    pub duplicate_cover: Option<f64>,
}

impl Default for PhdLabelConfig {
    fn default() -> Self {
        // General defaults: coast long (40 frames) and confirm on 2 hits, since the PHD path
        // loses mainly by misses on pedestrian files. The values `cargo xtask tune
        // mot-realistic` chose are fixtures/tuned/mot-realistic.toml.
        Self {
            confirm_hits: 2,
            confirm_window: 5,
            min_iou: 0.2,
            min_mass: 0.02,
            max_misses: 40,
            duplicate_cover: None,
        }
    }
}

/// A track of the PHD labeller.
struct PhdTrack {
    id: Option<u64>,
    phd_label: u64,
    first: Frame,
    hits: u32,
    misses: u32,
    /// Output points; the last `coasted` of them are predictions.
    points: Vec<TrackPoint>,
    coasted: usize,
    last_box: BoundingBox,
    velocity: Vec2,
    last_seen: Frame,
}

/// SMC-PHD on the boxes themselves, with [`PhdLabelConfig`]'s track management.
pub(super) fn track_boxes_phd(
    rows: &[MotRow],
    settings: &EffectiveConfig,
    seed: u64,
) -> Result<TrackSet> {
    let mut phd = SmcPhd::new(settings.phd, seed)?;
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<BoundingBox>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(r.bbox);
    }
    if by_frame.is_empty() {
        return Err(crate::error::Error::NoDetections {
            what: "the input".into(),
        });
    }
    // Only frames with detections are stepped. A frame number with no row is a frame in
    // which the detector found nothing (a MOTChallenge file has no way to say "no detector
    // ran"): the filter jumps such a gap of k frames in one prediction with the exact k-frame
    // transition and weights p_Sᵏ (1 − p_D)ᵏ⁻¹ (`SmcPhd::step_after`), and the labeller
    // coasts through it in closed form (`coast_through_gap`). The cost is bounded by the
    // detection frames, not by the span of frame numbers.
    let mut labeller = Labeller::new(settings.phd, settings.phd_labels);
    let mut previous: Option<Frame> = None;
    // The frames run on a thread of rayon's pool, so that the filter's parallel passes fork
    // from inside the pool. Called from outside it, each pass was handed to the pool and
    // waited for, a sleep and a wake-up of this thread per pass, which cost more than the
    // second thread saved: on the realistic files of `mot-realistic` the PHD tracker took
    // about 0.21 ms per frame that way and 0.15 this way (2 threads, load ≈ 3). The output is
    // the same either way: no result depends on the threads.
    rayon::scope(|_| -> Result<()> {
        for (&frame, boxes) in &by_frame {
            let frames = match previous {
                Some(prev) => {
                    let frames = u64::from(frame) - u64::from(prev);
                    labeller.coast_gap(prev, frames - 1, &phd);
                    frames
                }
                None => 1,
            };
            let step = phd.step_after(frames, boxes)?;
            labeller.take_frame(frame, &step.estimates, &phd);
            previous = Some(frame);
        }
        Ok(())
    })?;
    labeller.finish()
}

/// The track manager's state: live tracks (tentative or confirmed), ended ones, and the next
/// id to give. `--tracker phd` and the fused tracker of [`crate::frames`] share it: the
/// filter's labels are not tracks (a label can die and another take its target over, and a
/// newborn label need not be a target), so both confirm M of N, carry an id across label
/// changes by overlap, and coast a missed track while its label keeps its mass.
pub(crate) struct Labeller {
    config: PhdConfig,
    labels: PhdLabelConfig,
    live: Vec<PhdTrack>,
    done: Vec<PhdTrack>,
    next_id: u64,
}

impl Labeller {
    pub(crate) fn new(config: PhdConfig, labels: PhdLabelConfig) -> Self {
        Self {
            config,
            labels,
            live: Vec::new(),
            done: Vec::new(),
            next_id: 1,
        }
    }

    /// The `gap` frames after `prev` that had no step: [`coast_through_gap`], with the label
    /// masses of `phd` at `prev` (call before the filter steps past the gap).
    pub(crate) fn coast_gap(&mut self, prev: Frame, gap: u64, phd: &SmcPhd) {
        if gap > 0 {
            let (config, labels) = (self.config, self.labels);
            coast_through_gap(
                prev,
                gap,
                phd,
                &mut self.live,
                &mut self.done,
                config,
                labels,
            );
        }
    }

    /// A stepped frame: its estimates taken, tracks confirmed, coasted or ended with the
    /// label masses of `phd` after the step.
    pub(crate) fn take_frame(&mut self, frame: Frame, estimates: &[Estimate], phd: &SmcPhd) {
        let mass = LabelMasses::of(phd);
        let updated = self.take_estimates(frame, estimates);
        self.manage(frame, updated, &mass);
    }

    /// Gives each of a frame's estimates to the live track that holds its label, else to the
    /// unmatched one whose predicted box it overlaps most (IoU ≥ `min_iou`), else to a new
    /// tentative track. Returns, for each live track, whether it took an estimate.
    fn take_estimates(&mut self, frame: Frame, estimates: &[Estimate]) -> Vec<bool> {
        let live = &mut self.live;
        let mut updated = vec![false; live.len()];
        let mut unmatched = Vec::new();
        for e in estimates {
            match live
                .iter()
                .enumerate()
                .position(|(i, t)| !updated[i] && t.phd_label == e.label)
            {
                Some(i) => {
                    updated[i] = true;
                    observe(&mut live[i], frame, e.bbox, e.label);
                }
                None => unmatched.push(*e),
            }
        }
        for e in unmatched {
            let best = live
                .iter()
                .enumerate()
                .filter(|(i, _)| !updated[*i])
                .map(|(i, t)| (i, predicted(t, frame).iou(&e.bbox)))
                .filter(|&(_, iou)| iou >= self.labels.min_iou)
                .max_by(|a, b| a.1.total_cmp(&b.1));
            match best {
                Some((i, _)) => {
                    updated[i] = true;
                    observe(&mut live[i], frame, e.bbox, e.label);
                }
                None => {
                    live.push(PhdTrack {
                        id: None,
                        phd_label: e.label,
                        first: frame,
                        hits: 1,
                        misses: 0,
                        points: vec![TrackPoint::boxed(frame, e.bbox)],
                        coasted: 0,
                        last_box: e.bbox,
                        velocity: Vec2::zeros(),
                        last_seen: frame,
                    });
                    updated.push(true);
                }
            }
        }
        updated
    }

    /// After a frame: confirms the tentative tracks with enough hits (and drops those past
    /// their window), and keeps a missed confirmed track, coasted on its own prediction, while
    /// its label holds its share of the PHD mass and it has not missed too many frames.
    fn manage(&mut self, frame: Frame, updated: Vec<bool>, mass: &LabelMasses) {
        let (config, labels) = (self.config, self.labels);
        let followed: Vec<BoundingBox> = match labels.duplicate_cover {
            Some(_) => self
                .live
                .iter()
                .filter(|t| t.id.is_some())
                .map(|t| predicted(t, frame))
                .collect(),
            None => Vec::new(),
        };
        let mut kept = Vec::with_capacity(self.live.len());
        for (mut t, up) in self.live.drain(..).zip(updated) {
            if t.id.is_none() {
                if t.hits >= labels.confirm_hits
                    && covered(&t.last_box, &followed, labels.duplicate_cover)
                {
                    continue;
                }
                if t.hits >= labels.confirm_hits {
                    t.id = Some(self.next_id);
                    self.next_id += 1;
                } else if frame - t.first + 1 >= labels.confirm_window {
                    continue;
                }
            }
            if up {
                kept.push(t);
                continue;
            }
            t.misses += 1;
            let label_mass = mass.get(t.phd_label);
            // A missed target's PHD mass shrinks by p_S (1 − p_D) per frame; the label keeps
            // its track while it holds at least `min_mass` of that.
            let expected = (config.p_survive * (1.0 - config.p_detect)).powi(t.misses as i32);
            // Resampling gives a label about particles_per_target × its mass particles, so a
            // label missed for a few frames can lose them all: the track then keeps its id on
            // the frame count alone, still at most `max_misses` frames.
            let alive = t.id.is_some()
                && t.misses <= labels.max_misses
                && label_mass.is_none_or(|m| m >= labels.min_mass * expected);
            if !alive {
                if t.id.is_some() {
                    self.done.push(t);
                }
                continue;
            }
            // The output: the track's own constant-velocity prediction from its last two
            // estimates, with the last size. (The label's particle mean, output before, lags
            // and spreads once the label has missed a few frames: on the tuning sequences
            // of `mot-realistic` the prediction gave mean MOTA 0.863 against 0.843.)
            let bbox = predicted(&t, frame);
            t.points.push(TrackPoint::boxed(frame, bbox));
            t.coasted += 1;
            kept.push(t);
        }
        self.live = kept;
    }

    /// The confirmed tracks, each without the coasted frames after its last estimate.
    pub(crate) fn finish(self) -> Result<TrackSet> {
        let mut done = self.done;
        done.extend(self.live.into_iter().filter(|t| t.id.is_some()));
        let mut tracks = Vec::with_capacity(done.len());
        for mut t in done {
            let n = t.points.len() - t.coasted;
            t.points.truncate(n);
            if let Some(id) = t.id {
                tracks.push(Track::from_points(TrackId(id), t.points)?);
            }
        }
        Ok(TrackSet::from_tracks(tracks)?)
    }
}

/// Whether one of the `followed` boxes covers at least `cover` of `bbox`'s area.
fn covered(bbox: &BoundingBox, followed: &[BoundingBox], cover: Option<f64>) -> bool {
    let area = bbox.area();
    cover.is_some_and(|c| {
        area > 0.0
            && followed
                .iter()
                .any(|f| f.intersection_area(bbox) >= c * area)
    })
}

/// A PHD track takes an estimate: coasted points stay (they were output), velocity from the
/// last two estimates.
fn observe(t: &mut PhdTrack, frame: Frame, bbox: BoundingBox, label: u64) {
    let gap = f64::from(frame - t.last_seen).max(1.0);
    t.velocity = (bbox.centre() - t.last_box.centre()) / gap;
    t.points.push(TrackPoint::boxed(frame, bbox));
    t.coasted = 0;
    t.hits += 1;
    t.misses = 0;
    t.last_box = bbox;
    t.last_seen = frame;
    t.phd_label = label;
}

/// A PHD track's box moved on at its last velocity to `frame`.
fn predicted(t: &PhdTrack, frame: Frame) -> BoundingBox {
    let dt = f64::from(frame.saturating_sub(t.last_seen));
    let c = t.last_box.centre() + t.velocity * dt;
    BoundingBox::from_centre(c, t.last_box.width, t.last_box.height).unwrap_or(t.last_box)
}

/// The PHD mass of every label's particles, sorted by label.
struct LabelMasses(Vec<(u64, f64)>);

impl LabelMasses {
    /// One pass over the particles: a label's particles are mostly adjacent (resampling keeps
    /// their order and each newborn group joins as one run), so the mass is summed per run and
    /// the runs merged after a sort by label, rather than looked up per particle in a hash map
    /// (which took about a sixth of the PHD tracker's instructions).
    fn of(phd: &SmcPhd) -> Self {
        let mut runs: Vec<(u64, f64)> = Vec::new();
        let mut particles = phd.particles().iter();
        if let Some(first) = particles.next() {
            // The current run in locals, pushed when the label changes.
            let (mut label, mut mass) = (first.label, first.w);
            for p in particles {
                if p.label == label {
                    mass += p.w;
                } else {
                    runs.push((label, mass));
                    (label, mass) = (p.label, p.w);
                }
            }
            runs.push((label, mass));
        }
        // Stable: the runs of one label are summed in particle order.
        runs.sort_by_key(|r| r.0);
        let mut merged: Vec<(u64, f64)> = Vec::with_capacity(runs.len());
        for (label, m) in runs {
            match merged.last_mut() {
                Some(last) if last.0 == label => last.1 += m,
                _ => merged.push((label, m)),
            }
        }
        Self(merged)
    }

    /// The label's mass, if any particle carries it.
    fn get(&self, label: u64) -> Option<f64> {
        self.0
            .binary_search_by_key(&label, |r| r.0)
            .ok()
            .map(|i| self.0[i].1)
    }
}

/// The labeller through the `gap` frames after `prev` that hold no detection, in closed form
/// and in one pass over the live tracks, while the filter jumps them in one prediction.
/// Stepping each empty frame would give no estimate, so:
/// - a tentative track ends at the gap's first frame (it missed a frame before confirmation);
/// - a confirmed track keeps its id through the gap iff it would at every frame of it: at most
///   `max_misses` misses in all, and its label's mass at `prev`, m, at least `min_mass`
///   (p_S (1 − p_D))^misses (through the gap the label's mass and the bound shrink by the same
///   p_S (1 − p_D) per frame, so the check at each frame is this one). It is output at each
///   frame prev + j from its own constant-velocity prediction, as at a stepped miss;
/// - a track that ends in the gap keeps no coasted frame (they would be dropped at its end).
///
/// At most `max_misses` (≤ 10 000) boxes per track per gap, whatever the gap's length.
fn coast_through_gap(
    prev: Frame,
    gap: u64,
    phd: &SmcPhd,
    live: &mut Vec<PhdTrack>,
    done: &mut Vec<PhdTrack>,
    config: PhdConfig,
    labels: PhdLabelConfig,
) {
    let per_frame = config.p_survive * (1.0 - config.p_detect);
    let mass = LabelMasses::of(phd);
    let mut kept = Vec::with_capacity(live.len());
    for mut t in live.drain(..) {
        if t.id.is_none() {
            continue;
        }
        let label = mass.get(t.phd_label);
        let holds = label.is_none_or(|m| {
            // misses ≤ max_misses ≤ 10 000 fits an i32.
            m >= labels.min_mass * per_frame.powi(t.misses as i32)
        });
        if u64::from(t.misses) + gap > u64::from(labels.max_misses) || !holds {
            done.push(t);
            continue;
        }
        for j in 1..=gap {
            // j ≤ gap = frame − prev − 1 ≤ max_misses, so prev + j fits a Frame.
            let frame = prev + j as Frame;
            // As at a stepped miss: the track's own prediction.
            let bbox = predicted(&t, frame);
            t.points.push(TrackPoint::boxed(frame, bbox));
        }
        t.coasted += gap as usize;
        t.misses += gap as u32;
        kept.push(t);
    }
    *live = kept;
}

/// The most frames a PHD track may coast (`[phd_labels] max_misses`): a gap in the frame
/// numbers costs at most this many boxes per live track.
pub(super) const MAX_COAST_FRAMES: u32 = 10_000;

impl PhdLabelConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        // Without 1 ≤ M ≤ N no tentative track is ever confirmed, and the file would track to
        // nothing with no word why.
        if self.confirm_hits == 0 || self.confirm_window < self.confirm_hits {
            return Err(crate::error::invalid(
                "confirm_hits",
                format!(
                    "confirmation {} of {} needs 1 ≤ M ≤ N (confirm_hits ≤ confirm_window)",
                    self.confirm_hits, self.confirm_window
                ),
            ));
        }
        if !(0.0..=1.0).contains(&self.min_iou) {
            return Err(crate::error::invalid(
                "min_iou",
                format!("{} must be in [0, 1]", self.min_iou),
            ));
        }
        if !(self.min_mass.is_finite() && self.min_mass >= 0.0) {
            return Err(crate::error::invalid(
                "min_mass",
                format!("{} must be finite and ≥ 0", self.min_mass),
            ));
        }
        if let Some(cover) = self.duplicate_cover
            && !(cover.is_finite() && cover > 0.0 && cover <= 1.0)
        {
            return Err(crate::error::invalid(
                "duplicate_cover",
                format!("{cover} must be in (0, 1]"),
            ));
        }
        if self.max_misses > MAX_COAST_FRAMES {
            return Err(crate::error::invalid(
                "max_misses",
                format!(
                    "{} is over {MAX_COAST_FRAMES}: a track coasts at most that many frames, so \
                     that a gap in the frame numbers costs a bounded number of boxes",
                    self.max_misses
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(frame: Frame, left: f64, top: f64) -> MotRow {
        MotRow {
            frame,
            id: -1,
            bbox: BoundingBox::new(left, top, 40.0, 100.0).unwrap(),
            confidence: 0.9,
            world: [-1.0; 3],
        }
    }

    #[test]
    fn a_second_label_inside_a_followed_target_is_not_confirmed() {
        let estimate = |label, left: f64| Estimate {
            label,
            state: [0.0; 6],
            bbox: BoundingBox::new(left, 100.0, 40.0, 100.0).unwrap(),
            weight: 1.0,
            measurement: None,
        };
        let inside = |label| Estimate {
            bbox: BoundingBox::new(105.0, 110.0, 20.0, 60.0).unwrap(),
            ..estimate(label, 0.0)
        };
        let no_mass = LabelMasses(Vec::new());
        let run = |cover| {
            let labels = PhdLabelConfig {
                duplicate_cover: cover,
                ..PhdLabelConfig::default()
            };
            let mut labeller = Labeller::new(PhdConfig::default(), labels);
            // Label 1 is confirmed at its second estimate (frame 2); label 2, wholly inside
            // its box, from frame 2; label 3 far away from frame 2.
            for frame in 1..=5 {
                let mut estimates = vec![estimate(1, 100.0)];
                if frame >= 2 {
                    estimates.extend([inside(2), estimate(3, 400.0)]);
                }
                let updated = labeller.take_estimates(frame, &estimates);
                labeller.manage(frame, updated, &no_mass);
            }
            labeller.finish().unwrap().len()
        };
        // Label 2's box is 100 % covered by label 1's: dropped with any cover ≤ 1; the far
        // label 3 is confirmed either way.
        assert_eq!(run(Some(1.0)), 2);
        assert_eq!(run(Some(0.2)), 2);
        assert_eq!(run(None), 3);
    }

    #[test]
    fn label_masses_match_a_sum_per_particle() {
        // Two walkers and a clutter box a frame: labels interleave after a few frames.
        let config =
            PhdConfig::for_boxes(&[BoundingBox::new(0.0, 0.0, 40.0, 100.0).unwrap()]).unwrap();
        let mut phd = SmcPhd::new(config, 5).unwrap();
        for f in 0..12 {
            let t = f64::from(f);
            let boxes = [
                BoundingBox::new(100.0 + 3.0 * t, 100.0, 40.0, 100.0).unwrap(),
                BoundingBox::new(400.0 - 2.0 * t, 150.0, 40.0, 100.0).unwrap(),
                BoundingBox::new(50.0 + 37.0 * t, 300.0, 40.0, 100.0).unwrap(),
            ];
            phd.step(&boxes).unwrap();
        }
        let masses = LabelMasses::of(&phd);
        // The brute force: every particle's weight added to its label's total.
        let mut brute: std::collections::BTreeMap<u64, f64> = Default::default();
        for p in phd.particles() {
            *brute.entry(p.label).or_default() += p.w;
        }
        assert!(brute.len() >= 2);
        assert_eq!(masses.0.len(), brute.len());
        for (label, m) in &brute {
            let got = masses.get(*label).unwrap();
            assert!(
                (got - m).abs() <= 1e-12 * m.max(1.0),
                "{label}: {got} vs {m}"
            );
        }
        assert_eq!(masses.get(u64::MAX), None);
    }

    #[test]
    fn a_missed_track_is_output_on_its_last_two_estimates_velocity() {
        // Walker a moves (3, 1) px a frame and is missed in frames 12-14, while walker b,
        // far away, keeps every frame stepped. Through the miss, a's boxes continue its
        // last two estimates exactly: the box of frame 11 moved on by the centre's change
        // from frame 10 to 11, per frame, with frame 11's size.
        let mut rows = Vec::new();
        for f in 1..=25u32 {
            let t = f64::from(f);
            if !(12..=14).contains(&f) {
                rows.push(row(f, 100.0 + 3.0 * t, 100.0 + t));
            }
            rows.push(row(f, 700.0 - 2.0 * t, 400.0));
        }
        let tracks = track_detections(TrackerKind::Phd, &rows, &TrackConfig::default(), 3).unwrap();
        let a: Vec<&Track> = tracks
            .tracks()
            .iter()
            .filter(|t| t.points().iter().any(|p| p.location.position().x < 400.0))
            .collect();
        assert_eq!(a.len(), 1, "walker a has {} ids", a.len());
        let at = |f: Frame| {
            a[0].points()
                .iter()
                .find(|p| p.frame == f)
                .map(|p| match p.location {
                    tracker_model::Location::Box(b) => b,
                    tracker_model::Location::Point(_) => panic!("a point without a box"),
                })
                .unwrap_or_else(|| panic!("frame {f} missing"))
        };
        let (b10, b11) = (at(10), at(11));
        let v = b11.centre() - b10.centre();
        for f in 12..=14u32 {
            let b = at(f);
            let expected = b11.centre() + v * f64::from(f - 11);
            assert!((b.centre() - expected).norm() < 1e-9, "frame {f}: {b:?}");
            assert!((b.width - b11.width).abs() < 1e-9 && (b.height - b11.height).abs() < 1e-9);
        }
        // The same id after the miss.
        assert!(at(15).iou(&at(14)) > 0.3);
    }
}
