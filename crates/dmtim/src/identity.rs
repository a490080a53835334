//! Phase two: the identity layer. Each sensor keeps a [`BeliefMatrix`] over the identities it
//! knows × its tracks and replays its tracker's records frame by frame: mixing after
//! interactions, hand-overs of tracks that leave its range, new tracks (adopted from a
//! hand-over or a neighbour's track, announced as a new target, or unknown), local
//! information, and the query-based exchange with neighbours (belief columns and track
//! estimates only; tracks of one target matched by optimal assignment under a Mahalanobis
//! gate; beliefs fused by the configured criterion).

use std::collections::BTreeMap;

use identity_mgmt::{BeliefMatrix, EntropyUnit, IdentityId};
use tracker_model::{TrackId, Vec2, assignment};

use crate::config::{DmtimConfig, IdentityMode, ReadUpdate};
use crate::error::{Error, Result};
use crate::scene::{Observations, TruthTarget};
use crate::tracking::SensorFrame;

/// Bytes of one number on the wire (an f64 or a u64 id).
pub const BYTES_PER_NUMBER: u64 = 8;
/// Bytes of one raw measurement (x, y, frame).
pub const BYTES_PER_MEASUREMENT: u64 = 3 * BYTES_PER_NUMBER;

/// What happened, for the event log.
#[derive(Debug, Clone, PartialEq)]
pub enum EventKind {
    /// A new target's identity, announced when it first appeared.
    NewTarget {
        /// The identity.
        identity: IdentityId,
    },
    /// A new track took the belief of a track handed over by `from`.
    HandOverReceived {
        /// The sending sensor.
        from: usize,
    },
    /// A track leaving the range was sent to these sensors.
    HandOverSent {
        /// The receivers.
        to: Vec<usize>,
    },
    /// A new track took the belief of a neighbour's track of the same target.
    Adopted {
        /// The neighbour.
        from: usize,
    },
    /// A new track of no known origin: uniform over the known identities.
    Unknown,
    /// Identities of these tracks mixed after an interaction.
    Mixed {
        /// The tracks' labels.
        labels: Vec<u64>,
        /// Whether the uniform matrix was used (a piece had left the window).
        uniform: bool,
    },
    /// Local information about a track.
    LocalInformation {
        /// The identity read.
        identity: IdentityId,
        /// Whether the read was right.
        correct: bool,
        /// How it was incorporated.
        rule: ReadRule,
        /// H(B) before, nats.
        entropy_before_nats: f64,
        /// H(B) after, nats.
        entropy_after_nats: f64,
    },
    /// An update that identity-mgmt refused (contradicting or disjoint beliefs); the matrix
    /// is unchanged.
    Refused {
        /// What was refused and why.
        what: String,
    },
}

/// How a read was incorporated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReadRule {
    /// Replace the column and Sinkhorn-rescale with the row masses kept (Balakrishnan, Hwang
    /// & Tomlin 2004).
    Scaled,
    /// The read contradicted a (near-)certain belief, so the matrix was not scalable with
    /// it: first "doubt" (mix every track of the sensor with M = (1 − ε)I + ε/n·J, which
    /// keeps the row masses and spreads each column's support), then rescale.
    AfterDoubt,
    /// The sensor held too little of the read identity's mass for the read to fit: the
    /// column is set to the read (the mass is imported) without rescaling.
    MassImported,
}

/// One event of the log.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    /// Frame.
    pub frame: u64,
    /// Sensor.
    pub sensor: usize,
    /// The track concerned (its label at that sensor), if one.
    pub track: Option<u64>,
    /// What.
    pub kind: EventKind,
}

/// A belief matrix just before and just after some local information.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// Frame.
    pub frame: u64,
    /// Sensor.
    pub sensor: usize,
    /// Before.
    pub before: BeliefMatrix,
    /// After.
    pub after: BeliefMatrix,
}

/// The identity layer's output.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentityRun {
    /// Σ over sensors of H(B_s), nats, per frame.
    pub entropy_nats: Vec<f64>,
    /// Per frame: (tracks whose argmax identity is their target's, tracks scored). A track
    /// is scored if a true target is within the scoring distance of its estimate.
    pub correct: Vec<(usize, usize)>,
    /// The event log.
    pub events: Vec<Event>,
    /// Bytes exchanged between sensors (query replies, hand-overs).
    pub bytes_exchanged: u64,
    /// Bytes the same exchanges would cost with raw measurements instead.
    pub bytes_raw: u64,
    /// The first local information at a matrix with at least two tracks and positive entropy.
    pub snapshot: Option<Snapshot>,
    /// Every sensor's matrix at the end.
    pub final_beliefs: Vec<BeliefMatrix>,
}

impl IdentityRun {
    /// Fraction correct per frame (NaN-free: frames with nothing scored give `None`).
    pub fn correct_fraction(&self) -> Vec<Option<f64>> {
        self.correct
            .iter()
            .map(|&(c, n)| (n > 0).then(|| c as f64 / n as f64))
            .collect()
    }

    /// Correct over scored, pooled over all frames.
    pub fn pooled_correct_fraction(&self) -> f64 {
        let (c, n) = self
            .correct
            .iter()
            .fold((0, 0), |(a, b), &(c, n)| (a + c, b + n));
        if n == 0 { 0.0 } else { c as f64 / n as f64 }
    }
}

struct Pending {
    from: usize,
    position: Vec2,
    velocity: Vec2,
    age: u64,
    identities: Vec<IdentityId>,
    column: Vec<f64>,
}

struct Node {
    beliefs: BeliefMatrix,
    /// label → (position, velocity) in the previous frame.
    last: BTreeMap<u64, (Vec2, Vec2)>,
    pending: Vec<Pending>,
}

/// A column over `from_ids` re-expressed over `to_ids` (which must contain every identity
/// with positive mass).
fn align(column: &[f64], from_ids: &[IdentityId], to_ids: &[IdentityId]) -> Vec<f64> {
    let mut out = vec![0.0; to_ids.len()];
    for (id, p) in from_ids.iter().zip(column) {
        if let Some(k) = to_ids.iter().position(|x| x == id) {
            out[k] = *p;
        }
    }
    out
}

/// Incorporates a read of `identity` about `track` (information `info` over the matrix's
/// identities): see [`ReadRule`]. Returns the rule used and H(B) before and after, nats.
fn apply_read(
    beliefs: &mut BeliefMatrix,
    track: TrackId,
    info: &[f64],
    identity: IdentityId,
    config: &DmtimConfig,
) -> std::result::Result<(ReadRule, f64, f64), identity_mgmt::Error> {
    let h_before = beliefs.entropy(EntropyUnit::Nats);
    let took = |beliefs: &mut BeliefMatrix| {
        let mut trial = beliefs.clone();
        match trial.incorporate_local_information(track, info, &config.scaling) {
            Ok(r) if !r.softened && !r.forced_zero.contains(&(identity, track)) => {
                *beliefs = trial;
                true
            }
            _ => false,
        }
    };
    if took(beliefs) {
        return Ok((
            ReadRule::Scaled,
            h_before,
            beliefs.entropy(EntropyUnit::Nats),
        ));
    }
    let n = beliefs.n_tracks();
    if n >= 2 {
        let eps = config.read_doubt;
        let mut m = vec![eps / n as f64; n * n];
        for k in 0..n {
            m[k * n + k] += 1.0 - eps;
        }
        let mut trial = beliefs.clone();
        let tracks = trial.tracks().to_vec();
        trial.mix(&tracks, &identity_mgmt::Continuation::new(n, m)?)?;
        if took(&mut trial) {
            *beliefs = trial;
            return Ok((
                ReadRule::AfterDoubt,
                h_before,
                beliefs.entropy(EntropyUnit::Nats),
            ));
        }
    }
    beliefs.remove_track(track)?;
    beliefs.add_track(track, info)?;
    Ok((
        ReadRule::MassImported,
        h_before,
        beliefs.entropy(EntropyUnit::Nats),
    ))
}

/// A query reply: per track a label, a position and the column's non-zero entries as
/// (identity, probability) pairs.
fn reply_bytes(beliefs: &BeliefMatrix, tracks: &[(u64, Vec2)]) -> u64 {
    tracks
        .iter()
        .map(|(l, _)| {
            let nnz = beliefs
                .column(TrackId(*l))
                .map_or(0, |c| c.iter().filter(|p| **p > 0.0).count()) as u64;
            BYTES_PER_NUMBER * (3 + 2 * nnz)
        })
        .sum()
}

/// The raw alternative: every measurement inside the asking sensor's range.
fn raw_bytes(points: &[Vec2], asking: &crate::config::SensorSpec) -> u64 {
    BYTES_PER_MEASUREMENT * points.iter().filter(|p| asking.covers(**p)).count() as u64
}

fn learn(beliefs: &mut BeliefMatrix, ids: &[IdentityId]) {
    for id in ids {
        if !beliefs.identities().contains(id) {
            // Cannot fail: the identity is new.
            let _ = beliefs.add_identity(*id);
        }
    }
}

/// Runs the identity layer over the trackers' records. `truth` is used for two things
/// only: announcing a target's identity when it first appears (the papers' premise:
/// identities are assigned when a target first appears) and scoring.
#[expect(
    clippy::needless_range_loop,
    reason = "a frame indexes every radar's records and observations at once"
)]
pub fn manage_identities(
    records: &[Vec<SensorFrame>],
    observations: &Observations,
    truth: &[TruthTarget],
    config: &DmtimConfig,
) -> Result<IdentityRun> {
    config.check()?;
    let n_sensors = records.len();
    let sensors = &config.sensors;
    if sensors.len() != n_sensors || observations.scans.len() != n_sensors {
        return Err(Error::InvalidParameter {
            name: "records",
            reason: format!(
                "{n_sensors} sensors' records, {} sensors configured, {} observed",
                sensors.len(),
                observations.scans.len()
            ),
        });
    }
    let neighbours: Vec<Vec<usize>> = (0..n_sensors)
        .map(|s| {
            (0..n_sensors)
                .filter(|&n| n != s && sensors[s].overlaps(&sensors[n]))
                .collect()
        })
        .collect();
    let var = config.sensing.noise_std_m.powi(2);
    // Mahalanobis distance² of two position estimates with covariance k·σ² I.
    let d2 = |a: Vec2, b: Vec2, k: f64| (a - b).norm_squared() / (k * var);
    let gate = config.merge_gate_chi2;
    let mut nodes: Vec<Node> = (0..n_sensors)
        .map(|_| Node {
            beliefs: BeliefMatrix::new(),
            last: BTreeMap::new(),
            pending: Vec::new(),
        })
        .collect();
    let mut announced: Vec<IdentityId> = Vec::new();
    let mut run = IdentityRun {
        entropy_nats: Vec::new(),
        correct: Vec::new(),
        events: Vec::new(),
        bytes_exchanged: 0,
        bytes_raw: 0,
        snapshot: None,
        final_beliefs: Vec::new(),
    };
    let n_frames = records.iter().map(Vec::len).min().unwrap_or(0);
    for frame in 0..n_frames {
        let fr = frame as u64;
        let id_err = |sensor: usize| move |source| Error::Identity { sensor, source };
        // 1. Mixing, carrying columns to this frame's labels, hand-overs of ended tracks
        //    (delivered after every sensor has sent).
        let mut outbox: Vec<(usize, Pending)> = Vec::new();
        for s in 0..n_sensors {
            let rec = &records[s][frame];
            let node = &mut nodes[s];
            if config.identity_mode == IdentityMode::Beliefs {
                for m in &rec.mixings {
                    let tracks: Vec<TrackId> = m.labels.iter().map(|&l| TrackId(l)).collect();
                    if tracks.iter().all(|t| node.beliefs.tracks().contains(t)) {
                        node.beliefs
                            .mix(&tracks, &m.continuation)
                            .map_err(id_err(s))?;
                        run.events.push(Event {
                            frame: fr,
                            sensor: s,
                            track: None,
                            kind: EventKind::Mixed {
                                labels: m.labels.clone(),
                                uniform: m.uniform_fallback,
                            },
                        });
                    }
                }
            }
            let old: Vec<u64> = node.beliefs.tracks().iter().map(|t| t.0).collect();
            let now: Vec<u64> = rec.estimates.iter().map(|(l, _)| *l).collect();
            // carry: old label → new label.
            let carry: Vec<(u64, u64)> = match config.identity_mode {
                IdentityMode::Beliefs => old
                    .iter()
                    .filter(|l| now.contains(l))
                    .map(|&l| (l, l))
                    .collect(),
                IdentityMode::NearestTrack => {
                    let (r, c) = (old.len(), now.len());
                    let mut cost = vec![0.0; r * c];
                    for (i, l) in old.iter().enumerate() {
                        for (j, (_, p)) in rec.estimates.iter().enumerate() {
                            // Every track in the matrix was reported last frame, so it has a position;
                            // a missing one is treated as out of the gate.
                            cost[i * c + j] = node
                                .last
                                .get(l)
                                .map_or(gate * 10.0, |q| d2(q.0, *p, 2.0).min(gate * 10.0));
                        }
                    }
                    assignment::minimise(r, c, &cost)?
                        .into_iter()
                        .filter(|&(i, j)| cost[i * c + j] <= gate)
                        .map(|(i, j)| (old[i], now[j]))
                        .collect()
                }
            };
            let mut columns: BTreeMap<u64, Vec<f64>> = BTreeMap::new();
            for &l in &old {
                columns.insert(l, node.beliefs.remove_track(TrackId(l)).map_err(id_err(s))?);
            }
            for &(a, b) in &carry {
                node.beliefs
                    .add_track(TrackId(b), columns.get(&a).map_or(&[][..], Vec::as_slice))
                    .map_err(id_err(s))?;
            }
            // Ended tracks near the edge are handed over to the neighbours they head for.
            let spec = &sensors[s];
            for &l in old.iter().filter(|l| !carry.iter().any(|(a, _)| a == *l)) {
                let Some(&(p, v)) = node.last.get(&l) else {
                    continue;
                };
                if (p - spec.centre()).norm() < spec.range_m - config.handover_margin_m {
                    continue;
                }
                let to: Vec<usize> = neighbours[s]
                    .iter()
                    .copied()
                    .filter(|&n| sensors[n].covers(p + v) || sensors[n].covers(p))
                    .collect();
                if to.is_empty() {
                    continue;
                }
                let ids = node.beliefs.identities().to_vec();
                // A hand-over message (position, velocity, identities, column) costs the same
                // either way: raw measurements would not carry the belief.
                let message = BYTES_PER_NUMBER * (4 + 2 * ids.len() as u64) * to.len() as u64;
                run.bytes_exchanged += message;
                run.bytes_raw += message;
                let column = columns.get(&l).cloned().unwrap_or_default();
                for &n in &to {
                    let pending = Pending {
                        from: s,
                        position: p,
                        velocity: v,
                        age: 0,
                        identities: ids.clone(),
                        column: column.clone(),
                    };
                    outbox.push((n, pending));
                }
                run.events.push(Event {
                    frame: fr,
                    sensor: s,
                    track: Some(l),
                    kind: EventKind::HandOverSent { to },
                });
            }
        }
        for (n, p) in outbox {
            nodes[n].pending.push(p);
        }
        // 2. New tracks.
        for s in 0..n_sensors {
            let rec = &records[s][frame];
            let new: Vec<(u64, Vec2)> = rec
                .estimates
                .iter()
                .filter(|(l, _)| !nodes[s].beliefs.tracks().contains(&TrackId(*l)))
                .copied()
                .collect();
            for (l, x) in new {
                // a. A pending hand-over, extrapolated.
                let best_pending = nodes[s]
                    .pending
                    .iter()
                    .enumerate()
                    .map(|(k, p)| {
                        let age = p.age as f64 + 1.0;
                        (k, d2(p.position + p.velocity * age, x, 2.0 + age))
                    })
                    .filter(|(_, d)| *d <= gate)
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                if let Some((k, _)) = best_pending {
                    let p = nodes[s].pending.remove(k);
                    let node = &mut nodes[s];
                    learn(&mut node.beliefs, &p.identities);
                    let col = align(&p.column, &p.identities, node.beliefs.identities());
                    node.beliefs
                        .add_track(TrackId(l), &col)
                        .map_err(id_err(s))?;
                    run.events.push(Event {
                        frame: fr,
                        sensor: s,
                        track: Some(l),
                        kind: EventKind::HandOverReceived { from: p.from },
                    });
                    continue;
                }
                // b. A neighbour's track of the same target (a query: its tracks and columns).
                let mut best: Option<(usize, u64, f64)> = None;
                for &n in &neighbours[s] {
                    let theirs: Vec<(u64, Vec2)> = records[n][frame]
                        .estimates
                        .iter()
                        .filter(|(m, p)| {
                            nodes[n].beliefs.tracks().contains(&TrackId(*m))
                                && sensors[s].covers(*p)
                        })
                        .copied()
                        .collect();
                    run.bytes_exchanged += reply_bytes(&nodes[n].beliefs, &theirs);
                    run.bytes_raw += raw_bytes(&observations.scans[n][frame].points, &sensors[s]);
                    for (m, y) in &theirs {
                        let d = d2(*y, x, 2.0);
                        if d <= gate && best.is_none_or(|b| d < b.2) {
                            best = Some((n, *m, d));
                        }
                    }
                }
                if let Some((n, m, _)) = best {
                    let ids = nodes[n].beliefs.identities().to_vec();
                    let col = nodes[n].beliefs.column(TrackId(m)).map_err(id_err(n))?;
                    let node = &mut nodes[s];
                    learn(&mut node.beliefs, &ids);
                    let col = align(&col, &ids, node.beliefs.identities());
                    node.beliefs
                        .add_track(TrackId(l), &col)
                        .map_err(id_err(s))?;
                    run.events.push(Event {
                        frame: fr,
                        sensor: s,
                        track: Some(l),
                        kind: EventKind::Adopted { from: n },
                    });
                    continue;
                }
                // c. A target appearing for the first time: its identity is announced.
                let first = rec
                    .estimates
                    .iter()
                    .position(|(m, _)| *m == l)
                    .and_then(|k| rec.origins[k])
                    .and_then(|t| truth.get(t))
                    .map(|t| (t.identity, ()));
                let node = &mut nodes[s];
                if let Some((id, _)) = first
                    && !announced.contains(&id)
                {
                    announced.push(id);
                    learn(&mut node.beliefs, &[id]);
                    let col = align(&[1.0], &[id], node.beliefs.identities());
                    node.beliefs
                        .add_track(TrackId(l), &col)
                        .map_err(id_err(s))?;
                    run.events.push(Event {
                        frame: fr,
                        sensor: s,
                        track: Some(l),
                        kind: EventKind::NewTarget { identity: id },
                    });
                    continue;
                }
                // d. Unknown: uniform over the announced identities.
                if announced.is_empty() {
                    continue;
                }
                learn(&mut node.beliefs, &announced);
                let u = vec![1.0 / announced.len() as f64; announced.len()];
                let col = align(&u, &announced, node.beliefs.identities());
                node.beliefs
                    .add_track(TrackId(l), &col)
                    .map_err(id_err(s))?;
                run.events.push(Event {
                    frame: fr,
                    sensor: s,
                    track: Some(l),
                    kind: EventKind::Unknown,
                });
            }
            for p in &mut nodes[s].pending {
                p.age += 1;
            }
            let ttl = config.handover_ttl_frames;
            nodes[s].pending.retain(|p| p.age <= ttl);
        }
        // 3. Local information.
        for s in 0..n_sensors {
            let rec = &records[s][frame];
            for (read, track) in observations.scans[s][frame]
                .reads
                .iter()
                .zip(&rec.read_tracks)
            {
                let Some(l) = *track else { continue };
                if !nodes[s].beliefs.tracks().contains(&TrackId(l)) {
                    continue;
                }
                let node = &mut nodes[s];
                learn(&mut node.beliefs, &[read.identity]);
                let ids = node.beliefs.identities().to_vec();
                let e = config.local_info.error_rate;
                // The read's likelihood over the identities: 1 − e for the one read, e/(n − 1)
                // for each other.
                let likelihood: Vec<f64> = if ids.len() == 1 {
                    vec![1.0]
                } else {
                    ids.iter()
                        .map(|id| {
                            if *id == read.identity {
                                1.0 - e
                            } else {
                                e / (ids.len() - 1) as f64
                            }
                        })
                        .collect()
                };
                let info = match config.read_update {
                    ReadUpdate::Replace => likelihood,
                    ReadUpdate::Posterior => {
                        let prior = node.beliefs.column(TrackId(l)).map_err(id_err(s))?;
                        let post: Vec<f64> =
                            prior.iter().zip(&likelihood).map(|(p, q)| p * q).collect();
                        let z: f64 = post.iter().sum();
                        if z > 0.0 {
                            post.iter().map(|p| p / z).collect()
                        } else {
                            likelihood
                        }
                    }
                };
                let before = node.beliefs.clone();
                match apply_read(&mut node.beliefs, TrackId(l), &info, read.identity, config) {
                    Ok((rule, h_before, h_after)) => {
                        if run.snapshot.is_none() && before.n_tracks() >= 2 && h_before > 1e-6 {
                            run.snapshot = Some(Snapshot {
                                frame: fr,
                                sensor: s,
                                before,
                                after: node.beliefs.clone(),
                            });
                        }
                        run.events.push(Event {
                            frame: fr,
                            sensor: s,
                            track: Some(l),
                            kind: EventKind::LocalInformation {
                                identity: read.identity,
                                correct: read.correct,
                                rule,
                                entropy_before_nats: h_before,
                                entropy_after_nats: h_after,
                            },
                        });
                    }
                    Err(e) => run.events.push(Event {
                        frame: fr,
                        sensor: s,
                        track: Some(l),
                        kind: EventKind::Refused {
                            what: format!("local information {}: {e}", read.identity),
                        },
                    }),
                }
            }
        }
        // 4. Exchange with neighbours: each sensor queries its neighbours' tracks and
        //    columns (a snapshot, so the order of sensors does not matter) and fuses the
        //    columns of tracks matched to its own.
        if let Some(fusion) = &config.fusion
            && config.identity_mode == IdentityMode::Beliefs
            && fr.is_multiple_of(config.exchange_every)
        {
            let snapshot: Vec<BeliefMatrix> = nodes.iter().map(|n| n.beliefs.clone()).collect();
            for s in 0..n_sensors {
                let mine: Vec<(u64, Vec2)> = records[s][frame]
                    .estimates
                    .iter()
                    .filter(|(l, _)| snapshot[s].tracks().contains(&TrackId(*l)))
                    .copied()
                    .collect();
                for &n in &neighbours[s] {
                    // The query names this sensor's range; the reply holds the neighbour's
                    // tracks inside it (label, position, the column's non-zero entries as
                    // (identity, probability) pairs). Raw, the neighbour would send its
                    // measurements inside the range instead.
                    let theirs: Vec<(u64, Vec2)> = records[n][frame]
                        .estimates
                        .iter()
                        .filter(|(l, p)| {
                            snapshot[n].tracks().contains(&TrackId(*l)) && sensors[s].covers(*p)
                        })
                        .copied()
                        .collect();
                    run.bytes_exchanged += reply_bytes(&snapshot[n], &theirs);
                    run.bytes_raw += raw_bytes(&observations.scans[n][frame].points, &sensors[s]);
                    let (r, c) = (mine.len(), theirs.len());
                    let mut cost = vec![0.0; r * c];
                    for (i, (_, a)) in mine.iter().enumerate() {
                        for (j, (_, b)) in theirs.iter().enumerate() {
                            cost[i * c + j] = d2(*a, *b, 2.0).min(gate * 10.0);
                        }
                    }
                    for (i, j) in assignment::minimise(r, c, &cost)? {
                        if cost[i * c + j] > gate {
                            continue;
                        }
                        let (mt, tt) = (TrackId(mine[i].0), TrackId(theirs[j].0));
                        let node = &mut nodes[s];
                        learn(&mut node.beliefs, snapshot[n].identities());
                        let other = align(
                            &snapshot[n].column(tt).map_err(id_err(n))?,
                            snapshot[n].identities(),
                            node.beliefs.identities(),
                        );
                        if let Err(e) = node.beliefs.fuse_track(mt, &other, fusion, &config.scaling)
                        {
                            run.events.push(Event {
                                frame: fr,
                                sensor: s,
                                track: Some(mt.0),
                                kind: EventKind::Refused {
                                    what: format!("fusion with sensor {n}'s track {}: {e}", tt.0),
                                },
                            });
                        }
                    }
                }
            }
        }
        // 5. Remember positions and velocities; score.
        let mut correct = (0, 0);
        let mut h = 0.0;
        for s in 0..n_sensors {
            let rec = &records[s][frame];
            let node = &mut nodes[s];
            let mut last = BTreeMap::new();
            for (l, p) in &rec.estimates {
                let v = node.last.get(l).map_or(Vec2::zeros(), |(q, _)| p - q);
                last.insert(*l, (*p, v));
            }
            node.last = last;
            h += node.beliefs.entropy(EntropyUnit::Nats);
            for a in node.beliefs.argmax() {
                let Some(k) = rec.estimates.iter().position(|(l, _)| *l == a.track.0) else {
                    continue;
                };
                let target = rec.origins[k]
                    .and_then(|t| truth.get(t))
                    .map(|t| (t.identity, ()));
                if let Some((id, _)) = target {
                    correct.1 += 1;
                    if a.identity == Some(id) {
                        correct.0 += 1;
                    }
                }
            }
        }
        run.entropy_nats.push(h);
        run.correct.push(correct);
    }
    run.final_beliefs = nodes.into_iter().map(|n| n.beliefs).collect();
    Ok(run)
}
