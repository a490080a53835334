//! The SMC-PHD filter on boxes with its label-based track manager (`[phd_labels]`).

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
///   and for at most `max_misses` frames, and is output from the prediction (the weighted
///   mean of its label's particles, or, once resampling has left the label none, the track's
///   own constant-velocity prediction);
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
}

impl Default for PhdLabelConfig {
    fn default() -> Self {
        // Chosen on the tuning sequences of `mot-realistic` (mean MOTA / IDF1 there), where
        // the PHD path lost to online MCMCDA mainly by misses (FN), not false boxes: from
        // 3 hits, IoU 0.3, mass 0.1 and 8 frames (0.800 / 0.622), coasting 15 frames gave
        // 0.825 / 0.683, 40 with 2 hits and mass 0.02 0.842 / 0.771 (80 the same: tracks end
        // by their label's mass before), IoU 0.2 then 0.843 / 0.808 (0.1, tried with an
        // extraction threshold of 0.3 only: MOTA alike, IDF1 higher).
        Self {
            confirm_hits: 2,
            confirm_window: 5,
            min_iou: 0.2,
            min_mass: 0.02,
            max_misses: 40,
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
    let config = settings.phd;
    let labels = settings.phd_labels;
    let mut phd = SmcPhd::new(config, seed)?;
    let mut by_frame: std::collections::BTreeMap<Frame, Vec<BoundingBox>> = Default::default();
    for r in rows {
        by_frame.entry(r.frame).or_default().push(r.bbox);
    }
    if by_frame.is_empty() {
        bail!("no detections");
    }
    // Only frames with detections are stepped. A frame number with no row is a frame in
    // which the detector found nothing (a MOTChallenge file has no way to say "no detector
    // ran"): the filter jumps such a gap of k frames in one prediction with the exact k-frame
    // transition and weights p_Sᵏ (1 − p_D)ᵏ⁻¹ (`SmcPhd::step_after`), and the labeller
    // coasts through it in closed form (`coast_through_gap`). The cost is bounded by the
    // detection frames, not by the span of frame numbers.
    let mut live: Vec<PhdTrack> = Vec::new();
    let mut done: Vec<PhdTrack> = Vec::new();
    let mut next_id = 1u64;
    let mut previous: Option<Frame> = None;
    let mut step_frame = |frame: Frame,
                          frames: u64,
                          boxes: &[BoundingBox],
                          phd: &mut SmcPhd,
                          live: &mut Vec<PhdTrack>,
                          done: &mut Vec<PhdTrack>|
     -> Result<()> {
        let step = phd.step_after(frames, boxes)?;
        let mass = label_masses(phd);
        let mut updated = vec![false; live.len()];
        let mut unmatched = Vec::new();
        for e in &step.estimates {
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
                .filter(|&(_, iou)| iou >= labels.min_iou)
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
        let mut kept = Vec::with_capacity(live.len());
        for (mut t, up) in live.drain(..).zip(updated) {
            if t.id.is_none() {
                if t.hits >= labels.confirm_hits {
                    t.id = Some(next_id);
                    next_id += 1;
                } else if frame - t.first + 1 >= labels.confirm_window {
                    continue;
                }
            }
            if up {
                kept.push(t);
                continue;
            }
            t.misses += 1;
            let label_mass = mass.get(&t.phd_label);
            // A missed target's PHD mass shrinks by p_S (1 − p_D) per frame; the label keeps
            // its track while it holds at least `min_mass` of that.
            let expected = (config.p_survive * (1.0 - config.p_detect)).powi(t.misses as i32);
            // Resampling gives a label about particles_per_target × its mass particles, so a
            // label missed for a few frames can lose them all: then the track coasts on its
            // own constant-velocity prediction, still at most `max_misses` frames.
            let alive = t.id.is_some()
                && t.misses <= labels.max_misses
                && label_mass.is_none_or(|m| m.0 >= labels.min_mass * expected);
            if !alive {
                if t.id.is_some() {
                    done.push(t);
                }
                continue;
            }
            // The prediction: the label's particles' mean centre, the track's last size.
            let bbox = match label_mass {
                Some(&(m, x)) if m > 0.0 => BoundingBox::from_centre(
                    Vec2::new(x[0] / m, x[1] / m),
                    t.last_box.width,
                    t.last_box.height,
                )?,
                _ => predicted(&t, frame),
            };
            t.points.push(TrackPoint::boxed(frame, bbox));
            t.coasted += 1;
            kept.push(t);
        }
        *live = kept;
        Ok(())
    };
    for (&frame, boxes) in &by_frame {
        let frames = match previous {
            Some(prev) => {
                let frames = u64::from(frame) - u64::from(prev);
                if frames > 1 {
                    coast_through_gap(prev, frames - 1, &phd, &mut live, &mut done, settings)?;
                }
                frames
            }
            None => 1,
        };
        step_frame(frame, frames, boxes, &mut phd, &mut live, &mut done)?;
        previous = Some(frame);
    }
    done.extend(live.into_iter().filter(|t| t.id.is_some()));
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

/// Mass and weighted mean state of every PHD label's particles.
fn label_masses(phd: &SmcPhd) -> std::collections::HashMap<u64, (f64, [f64; 6])> {
    let mut mass: std::collections::HashMap<u64, (f64, [f64; 6])> = Default::default();
    for p in phd.particles() {
        let e = mass.entry(p.label).or_insert((0.0, [0.0; 6]));
        e.0 += p.w;
        for k in 0..6 {
            e.1[k] += p.w * p.x[k];
        }
    }
    mass
}

/// The labeller through the `gap` frames after `prev` that hold no detection, in closed form
/// and in one pass over the live tracks, while the filter jumps them in one prediction.
/// Stepping each empty frame would give no estimate, so:
/// - a tentative track ends at the gap's first frame (it missed a frame before confirmation);
/// - a confirmed track keeps its id through the gap iff it would at every frame of it: at most
///   `max_misses` misses in all, and its label's mass at `prev`, m, at least `min_mass`
///   (p_S (1 − p_D))^misses (through the gap the label's mass and the bound shrink by the same
///   p_S (1 − p_D) per frame, so the check at each frame is this one). It is output at each
///   frame prev + j from its label's mean state moved j frames by the motion model, F(j) x̄
///   (the mean of what stepping would give; or its own constant-velocity prediction when the
///   label has no particle left), with its last size;
/// - a track that ends in the gap keeps no coasted frame (they would be dropped at its end).
///
/// At most `max_misses` (≤ 10 000) boxes per track per gap, whatever the gap's length.
fn coast_through_gap(
    prev: Frame,
    gap: u64,
    phd: &SmcPhd,
    live: &mut Vec<PhdTrack>,
    done: &mut Vec<PhdTrack>,
    settings: &EffectiveConfig,
) -> Result<()> {
    let (config, labels) = (settings.phd, settings.phd_labels);
    let per_frame = config.p_survive * (1.0 - config.p_detect);
    let mass = label_masses(phd);
    let mut kept = Vec::with_capacity(live.len());
    for mut t in live.drain(..) {
        if t.id.is_none() {
            continue;
        }
        let label = mass.get(&t.phd_label);
        let holds = label.is_none_or(|m| {
            // misses ≤ max_misses ≤ 10 000 fits an i32.
            m.0 >= labels.min_mass * per_frame.powi(t.misses as i32)
        });
        if u64::from(t.misses) + gap > u64::from(labels.max_misses) || !holds {
            done.push(t);
            continue;
        }
        for j in 1..=gap {
            // j ≤ gap = frame − prev − 1 ≤ max_misses, so prev + j fits a Frame.
            let frame = prev + j as Frame;
            let bbox = match label {
                Some(&(m, x)) if m > 0.0 => {
                    let c = config.motion.predict_mean(&x.map(|v| v / m), j);
                    BoundingBox::from_centre(
                        Vec2::new(c[0], c[1]),
                        t.last_box.width,
                        t.last_box.height,
                    )?
                }
                _ => predicted(&t, frame),
            };
            t.points.push(TrackPoint::boxed(frame, bbox));
        }
        t.coasted += gap as usize;
        t.misses += gap as u32;
        kept.push(t);
    }
    *live = kept;
    Ok(())
}

/// The most frames a PHD track may coast (`[phd_labels] max_misses`): a gap in the frame
/// numbers costs at most this many boxes per live track.
pub(super) const MAX_COAST_FRAMES: u32 = 10_000;

impl PhdLabelConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        if !(0.0..=1.0).contains(&self.min_iou) {
            bail!("min_iou = {} must be in [0, 1]", self.min_iou);
        }
        if !(self.min_mass.is_finite() && self.min_mass >= 0.0) {
            bail!("min_mass = {} must be finite and ≥ 0", self.min_mass);
        }
        if self.max_misses > MAX_COAST_FRAMES {
            bail!(
                "max_misses = {} is over {MAX_COAST_FRAMES}: a track coasts at most that many \
                 frames, so that a gap in the frame numbers costs a bounded number of boxes",
                self.max_misses
            );
        }
        Ok(())
    }
}
