//! Tests of the DMTIM crate.

use identity_mgmt::{BeliefMatrix, Continuation, FusionConfig, FusionCriterion, IdentityId};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracker_model::{TrackId, Vec2};

use crate::identity::{Inputs, Layer, Pending, read_information};
use crate::tracking::clusters;
use crate::{
    DmtimConfig, EventKind, IdentityMode, IdentityRun, Mixing, Observations, Read, ReadRule,
    ReadUpdate, SensorFrame, SensorScan, SensorSpec, TruthTarget, manage_identities, observe,
    seven_radars, track_all,
};

fn config() -> DmtimConfig {
    let (sensors, _) = seven_radars().expect("valid");
    let mut c = DmtimConfig {
        sensors,
        ..DmtimConfig::default()
    };
    c.mcmcda.max_speed = 2.0;
    c.mcmcda.measurement_noise = nalgebra::Matrix2::identity() * 0.09;
    c.mcmcda.motion = tracker_model::ConstantVelocity2::mcmcda(1.0, 0.01).expect("valid");
    c.mcmcda.births_per_scan = 0.05;
    c.mcmcda.p_disappear = 0.01;
    c.mcmcda.max_gap = 3;
    c
}

fn run(c: &DmtimConfig, truth: &[TruthTarget], seed: u64) -> IdentityRun {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let obs = observe(truth, c, 100, &mut rng).expect("observe");
    let records = track_all(&obs, c, seed).expect("track");
    manage_identities(&records, &obs, truth, c).expect("identities")
}

/// With a correct read of every target at every sensor in every frame, every scored track's
/// argmax identity is its target's: the read is certain (l = e_i), so after Sinkhorn the
/// column is e_i whatever came before.
#[test]
fn perfect_local_information_gives_every_identity() {
    let (_, truth) = seven_radars().expect("valid");
    let mut c = config();
    c.local_info.sensors = (0..7).collect();
    c.local_info.probability = 1.0;
    c.local_info.error_rate = 0.0;
    c.sensing.p_detect = 1.0;
    for seed in 1..4 {
        let r = run(&c, &truth, seed);
        let scored: usize = r.correct.iter().map(|x| x.1).sum();
        assert!(
            scored > 300,
            "seed {seed}: only {scored} track-frames scored"
        );
        for (frame, &(ok, n)) in r.correct.iter().enumerate() {
            assert_eq!(ok, n, "seed {seed}, frame {frame}: {ok} of {n} correct");
        }
    }
}

/// Without any reads the same runs are not perfect: the test above can fail.
#[test]
fn without_local_information_some_identity_is_wrong() {
    let (_, truth) = seven_radars().expect("valid");
    let mut c = config();
    c.sensing.p_detect = 1.0;
    let wrong: usize = (1..4)
        .map(|seed| {
            run(&c, &truth, seed)
                .correct
                .iter()
                .map(|&(ok, n)| n - ok)
                .sum::<usize>()
        })
        .sum();
    assert!(wrong > 0);
}

/// A straight flight sampled at speed 1 passes through its waypoints and has unit steps.
#[test]
fn along_waypoints() {
    let t = TruthTarget::along(
        IdentityId(1),
        5,
        &[
            tracker_model::Vec2::new(0.0, 0.0),
            tracker_model::Vec2::new(3.0, 0.0),
            tracker_model::Vec2::new(3.0, 2.5),
        ],
        1.0,
    )
    .expect("valid");
    assert_eq!(t.at(4), None);
    assert_eq!(t.at(5), Some(tracker_model::Vec2::new(0.0, 0.0)));
    assert_eq!(t.at(8), Some(tracker_model::Vec2::new(3.0, 0.0)));
    assert_eq!(
        t.positions.last().copied(),
        Some(tracker_model::Vec2::new(3.0, 2.5))
    );
    for w in t.positions.windows(2).take(5) {
        assert!(((w[1] - w[0]).norm() - 1.0).abs() < 1e-12);
    }
    assert!(TruthTarget::along(IdentityId(1), 0, &[tracker_model::Vec2::zeros()], 1.0).is_err());
}

/// Bad configurations are typed errors naming the field.
#[test]
fn config_errors() {
    let mut c = config();
    c.local_info.sensors = vec![9];
    assert!(matches!(
        c.check(),
        Err(crate::Error::Model(
            tracker_model::Error::InvalidParameter {
                name: "local_info.sensors",
                ..
            }
        ))
    ));
    let mut c = config();
    c.sensors.clear();
    assert!(c.check().is_err());
    let mut c = config();
    c.exchange_every = 0;
    assert!(c.check().is_err());
    let parsed: Result<DmtimConfig, _> =
        serde_json::from_str(r#"{"interaction_distance_m": 2.0, "bogus": 1}"#);
    assert!(parsed.is_err(), "unknown fields are rejected");
}

/// Every mixing matrix a run builds is doubly stochastic, and the fusion criteria differ
/// from no fusion only through the exchange (same trackers, same reads).
#[test]
fn mixings_are_doubly_stochastic() {
    let (_, truth) = seven_radars().expect("valid");
    let c = config();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let obs = observe(&truth, &c, 100, &mut rng).expect("observe");
    let records = track_all(&obs, &c, 2).expect("track");
    let mut n_mixings = 0;
    for frames in &records {
        for f in frames {
            for m in &f.mixings {
                n_mixings += 1;
                let k = m.continuation.n();
                for i in 0..k {
                    let row: f64 = (0..k).map(|j| m.continuation.get(i, j)).sum();
                    let col: f64 = (0..k).map(|j| m.continuation.get(j, i)).sum();
                    assert!((row - 1.0).abs() < 1e-6 && (col - 1.0).abs() < 1e-6);
                }
            }
        }
    }
    assert!(n_mixings > 0, "the crossings produce mixings");
    let mut none = c.clone();
    none.fusion = None;
    let a = manage_identities(&records, &obs, &truth, &none).expect("no fusion");
    let mut chernoff = c.clone();
    chernoff.fusion = Some(FusionConfig {
        criterion: FusionCriterion::Chernoff,
        ..FusionConfig::default()
    });
    let b = manage_identities(&records, &obs, &truth, &chernoff).expect("fusion");
    assert!(b.bytes_exchanged > a.bytes_exchanged);
}

// Unit tests of the identity layer's phases, each on a hand-made frame whose outcome is
// worked out by hand. Two sensors of range 10, A at (0, 0) and B at (15, 0), overlap; σ = 0.3
// (default), so d² of two estimates a distance d apart is d²/0.18 against the gate 13.8.

const ID_A: IdentityId = IdentityId(1);
const ID_B: IdentityId = IdentityId(2);

fn spec(name: &str, x: f64) -> SensorSpec {
    SensorSpec {
        name: name.into(),
        centre: [x, 0.0],
        range_m: 10.0,
    }
}

fn pair_config() -> DmtimConfig {
    DmtimConfig {
        sensors: vec![spec("A", 0.0), spec("B", 15.0)],
        ..DmtimConfig::default()
    }
}

/// A tracker's frame reporting `estimates` (label, x, y), none with a known origin.
fn frame_of(estimates: &[(u64, f64, f64)]) -> SensorFrame {
    SensorFrame {
        estimates: estimates
            .iter()
            .map(|&(l, x, y)| (l, Vec2::new(x, y)))
            .collect(),
        mixings: Vec::new(),
        n_measurements: 0,
        read_tracks: Vec::new(),
        origins: vec![None; estimates.len()],
    }
}

/// `n_sensors` sensors observing nothing for `n_frames` frames.
fn quiet(n_sensors: usize, n_frames: usize) -> Observations {
    Observations {
        n_frames: n_frames as u64,
        scans: vec![vec![SensorScan::default(); n_frames]; n_sensors],
    }
}

/// A matrix over identities A, B with the given (track, [P(A), P(B)]) columns.
fn beliefs(columns: &[(u64, [f64; 2])]) -> BeliefMatrix {
    let rows: Vec<Vec<f64>> = (0..2)
        .map(|i| columns.iter().map(|(_, c)| c[i]).collect())
        .collect();
    BeliefMatrix::from_rows(
        vec![ID_A, ID_B],
        columns.iter().map(|(l, _)| TrackId(*l)).collect(),
        &rows,
    )
    .expect("valid matrix")
}

fn column(b: &BeliefMatrix, track: u64) -> Vec<f64> {
    b.column(TrackId(track)).expect("track in matrix")
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// Phase 1, mixing: with M = [[0.8, 0.2], [0.2, 0.8]] the certain columns e_A, e_B of tracks
/// 1 and 2 become B·M = (0.8, 0.2) and (0.2, 0.8); a mixing naming a track the matrix does
/// not hold is skipped and not logged.
#[test]
fn mixing_spreads_identities_by_the_mixing_matrix() {
    let c = DmtimConfig {
        sensors: vec![spec("A", 0.0)],
        ..DmtimConfig::default()
    };
    let m = Continuation::new(2, vec![0.8, 0.2, 0.2, 0.8]).expect("doubly stochastic");
    let mut f = frame_of(&[(1, 0.0, 0.0), (2, 1.0, 0.0)]);
    for labels in [vec![1, 2], vec![1, 9]] {
        f.mixings.push(Mixing {
            labels,
            continuation: m.clone(),
            uniform_fallback: false,
        });
    }
    let records = vec![vec![f]];
    let obs = quiet(1, 1);
    let inp = Inputs::new(&records, &obs, &[], &c).expect("inputs");
    let mut layer = Layer::new(1);
    layer.nodes[0].beliefs = beliefs(&[(1, [1.0, 0.0]), (2, [0.0, 1.0])]);
    layer.carry_and_hand_over(&inp, 0).expect("phase 1");
    let b = &layer.nodes[0].beliefs;
    assert!(close(&column(b, 1), &[0.8, 0.2], 1e-12));
    assert!(close(&column(b, 2), &[0.2, 0.8], 1e-12));
    assert_eq!(layer.run.events.len(), 1);
    assert!(
        matches!(&layer.run.events[0].kind, EventKind::Mixed { labels, uniform: false } if labels == &vec![1, 2])
    );
}

/// Phase 1, hand-over: track 1 of A ended at (8.5, 0), 1.5 from A's edge (margin 3), heading
/// +x into B; track 3 ended at (0, 1), deep inside A; track 2 continues. Only track 1 is
/// sent, to B only, with its column; the message costs 8 · (4 + 2·2 identities) = 64 bytes,
/// counted the same raw.
#[test]
fn an_ended_track_near_the_edge_is_handed_to_the_neighbour_it_heads_for() {
    let c = pair_config();
    let records = vec![vec![frame_of(&[(2, 0.0, 0.0)])], vec![frame_of(&[])]];
    let obs = quiet(2, 1);
    let inp = Inputs::new(&records, &obs, &[], &c).expect("inputs");
    let mut layer = Layer::new(2);
    let node = &mut layer.nodes[0];
    node.beliefs = beliefs(&[(1, [0.7, 0.3]), (2, [0.3, 0.7]), (3, [0.5, 0.5])]);
    let right = Vec2::new(1.0, 0.0);
    node.last.insert(1, (Vec2::new(8.5, 0.0), right));
    node.last.insert(2, (Vec2::new(-1.0, 0.0), right));
    node.last.insert(3, (Vec2::new(0.0, 1.0), right));
    layer.carry_and_hand_over(&inp, 0).expect("phase 1");
    assert_eq!(layer.nodes[0].beliefs.tracks(), &[TrackId(2)]);
    assert_eq!(column(&layer.nodes[0].beliefs, 2), vec![0.3, 0.7]);
    assert!(layer.nodes[0].pending.is_empty());
    let sent = &layer.nodes[1].pending;
    assert_eq!(sent.len(), 1);
    assert_eq!((sent[0].from, sent[0].age), (0, 0));
    assert_eq!(
        (sent[0].position, sent[0].velocity),
        (Vec2::new(8.5, 0.0), right)
    );
    assert_eq!(sent[0].identities, vec![ID_A, ID_B]);
    assert_eq!(sent[0].column, vec![0.7, 0.3]);
    assert_eq!((layer.run.bytes_exchanged, layer.run.bytes_raw), (64, 64));
    assert_eq!(layer.run.events.len(), 1);
    assert_eq!(layer.run.events[0].track, Some(1));
    assert_eq!(
        layer.run.events[0].kind,
        EventKind::HandOverSent { to: vec![1] }
    );
}

/// Phase 1, nearest-track baseline: the tracker relabelled both tracks (1 → 7, 2 → 8); the
/// columns follow the nearest estimates (d² 0.5 and 0.22, inside the gate). Track 3, last
/// at (−5, 4), is assigned the estimate at (−5, 0) but d² = 16/0.18 is outside the gate:
/// neither is carried.
#[test]
fn nearest_track_carries_each_column_to_the_nearest_estimate() {
    let mut c = DmtimConfig {
        sensors: vec![spec("A", 0.0)],
        ..DmtimConfig::default()
    };
    c.identity_mode = IdentityMode::NearestTrack;
    let records = vec![vec![frame_of(&[
        (8, 5.2, 0.0),
        (9, -5.0, 0.0),
        (7, 0.3, 0.0),
    ])]];
    let obs = quiet(1, 1);
    let inp = Inputs::new(&records, &obs, &[], &c).expect("inputs");
    let mut layer = Layer::new(1);
    layer.nodes[0].beliefs = beliefs(&[(1, [0.9, 0.1]), (2, [0.1, 0.9]), (3, [0.5, 0.5])]);
    for (l, x, y) in [(1, 0.0, 0.0), (2, 5.0, 0.0), (3, -5.0, 4.0)] {
        layer.nodes[0]
            .last
            .insert(l, (Vec2::new(x, y), Vec2::zeros()));
    }
    layer.carry_and_hand_over(&inp, 0).expect("phase 1");
    let b = &layer.nodes[0].beliefs;
    assert_eq!(b.tracks(), &[TrackId(7), TrackId(8)]);
    assert_eq!(column(b, 7), vec![0.9, 0.1]);
    assert_eq!(column(b, 8), vec![0.1, 0.9]);
}

/// Phase 2, a waiting hand-over: sent from (8, 0) at +2 per frame, it is expected at (10, 0)
/// one frame later; a new track of B at (10.1, 0) (d² = 0.01/(3·0.09); from (8, 0) it would
/// be 24.5, outside the gate) takes its column and learns its identities, and nothing is
/// queried.
#[test]
fn a_new_track_takes_the_extrapolated_hand_over() {
    let c = pair_config();
    let records = vec![vec![frame_of(&[])], vec![frame_of(&[(5, 10.1, 0.0)])]];
    let obs = quiet(2, 1);
    let inp = Inputs::new(&records, &obs, &[], &c).expect("inputs");
    let mut layer = Layer::new(2);
    layer.nodes[1].pending.push(Pending {
        from: 0,
        position: Vec2::new(8.0, 0.0),
        velocity: Vec2::new(2.0, 0.0),
        age: 0,
        identities: vec![ID_A, ID_B],
        column: vec![0.7, 0.3],
    });
    layer.start_new_tracks(&inp, 0).expect("phase 2");
    let b = &layer.nodes[1].beliefs;
    assert_eq!(b.identities(), &[ID_A, ID_B]);
    assert_eq!(column(b, 5), vec![0.7, 0.3]);
    assert!(layer.nodes[1].pending.is_empty());
    assert_eq!(
        layer.run.events[0].kind,
        EventKind::HandOverReceived { from: 0 }
    );
    assert_eq!((layer.run.bytes_exchanged, layer.run.bytes_raw), (0, 0));
}

/// Phase 2, a neighbour's track: B's new track at (9.2, 0) matches A's track 1 at (9, 0) and
/// takes its column. A's reply to B's query holds track 1 only (track 2 at the origin is
/// outside B's range): label, 2 coordinates and 2 non-zero (identity, probability) pairs,
/// 8 · 7 = 56 bytes; raw, A would send its 2 measurements inside B's range, 2 · 24 = 48.
#[test]
fn a_new_track_adopts_a_neighbours_column_and_the_query_is_counted() {
    let c = pair_config();
    let records = vec![
        vec![frame_of(&[(1, 9.0, 0.0), (2, 0.0, 0.0)])],
        vec![frame_of(&[(5, 9.2, 0.0)])],
    ];
    let mut obs = quiet(2, 1);
    obs.scans[0][0].points = vec![
        Vec2::new(9.0, 0.0),
        Vec2::new(0.0, 0.0),
        Vec2::new(6.0, 0.0),
    ];
    let inp = Inputs::new(&records, &obs, &[], &c).expect("inputs");
    let mut layer = Layer::new(2);
    layer.nodes[0].beliefs = beliefs(&[(1, [0.6, 0.4]), (2, [0.4, 0.6])]);
    layer.start_new_tracks(&inp, 0).expect("phase 2");
    assert_eq!(column(&layer.nodes[1].beliefs, 5), vec![0.6, 0.4]);
    assert_eq!(layer.run.events.len(), 1);
    assert_eq!(layer.run.events[0].kind, EventKind::Adopted { from: 0 });
    assert_eq!((layer.run.bytes_exchanged, layer.run.bytes_raw), (56, 48));
}

/// Phase 2, no hand-over and no neighbour: a track of a target seen for the first time
/// gets its identity with certainty (twice, for two targets); a track of clutter, and a
/// second track of an announced target, get the uniform column over the two announced
/// identities. Before anything is announced, an
/// unknown track is left out.
#[test]
fn first_appearances_are_announced_and_unknown_tracks_are_uniform() {
    let c = DmtimConfig {
        sensors: vec![spec("A", 0.0)],
        ..DmtimConfig::default()
    };
    let truth: Vec<TruthTarget> = [10, 11]
        .map(|i| TruthTarget {
            identity: IdentityId(i),
            first_frame: 0,
            positions: vec![Vec2::zeros(); 2],
        })
        .into();
    let early = frame_of(&[(4, 3.0, 3.0)]);
    let mut f = frame_of(&[(1, 0.0, 0.0), (2, 5.0, 0.0), (3, -5.0, 0.0), (5, 0.5, 0.0)]);
    f.origins = vec![Some(0), Some(1), None, Some(0)];
    let records = vec![vec![early, f]];
    let obs = quiet(1, 2);
    let inp = Inputs::new(&records, &obs, &truth, &c).expect("inputs");
    let mut layer = Layer::new(1);
    layer.start_new_tracks(&inp, 0).expect("phase 2");
    assert_eq!(layer.nodes[0].beliefs.n_tracks(), 0);
    assert!(layer.run.events.is_empty());
    layer.start_new_tracks(&inp, 1).expect("phase 2");
    let b = &layer.nodes[0].beliefs;
    assert_eq!(b.identities(), &[IdentityId(10), IdentityId(11)]);
    assert_eq!(column(b, 1), vec![1.0, 0.0]);
    assert_eq!(column(b, 2), vec![0.0, 1.0]);
    assert_eq!(column(b, 3), vec![0.5, 0.5]);
    assert_eq!(column(b, 5), vec![0.5, 0.5]);
    let kinds: Vec<&EventKind> = layer.run.events.iter().map(|e| &e.kind).collect();
    assert_eq!(
        kinds,
        [
            &EventKind::NewTarget {
                identity: IdentityId(10)
            },
            &EventKind::NewTarget {
                identity: IdentityId(11)
            },
            &EventKind::Unknown,
            &EventKind::Unknown
        ]
    );
}

/// Phase 2, expiry: with a time to live of 2 frames an unmatched hand-over survives two
/// frames (ages 1 and 2) and is dropped in the third.
#[test]
fn an_unmatched_hand_over_expires_after_its_time_to_live() {
    let mut c = DmtimConfig {
        sensors: vec![spec("A", 0.0)],
        ..DmtimConfig::default()
    };
    c.handover_ttl_frames = 2;
    let records = vec![vec![frame_of(&[]); 3]];
    let obs = quiet(1, 3);
    let inp = Inputs::new(&records, &obs, &[], &c).expect("inputs");
    let mut layer = Layer::new(1);
    layer.nodes[0].pending.push(Pending {
        from: 1,
        position: Vec2::zeros(),
        velocity: Vec2::zeros(),
        age: 0,
        identities: vec![ID_A],
        column: vec![1.0],
    });
    let mut ages = Vec::new();
    for frame in 0..3 {
        layer.start_new_tracks(&inp, frame).expect("phase 2");
        ages.push(
            layer.nodes[0]
                .pending
                .iter()
                .map(|p| p.age)
                .collect::<Vec<_>>(),
        );
    }
    assert_eq!(ages, vec![vec![1], vec![2], vec![]]);
}

/// A read's information vector, by hand: over (A, B, C) with error rate 0.1 a read of A has
/// likelihood (0.9, 0.05, 0.05); the posterior from (0.5, 0.5, 0) is (0.45, 0.025, 0)/0.475
/// = (18/19, 1/19, 0); a read contradicting a certain column falls back to the likelihood;
/// with one identity the read is certain.
#[test]
fn read_information_is_the_likelihood_or_the_posterior() {
    let ids = vec![ID_A, ID_B, IdentityId(3)];
    let b = BeliefMatrix::from_rows(
        ids,
        vec![TrackId(1), TrackId(2)],
        &[vec![0.5, 0.0], vec![0.5, 0.0], vec![0.0, 1.0]],
    )
    .expect("valid");
    let mut c = DmtimConfig::default();
    c.local_info.error_rate = 0.1;
    c.read_update = ReadUpdate::Replace;
    let info = read_information(&b, TrackId(1), ID_A, &c).expect("info");
    assert!(close(&info, &[0.9, 0.05, 0.05], 1e-15));
    c.read_update = ReadUpdate::Posterior;
    let info = read_information(&b, TrackId(1), ID_A, &c).expect("info");
    assert!(close(&info, &[18.0 / 19.0, 1.0 / 19.0, 0.0], 1e-15));
    c.local_info.error_rate = 0.0;
    let info = read_information(&b, TrackId(2), ID_A, &c).expect("info");
    assert_eq!(info, vec![1.0, 0.0, 0.0]);
    let one = BeliefMatrix::known(&[(ID_A, TrackId(1))]).expect("valid");
    assert_eq!(
        read_information(&one, TrackId(1), ID_A, &c).expect("info"),
        vec![1.0]
    );
}

/// Phase 3: two tracks, each A or B with probability ½, H(B) = 2 ln 2. A certain read of B
/// on track 1 sets track 1's column to e_B; keeping each identity's mass 1, Sinkhorn gives
/// track 2 e_A, and H(B) = 0. The first such read is the snapshot. A read whose measurement
/// no track in the matrix holds is ignored.
#[test]
fn a_read_sets_the_read_identity_on_its_track() {
    let c = DmtimConfig {
        sensors: vec![spec("A", 0.0)],
        ..DmtimConfig::default()
    };
    let mut f = frame_of(&[(1, 0.0, 0.0), (2, 5.0, 0.0)]);
    f.read_tracks = vec![Some(1), Some(9), None];
    let records = vec![vec![f]];
    let mut obs = quiet(1, 1);
    obs.scans[0][0].reads = (0..3)
        .map(|point| Read {
            position: Vec2::zeros(),
            identity: ID_B,
            point,
            correct: true,
        })
        .collect();
    let inp = Inputs::new(&records, &obs, &[], &c).expect("inputs");
    let mut layer = Layer::new(1);
    layer.nodes[0].beliefs = beliefs(&[(1, [0.5, 0.5]), (2, [0.5, 0.5])]);
    layer.take_local_information(&inp, 0).expect("phase 3");
    let b = &layer.nodes[0].beliefs;
    assert!(close(&column(b, 1), &[0.0, 1.0], 1e-9));
    assert!(close(&column(b, 2), &[1.0, 0.0], 1e-9));
    assert_eq!(layer.run.events.len(), 1);
    let EventKind::LocalInformation {
        identity,
        rule,
        entropy_before_nats,
        entropy_after_nats,
        ..
    } = layer.run.events[0].kind
    else {
        panic!("{:?}", layer.run.events[0].kind);
    };
    assert_eq!((identity, rule), (ID_B, ReadRule::Scaled));
    assert!((entropy_before_nats - 2.0 * 2.0f64.ln()).abs() < 1e-12);
    assert!(entropy_after_nats.abs() < 1e-9);
    let snap = layer.run.snapshot.as_ref().expect("snapshot");
    assert_eq!(column(&snap.before, 1), vec![0.5, 0.5]);
}

/// Phase 4 with the arithmetic-mean criterion: A's track 1 (0.9, 0.1) at (9, 0) matches B's
/// track 5 (0.5, 0.5) at (9.1, 0), so its column becomes (0.7, 0.3) and Sinkhorn rescales
/// A's matrix [[0.7, 0.1], [0.3, 0.9]] to a doubly stochastic [[x, 1 − x], [1 − x, x]] with
/// the same cross ratio: x²/(1 − x)² = 0.63/0.03 = 21. Each query's reply is one track, 56
/// bytes, against one measurement, 24, raw. With B's track at (7, 0) (d² = 22 > 13.8)
/// nothing is fused but the queries are still paid; off the exchange period nothing happens.
#[test]
fn the_exchange_fuses_matched_tracks_and_counts_the_replies() {
    let mut c = pair_config();
    c.fusion = Some(FusionConfig {
        criterion: FusionCriterion::KlSumArithmetic,
        ..FusionConfig::default()
    });
    let start = beliefs(&[(1, [0.9, 0.1]), (2, [0.1, 0.9])]);
    for (x5, matched) in [(9.1, true), (7.0, false)] {
        let records = vec![
            vec![frame_of(&[(1, 9.0, 0.0), (2, 0.0, 0.0)])],
            vec![frame_of(&[(5, x5, 0.0)])],
        ];
        let mut obs = quiet(2, 1);
        obs.scans[0][0].points = vec![Vec2::new(9.0, 0.0), Vec2::new(0.0, 0.0)];
        obs.scans[1][0].points = vec![Vec2::new(x5, 0.0)];
        let inp = Inputs::new(&records, &obs, &[], &c).expect("inputs");
        let mut layer = Layer::new(2);
        layer.nodes[0].beliefs = start.clone();
        layer.nodes[1].beliefs = beliefs(&[(5, [0.5, 0.5])]);
        layer.exchange(&inp, 0).expect("phase 4");
        assert_eq!((layer.run.bytes_exchanged, layer.run.bytes_raw), (112, 48));
        let b = &layer.nodes[0].beliefs;
        if matched {
            let x = 21f64.sqrt() / (1.0 + 21f64.sqrt());
            assert!(close(&column(b, 1), &[x, 1.0 - x], 1e-6), "{b:?}");
            assert!(close(&column(b, 2), &[1.0 - x, x], 1e-6), "{b:?}");
        } else {
            assert_eq!(b, &start);
        }
    }
    c.exchange_every = 2;
    let records = vec![vec![frame_of(&[]); 2], vec![frame_of(&[]); 2]];
    let obs = quiet(2, 2);
    let inp = Inputs::new(&records, &obs, &[], &c).expect("inputs");
    let mut layer = Layer::new(2);
    layer.exchange(&inp, 1).expect("phase 4");
    assert_eq!((layer.run.bytes_exchanged, layer.run.bytes_raw), (0, 0));
}

/// Phase 5: velocities are the step from the previous estimate (zero for a new label);
/// track 1 (argmax A, measured from target A) is right, track 2 (argmax B, from A) wrong,
/// track 3 (no origin this frame) not scored; H(B) = Σ of the column entropies.
#[test]
fn remember_and_score_by_hand() {
    let c = DmtimConfig {
        sensors: vec![spec("A", 0.0)],
        ..DmtimConfig::default()
    };
    let truth = vec![TruthTarget {
        identity: ID_A,
        first_frame: 0,
        positions: vec![Vec2::zeros()],
    }];
    let mut f = frame_of(&[(1, 1.0, 2.0), (2, 5.0, 5.0), (3, 7.0, 0.0)]);
    f.origins = vec![Some(0), Some(0), None];
    let records = vec![vec![f]];
    let obs = quiet(1, 1);
    let inp = Inputs::new(&records, &obs, &truth, &c).expect("inputs");
    let mut layer = Layer::new(1);
    layer.nodes[0].beliefs = beliefs(&[(1, [0.8, 0.2]), (2, [0.2, 0.8]), (3, [1.0, 0.0])]);
    layer.nodes[0]
        .last
        .insert(1, (Vec2::zeros(), Vec2::zeros()));
    layer.nodes[0]
        .last
        .insert(4, (Vec2::zeros(), Vec2::zeros()));
    layer.remember_and_score(&inp, 0);
    let last = &layer.nodes[0].last;
    assert_eq!(last.keys().copied().collect::<Vec<_>>(), vec![1, 2, 3]);
    assert_eq!(last[&1], (Vec2::new(1.0, 2.0), Vec2::new(1.0, 2.0)));
    assert_eq!(last[&2], (Vec2::new(5.0, 5.0), Vec2::zeros()));
    assert_eq!(layer.run.correct, vec![(1, 2)]);
    let h = -2.0 * (0.8f64 * 0.8f64.ln() + 0.2 * 0.2f64.ln());
    assert!((layer.run.entropy_nats[0] - h).abs() < 1e-12);
}

/// Interaction clusters by single linkage at 3: 1–3 and 3–4 are 2 apart (1–4 is 4 apart but
/// chained), 2–5 are 2.5 apart, 6 is alone.
#[test]
fn clusters_link_chains_of_close_estimates() {
    let est: Vec<(u64, Vec2)> = [
        (1, 0.0, 0.0),
        (2, 10.0, 0.0),
        (3, 2.0, 0.0),
        (4, 4.0, 0.0),
        (5, 10.0, 2.5),
        (6, 30.0, 0.0),
    ]
    .iter()
    .map(|&(l, x, y)| (l, Vec2::new(x, y)))
    .collect();
    assert_eq!(clusters(&est, 3.0), vec![vec![1, 3, 4], vec![2, 5]]);
    assert!(clusters(&est, 1.0).is_empty());
}

/// Each group of checks reports its own field, and the first bad field wins.
#[test]
fn config_checks_name_the_first_bad_field() {
    let name = |c: &DmtimConfig| match c.check() {
        Err(crate::Error::Model(tracker_model::Error::InvalidParameter { name, .. })) => name,
        other => panic!("{other:?}"),
    };
    let mut c = pair_config();
    c.sensors[1].centre[0] = f64::NAN;
    assert_eq!(name(&c), "sensors.centre");
    let mut c = pair_config();
    c.sensing.clutter_per_scan = -1.0;
    assert_eq!(name(&c), "sensing.clutter_per_scan");
    let mut c = pair_config();
    c.join_samples = 0;
    assert_eq!(name(&c), "join_samples");
    let mut c = pair_config();
    c.handover_margin_m = f64::INFINITY;
    assert_eq!(name(&c), "handover_margin_m");
    c.read_doubt = 0.0;
    c.local_info.sensors = vec![2];
    assert_eq!(name(&c), "handover_margin_m");
    c.handover_margin_m = 3.0;
    assert_eq!(name(&c), "read_doubt");
    c.read_doubt = 1.0;
    assert_eq!(name(&c), "local_info.sensors");
    c.local_info.sensors = vec![1];
    assert!(c.check().is_ok());
}

/// One sensor's tracker on two targets flying side by side 2 apart (inside the interaction
/// distance 3) for 6 frames, then splitting apart at ±1 per frame: no mixing while they are
/// together, exactly one mixing of both tracks once they are more than 3 apart, built from
/// samples (their pre pieces are in the window). Each target's read goes to the track
/// holding the plot it came with, and each estimate's origin is its target.
#[test]
fn tracking_mixes_the_identities_of_tracks_that_came_close() {
    let mut c = config();
    c.sensors = vec![SensorSpec {
        name: "A".into(),
        centre: [10.0, 0.0],
        range_m: 30.0,
    }];
    let mut m = c.mcmcda.clone();
    m.volume = std::f64::consts::PI * 900.0;
    let model = m.check().expect("model");
    let y = |frame: usize| {
        if frame < 6 {
            1.0
        } else {
            1.0 + (frame - 5) as f64
        }
    };
    let scans: Vec<SensorScan> = (0..12)
        .map(|frame| {
            let x = frame as f64;
            SensorScan {
                points: vec![Vec2::new(x, y(frame)), Vec2::new(x, -y(frame))],
                origins: vec![Some(0), Some(1)],
                reads: [ID_A, ID_B]
                    .iter()
                    .enumerate()
                    .map(|(point, &identity)| Read {
                        position: Vec2::zeros(),
                        identity,
                        point,
                        correct: true,
                    })
                    .collect(),
            }
        })
        .collect();
    let out = crate::track_sensor(0, model, c.online, &scans, &c, 3).expect("tracks");
    let split = (0..12).find(|&f| 2.0 * y(f) >= 3.0).expect("they split");
    let mut mixings = Vec::new();
    for (frame, f) in out.iter().enumerate() {
        if frame < split {
            assert!(f.mixings.is_empty(), "frame {frame}: {:?}", f.mixings);
        }
        mixings.extend(f.mixings.iter().map(|m| (frame, m.clone())));
        for (k, (l, p)) in f.estimates.iter().enumerate() {
            let target = usize::from(p.y < 0.0);
            assert_eq!(f.origins[k], Some(target), "frame {frame}");
            assert_eq!(f.read_tracks[target], Some(*l), "frame {frame}");
        }
    }
    assert_eq!(mixings.len(), 1, "{mixings:?}");
    let (_, m) = &mixings[0];
    let mut labels = m.labels.clone();
    labels.sort_unstable();
    let mut reported: Vec<u64> = out[11].estimates.iter().map(|(l, _)| *l).collect();
    reported.sort_unstable();
    assert_eq!(labels, reported);
    assert!(!m.uniform_fallback);
}
