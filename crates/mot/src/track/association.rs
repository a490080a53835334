//! MCMCDA (offline, online) and GNN on box centres, and the offline tracklet linking.

use super::*;

/// MCMCDA (offline or online) or GNN on the box centres; boxes from [`smooth_boxes`].
pub(super) fn track_points(
    tracker: TrackerKind,
    rows: &[MotRow],
    settings: &EffectiveConfig,
    seed: u64,
) -> Result<TrackSet> {
    let model = settings.model.check()?;
    let scores = settings.score_model.as_ref();
    let (detections, associations): (_, Vec<Vec<MeasId>>) = match tracker {
        // The online tracker builds its own problem, scan by scan.
        TrackerKind::McmcdaOnline => {
            return track_online(&model, &detections_by_frame(rows).1, settings, seed);
        }
        TrackerKind::Mcmcda => {
            let (detections, _, problem) = problem_of(&model, rows, scores, Problem::empty)?;
            // The chain starts from GNN's tracks (feasible in Ω by construction), so the MAP
            // is at least as probable as GNN's answer under the fitted model.
            let window = problem.all_scans()?;
            let start = nearest_neighbour_tracks(&model, &problem, window.clone(), &settings.gnn)?;
            let start = Partition::from_tracks(&model, &problem, window, &start)?;
            let map = run_chains(
                &start,
                settings.offline.chains,
                settings.offline.samples_for(detections.len())?,
                seed,
            )?;
            let max_gap = (settings.offline.link_gap_factor * f64::from(model.config().max_gap))
                .round() as u32;
            let linked = link_tracklets(map.tracks, &detections, model.config(), max_gap);
            (detections, linked)
        }
        // The fit's GNN pass; the PHD and box trackers never come here otherwise.
        TrackerKind::Gnn
        | TrackerKind::Phd
        | TrackerKind::Sort
        | TrackerKind::ByteTrack
        | TrackerKind::OcSort => {
            let (detections, _, problem) =
                problem_of(&model, rows, scores, Problem::without_neighbourhoods)?;
            let window = problem.all_scans()?;
            let tracks = nearest_neighbour_tracks(&model, &problem, window, &settings.gnn)?;
            (detections, tracks)
        }
        TrackerKind::GnnOnline => {
            let (detections, by_frame, problem) =
                problem_of(&model, rows, scores, Problem::without_neighbourhoods)?;
            let window = problem.all_scans()?;
            let tracks = nearest_neighbour_tracks(&model, &problem, window, &settings.gnn)?;
            let last = by_frame.keys().next_back().copied().unwrap_or(0);
            let coast = settings
                .gnn
                .max_gap
                .unwrap_or(model.config().max_gap)
                .min(settings.boxes.online_coast_frames);
            return gnn_online_output(&detections, &tracks, &settings.boxes, coast, last);
        }
    };
    let mut tracks = Vec::with_capacity(associations.len());
    for (i, meas) in associations.iter().enumerate() {
        let dets = detection_boxes(&detections, meas);
        let points = smooth_boxes(&dets, &settings.boxes, None)?;
        if !points.is_empty() {
            tracks.push(Track::from_points(TrackId(i as u64 + 1), points)?);
        }
    }
    Ok(TrackSet::from_tracks(tracks)?)
}

/// Min-cost tracklet linking after offline MCMCDA (the hierarchical association of Huang,
/// Wu & Nevatia 2008, ECCV, with its motion affinity alone): a track A that ends at frame ℓ
/// may be continued by a track B that starts at s, ℓ < s ≤ ℓ + `max_gap`, when each end's
/// constant-velocity prediction over the gap g = s − ℓ reaches the other's end: with A's
/// last centre c_A and velocity v_A (least squares over its last 8 detections) and B's first
/// c_B, v_B, the squared Mahalanobis distances of c_A + g v_A − c_B and c_B − g v_B − c_A
/// under the fitted model's spread over the gap (per axis 2R + q g³/3) must both pass the
/// 99 % χ² gate, and the heights must agree within 30 %. A one-to-one assignment of ends to
/// starts minimises the sum of the two distances. This bridges occlusions longer than the
/// posterior's d̄ (whose (1 − p_d)^g term treats the misses of an occlusion as independent).
fn link_tracklets(
    tracks: Vec<Vec<MeasId>>,
    detections: &Detections,
    model: &McmcdaConfig,
    max_gap: u32,
) -> Vec<Vec<MeasId>> {
    if max_gap == 0 || tracks.len() < 2 {
        return tracks;
    }
    let ends: Vec<_> = tracks
        .iter()
        .map(|t| end_state(t, detections, true))
        .collect();
    let starts: Vec<_> = tracks
        .iter()
        .map(|t| end_state(t, detections, false))
        .collect();
    let pairs = link_candidates(&ends, &starts, model, max_gap);
    if pairs.is_empty() {
        return tracks;
    }
    let Some(next) = chosen_links(tracks.len(), &pairs) else {
        return tracks;
    };
    let n = tracks.len();
    let mut has_prev = vec![false; n];
    for b in next.iter().flatten() {
        has_prev[*b] = true;
    }
    let mut out = Vec::with_capacity(n);
    for start in (0..n).filter(|&i| !has_prev[i]) {
        let mut chain = Vec::new();
        let mut at = Some(start);
        // Links go forward in time, so a chain cannot cycle; n bounds it anyway.
        for _ in 0..n {
            let Some(i) = at else { break };
            chain.extend_from_slice(&tracks[i]);
            at = next[i];
        }
        out.push(chain);
    }
    out
}

/// The 99 % χ² gate (2 degrees of freedom) of a link's two prediction distances.
const LINK_GATE: f64 = 9.21;

/// One end of a track for linking: its frame, the centre and velocity of a line fitted to its
/// first or last 8 detections (the centre at the end frame), and the box height there.
type TrackEnd = (Frame, Vec2, Vec2, f64);

/// The start (`at_end` false) or end of the track `meas`.
fn end_state(meas: &[MeasId], detections: &Detections, at_end: bool) -> TrackEnd {
    let k = meas.len().min(8);
    let part = if at_end {
        &meas[meas.len() - k..]
    } else {
        &meas[..k]
    };
    let pts: Vec<(f64, Vec2)> = part
        .iter()
        .map(|&m| {
            let d = detections.of(m);
            (f64::from(d.frame), d.bbox.centre())
        })
        .collect();
    let n = pts.len() as f64;
    let tm = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let cm = pts.iter().fold(Vec2::zeros(), |a, p| a + p.1) / n;
    let stt = pts.iter().map(|p| (p.0 - tm).powi(2)).sum::<f64>();
    let v = if stt > 0.0 {
        pts.iter()
            .fold(Vec2::zeros(), |a, p| a + (p.1 - cm) * (p.0 - tm))
            / stt
    } else {
        Vec2::zeros()
    };
    let m = if at_end {
        meas[meas.len() - 1]
    } else {
        meas[0]
    };
    let d = detections.of(m);
    // The fitted line's value at the end frame.
    let c = cm + v * (f64::from(d.frame) - tm);
    (d.frame, c, v, d.bbox.height)
}

/// Every (end a, start b, cost) whose gap is at most `max_gap`, whose heights agree within
/// 30 % and whose two predictions over the gap both pass [`LINK_GATE`]; the cost is the sum
/// of the two squared Mahalanobis distances.
fn link_candidates(
    ends: &[TrackEnd],
    starts: &[TrackEnd],
    model: &McmcdaConfig,
    max_gap: u32,
) -> Vec<(usize, usize, f64)> {
    let r = [
        model.measurement_noise[(0, 0)],
        model.measurement_noise[(1, 1)],
    ];
    let q = match model.motion.noise() {
        tracker_model::CvNoise::Discrete {
            acceleration_covariance,
        } => acceleration_covariance[(0, 0)],
        tracker_model::CvNoise::WhiteAcceleration { q } => q,
    };
    let mut pairs = Vec::new();
    for (a, &(la, ca, va, ha)) in ends.iter().enumerate() {
        for (b, &(sb, cb, vb, hb)) in starts.iter().enumerate() {
            if a == b || sb <= la || sb - la > max_gap || (hb / ha).ln().abs() > 0.3_f64.ln_1p() {
                continue;
            }
            let g = f64::from(sb - la);
            let var = [0, 1].map(|k| 2.0 * r[k] + q * g.powi(3) / 3.0);
            let d2 = |e: Vec2| e.x * e.x / var[0] + e.y * e.y / var[1];
            let (df, db) = (d2(ca + va * g - cb), d2(cb - vb * g - ca));
            if df <= LINK_GATE && db <= LINK_GATE {
                pairs.push((a, b, df + db));
            }
        }
    }
    pairs
}

/// The one-to-one assignment of the `n` tracks' ends to starts at least total cost, each end
/// free to stay unlinked at twice the gate's cost: the start that follows each end, if any.
/// `None` if the solver fails.
fn chosen_links(n: usize, pairs: &[(usize, usize, f64)]) -> Option<Vec<Option<usize>>> {
    // Rows: ends; columns: starts, then one "no link" column per end at the gate's cost.
    let n_cols = 2 * n;
    let forbidden = 1e6;
    let mut costs = vec![forbidden; n * n_cols];
    for &(a, b, c) in pairs {
        costs[a * n_cols + b] = c;
    }
    for a in 0..n {
        costs[a * n_cols + n + a] = 2.0 * LINK_GATE;
    }
    let chosen = tracker_model::assignment::minimise(n, n_cols, &costs).ok()?;
    let mut next: Vec<Option<usize>> = vec![None; n];
    for (a, b) in chosen {
        if b < n && costs[a * n_cols + b] < forbidden {
            next[a] = Some(b);
        }
    }
    Some(next)
}

/// GNN's tracks output as a frame-by-frame tracker would have output them. GNN's
/// associations are causal (scan by scan), so at every frame f from a track's first detection
/// on the output is what was known at f: with a detection at f, the box fitted to the track's
/// detections up to f ([`smooth_boxes`] with `until`); without one, the box fitted at its last
/// detection ℓ moved on at the velocity of the fitted boxes between its last two detections,
/// for at most `coast` frames after ℓ (`[boxes] online_coast_frames`, at most GNN's deletion
/// gap, after which GNN deletes the track) and not beyond the
/// file's last frame `end`. The first box of a track is its first detection (a track holds its
/// initiating detections, as the peer's trackers do): causal up to confirmation, since whether
/// a track is output at all is decided by its M-of-N confirmation, which may come after f.
fn gnn_online_output(
    detections: &Detections,
    tracks: &[Vec<MeasId>],
    boxes: &BoxConfig,
    coast: u32,
    end: Frame,
) -> Result<TrackSet> {
    let mut out = Vec::with_capacity(tracks.len());
    for (i, meas) in tracks.iter().enumerate() {
        let dets = detection_boxes(detections, meas);
        // The causal fit at each detection's frame, from the detections within the kernel's
        // reach before it (all the fit reads: the track's detection at f is the slice's last),
        // so a track costs O(length · reach), not O(length²).
        let reach = kernel_reach(boxes.smoothing_frames);
        let mut fitted: Vec<(Frame, BoundingBox)> = Vec::with_capacity(dets.len());
        let mut start = 0;
        for (k, &(f, _)) in dets.iter().enumerate() {
            while i64::from(dets[start].0) < i64::from(f).saturating_sub(reach) {
                start += 1;
            }
            if let Some(tracker_model::Location::Box(b)) =
                smooth_boxes(&dets[start..=k], boxes, Some(f))?
                    .last()
                    .map(|p| p.location)
            {
                fitted.push((f, b));
            }
        }
        let mut points = Vec::new();
        for (k, &(f, b)) in fitted.iter().enumerate() {
            points.push(TrackPoint::boxed(f, b));
            let velocity = match k.checked_sub(1).map(|j| fitted[j]) {
                Some((g, a)) => (b.centre() - a.centre()) / f64::from(f - g),
                None => Vec2::zeros(),
            };
            let next = fitted.get(k + 1).map_or(Frame::MAX, |n| n.0);
            let until = u64::from(f) + u64::from(coast);
            let stop = until
                .min(u64::from(end))
                .min(u64::from(next).saturating_sub(1));
            for g in u64::from(f) + 1..=stop {
                let dt = (g - u64::from(f)) as f64;
                let c = b.centre() + velocity * dt;
                // g ≤ end, a Frame.
                let frame = crate::error::frame_of(g)?;
                points.push(TrackPoint::boxed(
                    frame,
                    BoundingBox::from_centre(c, b.width, b.height)?,
                ));
            }
        }
        if !points.is_empty() {
            out.push(Track::from_points(TrackId(i as u64 + 1), points)?);
        }
    }
    Ok(TrackSet::from_tracks(out)?)
}

/// Online MCMCDA, output frame by frame: after each frame, every track the window's MAP
/// reports at that frame (its last detection at most `coast_scans` frames old) gets a box fitted
/// to its detections up to that frame only; a coasting track keeps the size of that fit and
/// moves with the tracker's prediction.
fn track_online(
    model: &mcmcda::Model,
    by_frame: &std::collections::BTreeMap<Frame, Vec<MotRow>>,
    settings: &EffectiveConfig,
    seed: u64,
) -> Result<TrackSet> {
    let first = by_frame.keys().next().copied().unwrap_or(0);
    let mut online = OnlineTracker::new(model.clone(), first, settings.online, seed)?;
    let mut detections = Detections::new();
    let mut out: std::collections::BTreeMap<u64, Vec<TrackPoint>> = Default::default();
    // The frames run on a thread of rayon's pool, so that the window's chains (`[online]
    // chains`) fork from inside it rather than wait for the pool to wake up at every frame
    // (like the PHD tracker's frames, track/phd.rs). No result depends on the threads.
    rayon::scope(|_| -> Result<()> {
        for (&frame, dets) in by_frame {
            detections.extend(dets);
            let step = online.push_scan_scored(
                frame,
                &centres(dets),
                &score_ratios(settings.score_model.as_ref(), dets),
            )?;
            let map: std::collections::HashMap<u64, &Vec<MeasId>> =
                online.map_tracks().iter().map(|(l, t)| (*l, t)).collect();
            for (label, position) in &step.estimates {
                let Some(meas) = map.get(label) else {
                    continue;
                };
                let dets: Vec<(Frame, BoundingBox)> = meas
                    .iter()
                    .map(|&m| {
                        let d = detections.of(m);
                        (d.frame, d.bbox)
                    })
                    .collect();
                let Some(&(last_frame, _)) = dets.last() else {
                    continue;
                };
                let fitted = smooth_boxes(&dets, &settings.boxes, Some(last_frame))?;
                let Some(tracker_model::Location::Box(at_last)) = fitted.last().map(|p| p.location)
                else {
                    continue;
                };
                let bbox = if last_frame == frame {
                    at_last
                } else {
                    BoundingBox::from_centre(*position, at_last.width, at_last.height)?
                };
                out.entry(*label)
                    .or_default()
                    .push(TrackPoint::boxed(frame, bbox));
            }
        }
        Ok(())
    })?;
    let tracks = out
        .into_iter()
        .map(|(label, points)| Track::from_points(TrackId(label + 1), points))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    Ok(TrackSet::from_tracks(tracks)?)
}
