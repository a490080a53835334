//! Phase two: the identity layer. Each sensor keeps a [`BeliefMatrix`] over the identities it
//! knows × its tracks and replays its tracker's records frame by frame: mixing after
//! interactions, hand-overs of tracks that leave its range, new tracks (adopted from a
//! hand-over or a neighbour's track, announced as a new target, or unknown), local
//! information, and the query-based exchange with neighbours (belief columns and track
//! estimates only; tracks of one target matched by optimal assignment under a Mahalanobis
//! gate; beliefs fused by the configured criterion).

use std::collections::BTreeMap;

use identity_mgmt::{BeliefMatrix, EntropyUnit, FusionConfig, IdentityId};
use tracker_model::{TrackId, Vec2, assignment};

use crate::config::{DmtimConfig, IdentityMode, ReadUpdate};
use crate::error::{Error, Result, invalid};
use crate::scene::{Observations, Read, TruthTarget};
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
    /// H(before) − H(after), nats: the snapshot kept is the read that lowered it most.
    pub entropy_drop_nats: f64,
}

/// The identity layer's output.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentityRun {
    /// Σ over sensors of H(B_s), nats, per frame.
    pub entropy_nats: Vec<f64>,
    /// Per frame: (tracks whose argmax identity is their target's, tracks scored). A track
    /// is scored in a frame where its measurement comes from a target
    /// ([`SensorFrame::origins`]).
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

/// A hand-over waiting at its receiver for a matching new track.
pub(crate) struct Pending {
    /// The sending sensor.
    pub(crate) from: usize,
    /// The track's last position at the sender.
    pub(crate) position: Vec2,
    /// Its last velocity (a step per frame).
    pub(crate) velocity: Vec2,
    /// Frames waited so far.
    pub(crate) age: u64,
    /// The sender's identities: the column's rows.
    pub(crate) identities: Vec<IdentityId>,
    /// The track's column at the sender.
    pub(crate) column: Vec<f64>,
}

/// One sensor of the identity layer.
pub(crate) struct Node {
    /// Identities it knows × its tracks.
    pub(crate) beliefs: BeliefMatrix,
    /// label → (position, velocity) in the previous frame.
    pub(crate) last: BTreeMap<u64, (Vec2, Vec2)>,
    /// Hand-overs received and not yet matched.
    pub(crate) pending: Vec<Pending>,
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

/// Adds `track` to `beliefs` with a column given over `ids` (another sensor's rows, or the
/// announced identities): the identities the sensor did not know become zero rows first,
/// then the column is re-expressed over the sensor's rows. Identity mass travels with the
/// track, as in the identity-mass flow of Hwang, Balakrishnan, Roy & Tomlin 2004.
fn add_column(
    beliefs: &mut BeliefMatrix,
    track: u64,
    column: &[f64],
    ids: &[IdentityId],
) -> std::result::Result<(), identity_mgmt::Error> {
    learn(beliefs, ids);
    let col = align(column, ids, beliefs.identities());
    beliefs.add_track(TrackId(track), &col)
}

/// The error of an identity-mgmt call at `sensor`.
fn id_err(sensor: usize) -> impl Fn(identity_mgmt::Error) -> Error {
    move |source| Error::Identity { sensor, source }
}

/// Track-to-track association. The trackers report position estimates without their
/// covariance, so an estimate is taken to err by σ²I (σ the measurement noise): the
/// difference of two independent estimates has covariance 2σ²I, and an extrapolated
/// hand-over more. Tracks of one target are matched under a χ² gate on this Mahalanobis
/// distance (Oh, Hwang & Sastry 2008 associate tracks across sensors from estimates only).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Gate {
    /// σ², the variance of one position coordinate of a measurement.
    pub(crate) var: f64,
    /// The χ² gate on d².
    pub(crate) chi2: f64,
}

impl Gate {
    /// Mahalanobis d² of two position estimates whose difference has covariance k·σ²I.
    pub(crate) fn d2(&self, a: Vec2, b: Vec2, k: f64) -> f64 {
        (a - b).norm_squared() / (k * self.var)
    }
}

/// What every phase of a run reads and none changes: the trackers' records, the
/// observations (for reads and for the raw-byte comparison), the truth (for announcing and
/// scoring only), the settings, and what follows from them once.
pub(crate) struct Inputs<'a> {
    pub(crate) records: &'a [Vec<SensorFrame>],
    pub(crate) observations: &'a Observations,
    pub(crate) truth: &'a [TruthTarget],
    pub(crate) config: &'a DmtimConfig,
    /// Per sensor, the sensors whose ranges overlap its own: the only ones it talks to (the
    /// exchange is local, Oh, Hwang & Sastry 2008).
    pub(crate) neighbours: Vec<Vec<usize>>,
    pub(crate) gate: Gate,
}

impl<'a> Inputs<'a> {
    /// Checks the settings and that records, sensors and observations agree in number.
    pub(crate) fn new(
        records: &'a [Vec<SensorFrame>],
        observations: &'a Observations,
        truth: &'a [TruthTarget],
        config: &'a DmtimConfig,
    ) -> Result<Self> {
        config.check()?;
        let n_sensors = records.len();
        let sensors = &config.sensors;
        if sensors.len() != n_sensors || observations.scans.len() != n_sensors {
            return Err(invalid(
                "records",
                format!(
                    "{n_sensors} sensors' records, {} sensors configured, {} observed",
                    sensors.len(),
                    observations.scans.len()
                ),
            ));
        }
        let neighbours: Vec<Vec<usize>> = (0..n_sensors)
            .map(|s| {
                (0..n_sensors)
                    .filter(|&n| n != s && sensors[s].overlaps(&sensors[n]))
                    .collect()
            })
            .collect();
        let gate = Gate {
            var: config.sensing.noise_std_m.powi(2),
            chi2: config.merge_gate_chi2,
        };
        Ok(Self {
            records,
            observations,
            truth,
            config,
            neighbours,
            gate,
        })
    }
}

/// Sensor `asking` queries its neighbour `n` (Oh, Hwang & Sastry 2008: sensors exchange
/// track estimates and beliefs, never raw measurements). The query names the asker's
/// range; the reply holds `n`'s reported tracks that `beliefs` (n's matrix) has a column
/// for and whose estimates lie inside that range. Its cost (label, position, the column's
/// non-zero (identity, probability) pairs) is added to `run.bytes_exchanged`, and what `n`'s
/// measurements inside the range would have cost to `run.bytes_raw`.
fn query(
    run: &mut IdentityRun,
    inp: &Inputs<'_>,
    beliefs: &BeliefMatrix,
    asking: usize,
    n: usize,
    frame: usize,
) -> Vec<(u64, Vec2)> {
    let range = &inp.config.sensors[asking];
    let theirs: Vec<(u64, Vec2)> = inp.records[n][frame]
        .estimates
        .iter()
        .filter(|(m, p)| beliefs.tracks().contains(&TrackId(*m)) && range.covers(*p))
        .copied()
        .collect();
    run.bytes_exchanged += reply_bytes(beliefs, &theirs);
    run.bytes_raw += raw_bytes(&inp.observations.scans[n][frame].points, range);
    theirs
}

/// Which of a sensor's previous labels continue as which of this frame's (old → new).
/// With beliefs the labels are MCMCDA's, which persist through its window, so a label
/// continues itself; swaps are the mixings' business. The nearest-track baseline has no
/// labels to trust: each previous track moves to the nearest estimate from where it was, by
/// optimal assignment on d² (covariance 2σ²I) under the gate.
fn carry_labels(
    node: &Node,
    rec: &SensorFrame,
    old: &[u64],
    inp: &Inputs<'_>,
) -> Result<Vec<(u64, u64)>> {
    let now: Vec<u64> = rec.estimates.iter().map(|(l, _)| *l).collect();
    let gate = inp.gate.chi2;
    Ok(match inp.config.identity_mode {
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
                        .map_or(gate * 10.0, |q| inp.gate.d2(q.0, *p, 2.0).min(gate * 10.0));
                }
            }
            assignment::minimise(r, c, &cost)?
                .into_iter()
                .filter(|&(i, j)| cost[i * c + j] <= gate)
                .map(|(i, j)| (old[i], now[j]))
                .collect()
        }
    })
}

/// Takes every column in `old` out of `beliefs` and puts the carried ones back under their
/// new labels; returns the columns taken out, so that ended tracks can be handed over.
fn relabel(
    beliefs: &mut BeliefMatrix,
    old: &[u64],
    carry: &[(u64, u64)],
) -> std::result::Result<BTreeMap<u64, Vec<f64>>, identity_mgmt::Error> {
    let mut columns: BTreeMap<u64, Vec<f64>> = BTreeMap::new();
    for &l in old {
        columns.insert(l, beliefs.remove_track(TrackId(l))?);
    }
    for &(a, b) in carry {
        beliefs.add_track(TrackId(b), columns.get(&a).map_or(&[][..], Vec::as_slice))?;
    }
    Ok(columns)
}

/// Matches two sensors' tracks of one target: optimal assignment on d² between their
/// estimates (covariance 2σ²I), each cost capped at ten gates, keeping the pairs inside the
/// gate, in the assignment's order. Returns (index in `mine`, index in `theirs`).
fn match_tracks(
    mine: &[(u64, Vec2)],
    theirs: &[(u64, Vec2)],
    gate: Gate,
) -> Result<Vec<(usize, usize)>> {
    let (r, c) = (mine.len(), theirs.len());
    let mut cost = vec![0.0; r * c];
    for (i, (_, a)) in mine.iter().enumerate() {
        for (j, (_, b)) in theirs.iter().enumerate() {
            cost[i * c + j] = gate.d2(*a, *b, 2.0).min(gate.chi2 * 10.0);
        }
    }
    Ok(assignment::minimise(r, c, &cost)?
        .into_iter()
        .filter(|&(i, j)| cost[i * c + j] <= gate.chi2)
        .collect())
}

/// The information vector a read of `identity` about `track` contributes, over the
/// matrix's identities (which must include `identity`). The read's likelihood is 1 − e at
/// the identity read and e/(n − 1) at each other (e the known error rate). With
/// [`ReadUpdate::Replace`] that is the column, as in the papers' "replace the column"
/// (Hwang, Balakrishnan, Roy & Tomlin 2004); with [`ReadUpdate::Posterior`] it is the
/// track's column times the likelihood, normalised (Bayes' rule), or the likelihood alone if
/// the read contradicts the column entirely.
pub(crate) fn read_information(
    beliefs: &BeliefMatrix,
    track: TrackId,
    identity: IdentityId,
    config: &DmtimConfig,
) -> std::result::Result<Vec<f64>, identity_mgmt::Error> {
    let ids = beliefs.identities();
    let e = config.local_info.error_rate;
    let likelihood: Vec<f64> = if ids.len() == 1 {
        vec![1.0]
    } else {
        ids.iter()
            .map(|id| {
                if *id == identity {
                    1.0 - e
                } else {
                    e / (ids.len() - 1) as f64
                }
            })
            .collect()
    };
    Ok(match config.read_update {
        ReadUpdate::Replace => likelihood,
        ReadUpdate::Posterior => {
            let prior = beliefs.column(track)?;
            let post: Vec<f64> = prior.iter().zip(&likelihood).map(|(p, q)| p * q).collect();
            let z: f64 = post.iter().sum();
            if z > 0.0 {
                post.iter().map(|p| p / z).collect()
            } else {
                likelihood
            }
        }
    })
}

/// Per frame, the tracks scored and those whose argmax identity is right. A track is scored
/// where its measurement in this frame comes from a target (the tracker never sees
/// origins); it is right if its most probable identity is that target's.
fn score(beliefs: &BeliefMatrix, rec: &SensorFrame, truth: &[TruthTarget]) -> (usize, usize) {
    let mut correct = (0, 0);
    for a in beliefs.argmax() {
        let Some(k) = rec.estimates.iter().position(|(l, _)| *l == a.track.0) else {
            continue;
        };
        if let Some(id) = rec.origins[k]
            .and_then(|t| truth.get(t))
            .map(|t| t.identity)
        {
            correct.1 += 1;
            if a.identity == Some(id) {
                correct.0 += 1;
            }
        }
    }
    correct
}

impl Node {
    /// An empty node: no identities, no tracks, nothing pending.
    fn new() -> Self {
        Self {
            beliefs: BeliefMatrix::new(),
            last: BTreeMap::new(),
            pending: Vec::new(),
        }
    }

    /// Remembers this frame's estimates and their velocities (the step from the previous
    /// frame's estimate of the same label; zero for a new label), for the next frame's
    /// hand-overs and the nearest-track baseline.
    pub(crate) fn remember(&mut self, estimates: &[(u64, Vec2)]) {
        let mut last = BTreeMap::new();
        for (l, p) in estimates {
            let v = self.last.get(l).map_or(Vec2::zeros(), |(q, _)| p - q);
            last.insert(*l, (*p, v));
        }
        self.last = last;
    }

    /// Ages the hand-overs still waiting and drops those older than `ttl` frames: a receiver
    /// that has not started a matching track by then will not.
    fn expire_hand_overs(&mut self, ttl: u64) {
        for p in &mut self.pending {
            p.age += 1;
        }
        self.pending.retain(|p| p.age <= ttl);
    }
}

impl IdentityRun {
    /// Appends an event to the log.
    fn log(&mut self, frame: usize, sensor: usize, track: Option<u64>, kind: EventKind) {
        self.events.push(Event {
            frame: frame as u64,
            sensor,
            track,
            kind,
        });
    }
}

/// What the phases of a run change: every sensor's node, the identities announced so far,
/// and the output being built.
pub(crate) struct Layer {
    pub(crate) nodes: Vec<Node>,
    pub(crate) announced: Vec<IdentityId>,
    pub(crate) run: IdentityRun,
}

impl Layer {
    /// `n_sensors` empty nodes and an empty output.
    pub(crate) fn new(n_sensors: usize) -> Self {
        Self {
            nodes: (0..n_sensors).map(|_| Node::new()).collect(),
            announced: Vec::new(),
            run: IdentityRun {
                entropy_nats: Vec::new(),
                correct: Vec::new(),
                events: Vec::new(),
                bytes_exchanged: 0,
                bytes_raw: 0,
                snapshot: None,
                final_beliefs: Vec::new(),
            },
        }
    }

    /// The output, with every sensor's matrix at the end.
    pub(crate) fn finish(mut self) -> IdentityRun {
        self.run.final_beliefs = self.nodes.into_iter().map(|n| n.beliefs).collect();
        self.run
    }

    /// Phase 1, sensor by sensor: mix the identities of tracks that interacted, carry the
    /// columns to this frame's labels, and hand over the tracks that ended near the edge.
    /// Hand-overs are delivered only after every sensor has sent, so what a sensor receives
    /// does not depend on the order of sensors.
    pub(crate) fn carry_and_hand_over(&mut self, inp: &Inputs<'_>, frame: usize) -> Result<()> {
        let mut outbox: Vec<(usize, Pending)> = Vec::new();
        for s in 0..self.nodes.len() {
            let rec = &inp.records[s][frame];
            if inp.config.identity_mode == IdentityMode::Beliefs {
                self.mix(s, frame, rec)?;
            }
            let old: Vec<u64> = self.nodes[s].beliefs.tracks().iter().map(|t| t.0).collect();
            let carry = carry_labels(&self.nodes[s], rec, &old, inp)?;
            let columns = relabel(&mut self.nodes[s].beliefs, &old, &carry).map_err(id_err(s))?;
            for &l in old.iter().filter(|l| !carry.iter().any(|(a, _)| a == *l)) {
                let column = columns.get(&l).map_or(&[][..], Vec::as_slice);
                self.hand_over(inp, s, frame, l, column, &mut outbox);
            }
        }
        for (n, p) in outbox {
            self.nodes[n].pending.push(p);
        }
        Ok(())
    }

    /// Mixes the identities of tracks whose interaction ended this frame with the mixing
    /// matrix built from MCMCDA samples (Oh, Hwang & Sastry 2008): their columns B_T become
    /// B_T·M. A mixing that names a track the matrix does not hold is skipped.
    fn mix(&mut self, s: usize, frame: usize, rec: &SensorFrame) -> Result<()> {
        let node = &mut self.nodes[s];
        for m in &rec.mixings {
            let tracks: Vec<TrackId> = m.labels.iter().map(|&l| TrackId(l)).collect();
            if tracks.iter().all(|t| node.beliefs.tracks().contains(t)) {
                node.beliefs
                    .mix(&tracks, &m.continuation)
                    .map_err(id_err(s))?;
                let kind = EventKind::Mixed {
                    labels: m.labels.clone(),
                    uniform: m.uniform_fallback,
                };
                self.run.log(frame, s, None, kind);
            }
        }
        Ok(())
    }

    /// Hands over track `l` of sensor `s`, which ended with `column`: if its last estimate
    /// was within the hand-over margin of the range's edge, it goes (position, velocity,
    /// identities, column) to the neighbours covering its last or next position (Oh, Hwang
    /// & Sastry 2008: a target leaving a range takes its identity belief to the sensor it
    /// enters). The message costs the same counted raw: measurements would not carry it.
    fn hand_over(
        &mut self,
        inp: &Inputs<'_>,
        s: usize,
        frame: usize,
        l: u64,
        column: &[f64],
        outbox: &mut Vec<(usize, Pending)>,
    ) {
        let node = &self.nodes[s];
        let Some(&(p, v)) = node.last.get(&l) else {
            return;
        };
        let spec = &inp.config.sensors[s];
        if (p - spec.centre()).norm() < spec.range_m - inp.config.handover_margin_m {
            return;
        }
        let sensors = &inp.config.sensors;
        let to: Vec<usize> = inp.neighbours[s]
            .iter()
            .copied()
            .filter(|&n| sensors[n].covers(p + v) || sensors[n].covers(p))
            .collect();
        if to.is_empty() {
            return;
        }
        let ids = node.beliefs.identities().to_vec();
        let message = BYTES_PER_NUMBER * (4 + 2 * ids.len() as u64) * to.len() as u64;
        self.run.bytes_exchanged += message;
        self.run.bytes_raw += message;
        for &n in &to {
            let pending = Pending {
                from: s,
                position: p,
                velocity: v,
                age: 0,
                identities: ids.clone(),
                column: column.to_vec(),
            };
            outbox.push((n, pending));
        }
        self.run
            .log(frame, s, Some(l), EventKind::HandOverSent { to });
    }

    /// Phase 2, sensor by sensor: every track new to the sensor's matrix takes, in this
    /// order of preference, a waiting hand-over, a neighbour's track of the same target, a
    /// newly appeared target's identity, or else a uniform column over the identities
    /// announced so far (Oh, Hwang & Sastry 2008). Then the hand-overs still waiting age.
    /// Sensors go in order and see the tracks earlier sensors started this frame.
    pub(crate) fn start_new_tracks(&mut self, inp: &Inputs<'_>, frame: usize) -> Result<()> {
        for s in 0..self.nodes.len() {
            let new: Vec<(u64, Vec2)> = inp.records[s][frame]
                .estimates
                .iter()
                .filter(|(l, _)| !self.nodes[s].beliefs.tracks().contains(&TrackId(*l)))
                .copied()
                .collect();
            for (l, x) in new {
                let taken = self.take_hand_over(s, frame, l, x, inp.gate)?
                    || self.adopt_from_neighbour(inp, s, frame, l, x)?
                    || self.announce(inp, s, frame, l)?;
                if !taken {
                    self.start_unknown(s, frame, l)?;
                }
            }
            self.nodes[s].expire_hand_overs(inp.config.handover_ttl_frames);
        }
        Ok(())
    }

    /// New track `l` at `x` takes the nearest waiting hand-over, extrapolated to this frame,
    /// if within the gate (covariance (2 + age)σ²I: the extrapolation adds error as it
    /// ages). Returns whether it did.
    fn take_hand_over(
        &mut self,
        s: usize,
        frame: usize,
        l: u64,
        x: Vec2,
        gate: Gate,
    ) -> Result<bool> {
        let best = self.nodes[s]
            .pending
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let age = p.age as f64 + 1.0;
                (k, gate.d2(p.position + p.velocity * age, x, 2.0 + age))
            })
            .filter(|(_, d)| *d <= gate.chi2)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let Some((k, _)) = best else {
            return Ok(false);
        };
        let p = self.nodes[s].pending.remove(k);
        add_column(&mut self.nodes[s].beliefs, l, &p.column, &p.identities).map_err(id_err(s))?;
        self.run.log(
            frame,
            s,
            Some(l),
            EventKind::HandOverReceived { from: p.from },
        );
        Ok(true)
    }

    /// New track `l` at `x` queries every neighbour and takes the column of the nearest of
    /// their tracks within the gate (the first neighbour on ties), a track of the same target
    /// already carrying its identity. Every neighbour's reply is counted. Returns whether it
    /// took one.
    fn adopt_from_neighbour(
        &mut self,
        inp: &Inputs<'_>,
        s: usize,
        frame: usize,
        l: u64,
        x: Vec2,
    ) -> Result<bool> {
        let mut best: Option<(usize, u64, f64)> = None;
        for &n in &inp.neighbours[s] {
            let theirs = query(&mut self.run, inp, &self.nodes[n].beliefs, s, n, frame);
            for (m, y) in &theirs {
                let d = inp.gate.d2(*y, x, 2.0);
                if d <= inp.gate.chi2 && best.is_none_or(|b| d < b.2) {
                    best = Some((n, *m, d));
                }
            }
        }
        let Some((n, m, _)) = best else {
            return Ok(false);
        };
        let ids = self.nodes[n].beliefs.identities().to_vec();
        let col = self.nodes[n]
            .beliefs
            .column(TrackId(m))
            .map_err(id_err(n))?;
        add_column(&mut self.nodes[s].beliefs, l, &col, &ids).map_err(id_err(s))?;
        self.run
            .log(frame, s, Some(l), EventKind::Adopted { from: n });
        Ok(true)
    }

    /// New track `l` is the first track of a target not announced yet: the target's identity
    /// is announced and the track carries it with certainty (the papers' premise: an
    /// identity is assigned when its target first appears, Hwang, Balakrishnan, Roy & Tomlin
    /// 2004). Returns whether it was.
    fn announce(&mut self, inp: &Inputs<'_>, s: usize, frame: usize, l: u64) -> Result<bool> {
        let rec = &inp.records[s][frame];
        let first = rec
            .estimates
            .iter()
            .position(|(m, _)| *m == l)
            .and_then(|k| rec.origins[k])
            .and_then(|t| inp.truth.get(t))
            .map(|t| t.identity);
        let Some(id) = first.filter(|id| !self.announced.contains(id)) else {
            return Ok(false);
        };
        self.announced.push(id);
        add_column(&mut self.nodes[s].beliefs, l, &[1.0], &[id]).map_err(id_err(s))?;
        let kind = EventKind::NewTarget { identity: id };
        self.run.log(frame, s, Some(l), kind);
        Ok(true)
    }

    /// New track `l` of no known origin: uniform over the identities announced so far (no
    /// information). With none announced yet the track is left out of the matrix.
    fn start_unknown(&mut self, s: usize, frame: usize, l: u64) -> Result<()> {
        if self.announced.is_empty() {
            return Ok(());
        }
        let u = vec![1.0 / self.announced.len() as f64; self.announced.len()];
        add_column(&mut self.nodes[s].beliefs, l, &u, &self.announced).map_err(id_err(s))?;
        self.run.log(frame, s, Some(l), EventKind::Unknown);
        Ok(())
    }

    /// Phase 3, sensor by sensor: each read that came with a measurement of a track in the
    /// matrix is incorporated as local information (Hwang, Balakrishnan, Roy & Tomlin 2004).
    pub(crate) fn take_local_information(&mut self, inp: &Inputs<'_>, frame: usize) -> Result<()> {
        for s in 0..self.nodes.len() {
            let rec = &inp.records[s][frame];
            for (read, track) in inp.observations.scans[s][frame]
                .reads
                .iter()
                .zip(&rec.read_tracks)
            {
                let Some(l) = *track else { continue };
                if !self.nodes[s].beliefs.tracks().contains(&TrackId(l)) {
                    continue;
                }
                self.take_read(inp.config, s, frame, read, l)?;
            }
        }
        Ok(())
    }

    /// Incorporates `read` about track `l` of sensor `s` (see [`read_information`] and
    /// [`ReadRule`]) and logs it; a read identity-mgmt refuses is logged and leaves the
    /// matrix as it was. Of the reads at a matrix with at least two tracks, the one that
    /// lowered its entropy most is kept as the run's snapshot (the first such read often
    /// changed it by less than a table's third decimal, so before and after looked alike).
    fn take_read(
        &mut self,
        config: &DmtimConfig,
        s: usize,
        frame: usize,
        read: &Read,
        l: u64,
    ) -> Result<()> {
        let node = &mut self.nodes[s];
        learn(&mut node.beliefs, &[read.identity]);
        let info = read_information(&node.beliefs, TrackId(l), read.identity, config)
            .map_err(id_err(s))?;
        let before = node.beliefs.clone();
        let kind = match apply_read(&mut node.beliefs, TrackId(l), &info, read.identity, config) {
            Ok((rule, h_before, h_after)) => {
                let drop = h_before - h_after;
                let best = self
                    .run
                    .snapshot
                    .as_ref()
                    .map_or(0.0, |s| s.entropy_drop_nats);
                if before.n_tracks() >= 2 && drop > best {
                    self.run.snapshot = Some(Snapshot {
                        frame: frame as u64,
                        sensor: s,
                        before,
                        after: node.beliefs.clone(),
                        entropy_drop_nats: drop,
                    });
                }
                EventKind::LocalInformation {
                    identity: read.identity,
                    correct: read.correct,
                    rule,
                    entropy_before_nats: h_before,
                    entropy_after_nats: h_after,
                }
            }
            Err(e) => EventKind::Refused {
                what: format!("local information {}: {e}", read.identity),
            },
        };
        self.run.log(frame, s, Some(l), kind);
        Ok(())
    }

    /// Phase 4, every `exchange_every` frames with beliefs and a fusion criterion: each
    /// sensor queries its neighbours for their tracks inside its range and their columns,
    /// matches them to its own tracks and fuses the matched columns (Oh, Hwang & Sastry
    /// 2008; fusion criteria after Hwang, Roy, Balakrishnan & Tomlin 2004). Every sensor
    /// reads the matrices as they were before the exchange, so the order of sensors does not
    /// matter.
    pub(crate) fn exchange(&mut self, inp: &Inputs<'_>, frame: usize) -> Result<()> {
        let config = inp.config;
        let Some(fusion) = &config.fusion else {
            return Ok(());
        };
        let fr = frame as u64;
        if config.identity_mode != IdentityMode::Beliefs
            || !fr.is_multiple_of(config.exchange_every)
        {
            return Ok(());
        }
        let snapshot: Vec<BeliefMatrix> = self.nodes.iter().map(|n| n.beliefs.clone()).collect();
        for s in 0..self.nodes.len() {
            let mine: Vec<(u64, Vec2)> = inp.records[s][frame]
                .estimates
                .iter()
                .filter(|(l, _)| snapshot[s].tracks().contains(&TrackId(*l)))
                .copied()
                .collect();
            for &n in &inp.neighbours[s] {
                let theirs = query(&mut self.run, inp, &snapshot[n], s, n, frame);
                for (i, j) in match_tracks(&mine, &theirs, inp.gate)? {
                    let pair = ((s, TrackId(mine[i].0)), (n, TrackId(theirs[j].0)));
                    self.fuse(config, frame, pair, &snapshot[n], fusion)?;
                }
            }
        }
        Ok(())
    }

    /// Fuses sensor `s`'s column of track `mt` with neighbour `n`'s column of its track `tt`
    /// (read from `theirs`, n's matrix before the exchange), learning n's identities first.
    /// A fusion identity-mgmt refuses is logged and leaves the matrix as it was.
    fn fuse(
        &mut self,
        config: &DmtimConfig,
        frame: usize,
        ((s, mt), (n, tt)): ((usize, TrackId), (usize, TrackId)),
        theirs: &BeliefMatrix,
        fusion: &FusionConfig,
    ) -> Result<()> {
        let node = &mut self.nodes[s];
        learn(&mut node.beliefs, theirs.identities());
        let other = align(
            &theirs.column(tt).map_err(id_err(n))?,
            theirs.identities(),
            node.beliefs.identities(),
        );
        if let Err(e) = node.beliefs.fuse_track(mt, &other, fusion, &config.scaling) {
            let what = format!("fusion with sensor {n}'s track {}: {e}", tt.0);
            self.run
                .log(frame, s, Some(mt.0), EventKind::Refused { what });
        }
        Ok(())
    }

    /// Phase 5: every sensor remembers this frame's estimates; the frame's Σ H(B_s) and
    /// score are recorded.
    pub(crate) fn remember_and_score(&mut self, inp: &Inputs<'_>, frame: usize) {
        let mut correct = (0, 0);
        let mut h = 0.0;
        for (node, records) in self.nodes.iter_mut().zip(inp.records) {
            let rec = &records[frame];
            node.remember(&rec.estimates);
            h += node.beliefs.entropy(EntropyUnit::Nats);
            let (c, n) = score(&node.beliefs, rec, inp.truth);
            correct.0 += c;
            correct.1 += n;
        }
        self.run.entropy_nats.push(h);
        self.run.correct.push(correct);
    }
}

/// Runs the identity layer over the trackers' records. `truth` is used for two things
/// only: announcing a target's identity when it first appears (the papers' premise:
/// identities are assigned when a target first appears) and scoring.
///
/// Each frame goes through five phases, every sensor in turn within each: mixing and
/// hand-overs, new tracks, local information, the exchange with neighbours, then
/// bookkeeping and scoring (Oh, Hwang & Sastry 2008).
pub fn manage_identities(
    records: &[Vec<SensorFrame>],
    observations: &Observations,
    truth: &[TruthTarget],
    config: &DmtimConfig,
) -> Result<IdentityRun> {
    let inputs = Inputs::new(records, observations, truth, config)?;
    let mut layer = Layer::new(records.len());
    let n_frames = records.iter().map(Vec::len).min().unwrap_or(0);
    for frame in 0..n_frames {
        layer.carry_and_hand_over(&inputs, frame)?;
        layer.start_new_tracks(&inputs, frame)?;
        layer.take_local_information(&inputs, frame)?;
        layer.exchange(&inputs, frame)?;
        layer.remember_and_score(&inputs, frame);
    }
    Ok(layer.finish())
}
