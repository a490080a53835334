//! Unit tests: expected values come from closed forms (line intersections, Gaussian moments)
//! or from hand-built buffers, never from the code under test.

use nalgebra::Matrix2;
use tracker_model::{
    ConstantVelocity2, LikelihoodGrid, Region2, SensorPose, TrackSet, Vec2, wrap_angle_rad,
};

use crate::*;

const DEG: f64 = std::f64::consts::PI / 180.0;

fn pose(x: f64, y: f64, heading_deg: f64) -> SensorPose {
    SensorPose {
        position: Vec2::new(x, y),
        heading_rad: heading_deg * DEG,
    }
}

/// Values of a Gaussian bump of width `sigma_rad` at world bearing `bearing_rad`, for `node`'s
/// layout.
fn bump(node: &SensorNode, bearing_rad: f64, sigma_rad: f64) -> Vec<f64> {
    let n = node.shape.n_bins();
    (0..n)
        .map(|i| {
            let rel = match node.shape {
                ProfileShape::FullCircle { n_bins } => {
                    i as f64 * std::f64::consts::TAU / n_bins as f64
                }
                ProfileShape::Sector {
                    start_rad,
                    step_rad,
                    ..
                } => start_rad + i as f64 * step_rad,
            };
            let off = wrap_angle_rad(node.pose.heading_rad + rel - bearing_rad);
            (-0.5 * (off / sigma_rad).powi(2)).exp()
        })
        .collect()
}

fn bearing_to(node: &SensorNode, target: Vec2) -> f64 {
    let d = target - node.pose.position;
    d.y.atan2(d.x)
}

fn region() -> Region2 {
    Region2::new(Vec2::new(0.0, 0.0), Vec2::new(35.0, 20.0)).expect("valid region")
}

fn fusion_config(rule: FusionRule) -> FusionConfig {
    FusionConfig {
        region: region(),
        cell_size_m: 0.5,
        max_range_m: None,
        min_range_m: 0.5,
        range_fade: None,
        rule,
        modalities: Modalities::Both,
        peaks: PeakExtraction::default(),
    }
}

fn scheduler() -> SchedulerConfig {
    SchedulerConfig {
        rate_hz: 10.0,
        start_s: 0.0,
        staleness_s: 0.06,
        buffer_capacity: 8,
    }
}

fn report(sensor: usize, t: f64, values: Vec<f64>) -> Report {
    Report {
        sensor,
        local_time_s: t,
        values,
    }
}

// ---------------------------------------------------------------- buffers and scheduler

#[test]
fn buffer_sorts_out_of_order_arrivals_and_drops_the_oldest() {
    let mut b = SensorBuffer::new(3).expect("capacity 3");
    assert_eq!(b.insert(0.3, vec![3.0]), Arrival::Stored);
    assert_eq!(b.insert(0.1, vec![1.0]), Arrival::Stored);
    assert_eq!(b.insert(0.2, vec![2.0]), Arrival::Stored);
    let times: Vec<f64> = b.entries().map(|e| e.time_s).collect();
    assert_eq!(times, vec![0.1, 0.2, 0.3]);
    // Full: a newer late report goes to its place and the oldest leaves.
    assert_eq!(b.insert(0.25, vec![2.5]), Arrival::StoredDroppingOldest);
    let times: Vec<f64> = b.entries().map(|e| e.time_s).collect();
    assert_eq!(times, vec![0.2, 0.25, 0.3]);
    // Older than everything in a full buffer: dropped.
    assert_eq!(b.insert(0.05, vec![0.5]), Arrival::DroppedTooOld);
    // Same time stamp: replaced.
    assert_eq!(b.insert(0.25, vec![9.0]), Arrival::Replaced);
    assert_eq!(b.nearest(0.26, 0.1).map(|e| e.values[0]), Some(9.0));
    // Nearest on either side; a tie goes to the later report.
    assert_eq!(b.nearest(0.21, 1.0).map(|e| e.time_s), Some(0.2));
    assert_eq!(b.nearest(0.29, 1.0).map(|e| e.time_s), Some(0.3));
    assert_eq!(b.nearest(0.275, 1.0).map(|e| e.time_s), Some(0.3));
    assert!(SensorBuffer::new(0).is_err());
}

#[test]
fn scheduler_leaves_out_a_sensor_with_nothing_recent_enough() {
    let sensors = vec![
        SensorNode::audio("a", pose(0.0, 0.0, 0.0), 36),
        SensorNode::audio("b", pose(35.0, 0.0, 0.0), 36),
    ];
    let mut node = FusionNode::new(sensors, scheduler()).expect("valid node");
    node.receive(report(0, 0.98, vec![1.0; 36])).expect("ok");
    // Sensor 1's last report is 0.1 s before tick 10 (t = 1.0): staler than 0.06 s.
    node.receive(report(1, 0.9, vec![1.0; 36])).expect("ok");
    let snap = node.snapshot(10);
    assert!((snap.time_s - 1.0).abs() < 1e-12);
    let used: Vec<usize> = snap.selected.iter().map(|s| s.sensor).collect();
    assert_eq!(used, vec![0]);
    // At tick 9 (t = 0.9) both are within the limit? Sensor 0's 0.98 is 0.08 away: left out.
    let used: Vec<usize> = node.snapshot(9).selected.iter().map(|s| s.sensor).collect();
    assert_eq!(used, vec![1]);
    // Left out means absent from the fusion, not a zero grid: the fused grid equals sensor
    // 0's grid alone, which a zero grid would have vetoed under the plain product.
    let config = fusion_config(FusionRule::Product { floor: 0.0 });
    let fused = fuse_snapshot(node.sensors(), &node.snapshot(10), &config).expect("fuses");
    assert_eq!(fused.used, vec![0]);
    assert!(fused.grid.values().iter().any(|v| *v > 0.0));
}

#[test]
fn scheduler_picks_the_nearest_report_whatever_the_arrival_order() {
    let sensors = vec![SensorNode::audio("a", pose(0.0, 0.0, 0.0), 4)];
    let mut node = FusionNode::new(sensors, scheduler()).expect("valid node");
    for (t, v) in [(0.31, 3.0), (0.09, 1.0), (0.22, 2.0), (0.12, 1.5)] {
        node.receive(report(0, t, vec![v; 4])).expect("ok");
    }
    let pick = |k| node.snapshot(k).selected.first().map(|s| s.values[0]);
    assert_eq!(pick(1), Some(1.0)); // 0.1: 0.09 beats 0.12
    assert_eq!(pick(2), Some(2.0)); // 0.2: 0.22
    assert_eq!(pick(3), Some(3.0)); // 0.3: 0.31
    assert_eq!(pick(5), None); // 0.5: nothing within 0.06 s
}

#[test]
fn clock_offsets_are_removed() {
    let mut a = SensorNode::audio("a", pose(0.0, 0.0, 0.0), 4);
    a.clock_offset_s = 100.0; // its clock reads fusion time + 100 s
    let mut b = SensorNode::audio("b", pose(1.0, 0.0, 0.0), 4);
    b.clock_offset_s = -0.5;
    let mut node = FusionNode::new(vec![a, b], scheduler()).expect("valid node");
    node.receive(report(0, 100.2, vec![1.0; 4])).expect("ok");
    node.receive(report(1, -0.3, vec![1.0; 4])).expect("ok");
    let snap = node.snapshot(2); // t = 0.2
    let times: Vec<(usize, f64)> = snap.selected.iter().map(|s| (s.sensor, s.time_s)).collect();
    assert_eq!(times.len(), 2);
    assert!(
        times.iter().all(|(_, t)| (t - 0.2).abs() < 1e-9),
        "{times:?}"
    );
    assert!(node.snapshot(1002).selected.is_empty());
}

#[test]
fn bad_reports_are_errors() {
    let sensors = vec![SensorNode::audio("a", pose(0.0, 0.0, 0.0), 4)];
    let mut node = FusionNode::new(sensors, scheduler()).expect("valid node");
    assert!(matches!(
        node.receive(report(3, 0.0, vec![1.0; 4])),
        Err(Error::UnknownSensor { sensor: 3, .. })
    ));
    assert!(matches!(
        node.receive(report(0, 0.0, vec![1.0; 5])),
        Err(Error::ProfileLength { got: 5, .. })
    ));
    assert!(matches!(
        node.receive(report(0, 0.0, vec![1.0, f64::NAN, 1.0, 1.0])),
        Err(Error::BadReport { index: 1, .. })
    ));
    assert!(matches!(
        node.receive(report(0, f64::INFINITY, vec![1.0; 4])),
        Err(Error::BadReport { .. })
    ));
    assert!(node.receive(report(0, 0.0, vec![-1.0; 4])).is_err());
    assert!(FusionNode::new(Vec::new(), scheduler()).is_err());
    let bad = SchedulerConfig {
        rate_hz: 0.0,
        ..scheduler()
    };
    assert!(bad.check().is_err());
    assert!(
        fusion_config(FusionRule::Product { floor: 1.0 })
            .check()
            .is_err()
    );
    assert!(
        fusion_config(FusionRule::Product { floor: -0.1 })
            .check()
            .is_err()
    );
}

// ---------------------------------------------------------------- fusion and peaks

/// Closed-form intersection of the rays from p1 at θ1 and from p2 at θ2.
fn intersection(p1: Vec2, t1: f64, p2: Vec2, t2: f64) -> Vec2 {
    let (u1, u2) = (Vec2::new(t1.cos(), t1.sin()), Vec2::new(t2.cos(), t2.sin()));
    // p1 + a u1 = p2 + b u2 → a = ((p2 − p1) × u2) / (u1 × u2).
    let cross = |a: Vec2, b: Vec2| a.x * b.y - a.y * b.x;
    p1 + u1 * (cross(p2 - p1, u2) / cross(u1, u2))
}

#[test]
fn two_bearings_fuse_to_their_intersection_under_both_rules() {
    let s1 = SensorNode::audio("a", pose(2.0, 1.0, 0.0), 360);
    let s2 = SensorNode::audio("b", pose(33.0, 1.5, 0.0), 360);
    for (t1, t2) in [(30.0, 150.0), (20.0, 150.0), (35.0, 130.0)] {
        let (t1, t2) = (t1 * DEG, t2 * DEG);
        let truth = intersection(s1.pose.position, t1, s2.pose.position, t2);
        let mut node =
            FusionNode::new(vec![s1.clone(), s2.clone()], scheduler()).expect("valid node");
        node.receive(report(0, 0.0, bump(&s1, t1, 2.0 * DEG)))
            .expect("ok");
        node.receive(report(1, 0.0, bump(&s2, t2, 2.0 * DEG)))
            .expect("ok");
        for rule in [
            FusionRule::WeightedSum {
                scaling: SumScaling::Max,
            },
            FusionRule::WeightedSum {
                scaling: SumScaling::Sum,
            },
            FusionRule::Product { floor: 0.01 },
        ] {
            let mut config = fusion_config(rule);
            config.peaks.moment_fraction = 0.8;
            config.peaks.moment_radius_m = 1.0;
            let fused = fuse_snapshot(node.sensors(), &node.snapshot(0), &config).expect("fuses");
            let best = fused.peaks.first().expect("a peak");
            let err = (best.position - truth).norm();
            assert!(
                err < 0.25,
                "{rule:?}: peak {:?} vs intersection {truth:?} ({err} m)",
                best.position
            );
            assert!((fused.grid.values().iter().sum::<f64>() - 1.0).abs() < 1e-9);
        }
    }
}

#[test]
fn the_floor_keeps_a_sensor_that_misses_from_vetoing_the_target() {
    let s1 = SensorNode::audio("a", pose(2.0, 1.0, 0.0), 360);
    let s2 = SensorNode::audio("b", pose(33.0, 1.5, 0.0), 360);
    let s3 = SensorNode::audio("c", pose(17.0, 19.0, 0.0), 360);
    let (t1, t2) = (30.0 * DEG, 150.0 * DEG);
    let truth = intersection(s1.pose.position, t1, s2.pose.position, t2);
    let mut node =
        FusionNode::new(vec![s1.clone(), s2.clone(), s3.clone()], scheduler()).expect("valid node");
    node.receive(report(0, 0.0, bump(&s1, t1, 2.0 * DEG)))
        .expect("ok");
    node.receive(report(1, 0.0, bump(&s2, t2, 2.0 * DEG)))
        .expect("ok");
    // Sensor c points 60° away from the target and is exactly zero there (a sector of 20
    // bins covering ±10° about its wrong bearing, zero elsewhere).
    let wrong = bearing_to(&s3, truth) + 60.0 * DEG;
    let values: Vec<f64> = bump(&s3, wrong, 2.0 * DEG)
        .into_iter()
        .map(|v| if v > 1e-3 { v } else { 0.0 })
        .collect();
    node.receive(report(2, 0.0, values)).expect("ok");
    let peak_error = |floor: f64| {
        let config = fusion_config(FusionRule::Product { floor });
        let fused = fuse_snapshot(node.sensors(), &node.snapshot(0), &config).expect("fuses");
        let cell = fused.grid.cell_of(&truth).expect("inside");
        let at_truth = fused.grid.value(cell.0, cell.1);
        let best = fused.peaks.first().map(|p| (p.position - truth).norm());
        (at_truth, best)
    };
    // Plain product: sensor c's zero vetoes the target's cell.
    let (v0, _) = peak_error(0.0);
    assert!(v0 < 1e-12);
    // With a floor of 0.2 the target survives as the strongest peak: there the floored
    // product is 1 · 1 · 0.2, the best a cell on c's line alone can do is 0.2 · 0.2 · 1.
    let (v, err) = peak_error(0.2);
    assert!(v > 0.0);
    assert!(err.is_some_and(|e| e < 0.5), "{err:?}");
}

#[test]
fn peak_covariance_is_the_shape_second_moment() {
    // A Gaussian blob with known covariance, sampled on 0.1 m cells: the discrete second
    // moment equals Σ (the sampling error is exponentially small for σ ≫ s), and the
    // extraction adds the cell's s²/12.
    let region = Region2::new(Vec2::new(0.0, 0.0), Vec2::new(20.0, 20.0)).expect("region");
    let s = 0.1;
    let (a, b, rho) = (1.2f64, 0.6f64, 0.5f64);
    let sigma = Matrix2::new(a * a, rho * a * b, rho * a * b, b * b);
    let inv = sigma.try_inverse().expect("invertible");
    let centre = Vec2::new(10.0, 10.0);
    let grid = LikelihoodGrid::from_fn(region, s, |q| {
        let d = q - centre;
        (-0.5 * (d.transpose() * inv * d)[(0, 0)]).exp()
    })
    .expect("grid");
    let config = PeakExtraction {
        relative_threshold: 0.5,
        min_contrast: 0.0,
        suppression_radius_m: 3.0,
        moment_radius_m: 8.0,
        moment_fraction: 0.0,
        max_peaks: 4,
        border_cells: 0,
        explain_away_deg: 0.0,
    };
    let peaks = extract_peaks(&grid, &config).expect("peaks");
    assert_eq!(peaks.len(), 1);
    let expected = sigma + Matrix2::identity() * s * s / 12.0;
    let diff = (peaks[0].covariance - expected).abs().max();
    assert!(diff < 1e-3, "{} vs {expected}", peaks[0].covariance);
    assert!((peaks[0].position - centre).norm() < 1e-6);
    // min_contrast: a flat grid yields no measurement.
    let flat = LikelihoodGrid::from_fn(region, 1.0, |q| 1.0 + 1e-3 * (q.x * 7.0).sin())
        .expect("flat grid");
    let mut c = config;
    c.min_contrast = 2.0;
    assert!(extract_peaks(&flat, &c).expect("ok").is_empty());
}

// ---------------------------------------------------------------- tracking

/// The Table 1 layout in miniature: six full-circle (audio-like) nodes and three sector
/// (camera-like) nodes either side of a road along y = 10.
fn road_sensors() -> Vec<SensorNode> {
    let mut sensors = Vec::new();
    for (i, (x, y)) in [
        (4.0, 3.0),
        (17.5, 3.0),
        (31.0, 3.0),
        (4.0, 17.0),
        (17.5, 17.0),
        (31.0, 17.0),
    ]
    .into_iter()
    .enumerate()
    {
        sensors.push(SensorNode::audio(format!("a{i}"), pose(x, y, 0.0), 36));
    }
    for (i, (x, y, h)) in [(5.0, 0.5, 45.0), (30.0, 0.5, 135.0), (17.5, 19.5, -90.0)]
        .into_iter()
        .enumerate()
    {
        sensors.push(SensorNode {
            name: format!("v{i}"),
            kind: SensorKind::Video,
            pose: pose(x, y, h),
            shape: ProfileShape::Sector {
                start_rad: -40.0 * DEG,
                step_rad: 0.5 * DEG,
                n_bins: 160,
            },
            clock_offset_s: 0.0,
            weight: 1.0,
            exponent: 1.0,
            lobes: None,
        });
    }
    sensors
}

fn vehicle(t: f64) -> Vec2 {
    Vec2::new(-3.0 + 11.0 * t, 10.0)
}

/// Noise-free reports of one vehicle, every 0.05 s from every node.
fn noise_free_reports(sensors: &[SensorNode], duration_s: f64) -> Vec<Report> {
    let mut reports = Vec::new();
    for (i, s) in sensors.iter().enumerate() {
        let width = match s.kind {
            SensorKind::Audio => 12.0 * DEG,
            SensorKind::Video => 1.5 * DEG,
        };
        for k in 0..=(duration_s / 0.05).round() as u32 {
            let t = 0.05 * f64::from(k);
            let values = bump(s, bearing_to(s, vehicle(t)), width);
            reports.push(report(i, t, values));
        }
    }
    reports
}

fn av_config(rule: FusionRule) -> AvConfig {
    AvConfig {
        scheduler: SchedulerConfig {
            rate_hz: 10.0,
            start_s: 0.0,
            staleness_s: 0.05,
            buffer_capacity: 16,
        },
        fusion: fusion_config(rule),
        tracker: TrackerConfig {
            mcmcda: mcmcda::McmcdaConfig {
                volume: 700.0,
                births_per_scan: 0.05,
                clutter_per_scan: 0.5,
                p_disappear: 0.01,
                p_detect: 0.9,
                motion: ConstantVelocity2::mcmcda(0.1, 1.0).expect("valid"),
                measurement_noise: Matrix2::identity() * 0.1,
                max_speed: 20.0,
                ..mcmcda::McmcdaConfig::default()
            },
            online: mcmcda::OnlineConfig {
                window: 8,
                samples_per_scan: 300,
                ..mcmcda::OnlineConfig::default()
            },
            seed: 11,
            peak_scores: None,
        },
    }
}

/// Mean distance between the track and the vehicle over the ticks the vehicle is inside the
/// region (where the truth exists).
fn mean_track_error(tracks: &TrackSet, clock: &tracker_model::FrameClock) -> f64 {
    let t = &tracks.tracks()[0];
    let errors: Vec<f64> = t
        .points()
        .iter()
        .filter_map(|p| {
            let truth = vehicle(clock.time_s(p.frame));
            region()
                .contains(&truth)
                .then(|| (p.location.position() - truth).norm())
        })
        .collect();
    errors.iter().sum::<f64>() / errors.len().max(1) as f64
}

#[test]
fn a_noise_free_pass_is_tracked_within_one_cell() {
    let sensors = road_sensors();
    let reports = noise_free_reports(&sensors, 4.0);
    for rule in [
        FusionRule::Product { floor: 0.05 },
        FusionRule::WeightedSum {
            scaling: SumScaling::Max,
        },
    ] {
        let mut config = av_config(rule);
        if let FusionRule::WeightedSum { .. } = rule {
            // The sum keeps every sensor's ridge: only the top of the crossing is a target.
            config.fusion.peaks.relative_threshold = 0.85;
        }
        let run = track_reports(sensors.clone(), reports.clone(), 40, &config).expect("runs");
        assert_eq!(run.tracks.len(), 1, "{rule:?}: {:?}", run.tracks.len());
        let err = mean_track_error(&run.tracks, &run.clock);
        assert!(
            err < 0.5,
            "{rule:?}: mean error {err} m is not below one cell"
        );
        // The track covers the pass inside the region (x from 0 to 35: t ≈ 0.27–3.45 s).
        assert!(run.tracks.tracks()[0].len() >= 25);
    }
}

#[test]
fn output_is_identical_with_one_and_two_threads() {
    let sensors = road_sensors();
    let reports = noise_free_reports(&sensors, 3.0);
    let run_with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            track_reports(
                sensors.clone(),
                reports.clone(),
                30,
                &av_config(FusionRule::Product { floor: 0.05 }),
            )
            .expect("runs")
        })
    };
    let (one, two) = (run_with(1), run_with(2));
    assert_eq!(one.tracks, two.tracks);
    assert_eq!(one.scans, two.scans);
}

#[test]
fn peak_scores_look_up_their_bin_and_reject_bad_tables() {
    let table = PeakScores {
        contrast_edges: vec![1.0, 3.0],
        log_ratios: vec![-2.0, 0.5, 3.0],
    };
    table.check().expect("valid");
    // Bins [.., 1), [1, 3), [3, ..): an edge belongs to the bin above it.
    for (c, want) in [
        (0.5, -2.0_f64),
        (1.0, 0.5),
        (2.9, 0.5),
        (3.0, 3.0),
        (100.0, 3.0),
    ] {
        let got = table.log_ratio(c).expect("valid");
        assert_eq!(got.to_bits(), want.to_bits(), "contrast {c}");
    }
    assert!(table.log_ratio(f64::NAN).is_err());
    let bad = [
        PeakScores {
            contrast_edges: vec![1.0, 3.0],
            log_ratios: vec![0.0, 0.0],
        },
        PeakScores {
            contrast_edges: vec![3.0, 1.0],
            log_ratios: vec![0.0; 3],
        },
        PeakScores {
            contrast_edges: vec![1.0],
            log_ratios: vec![0.0, f64::NAN],
        },
    ];
    for table in bad {
        assert!(table.check().is_err(), "{table:?}");
        assert!(table.log_ratio(1.0).is_err(), "{table:?}");
        let mut config = av_config(FusionRule::Product { floor: 0.05 });
        config.tracker.peak_scores = Some(table);
        assert!(AvPipeline::new(road_sensors(), &config).is_err());
    }
}

#[test]
fn peak_scores_reach_the_tracker() {
    let sensors = road_sensors();
    let reports = noise_free_reports(&sensors, 4.0);
    let run = |scores: Option<f64>| {
        let mut config = av_config(FusionRule::Product { floor: 0.05 });
        config.tracker.peak_scores = scores.map(|r| PeakScores {
            contrast_edges: Vec::new(),
            log_ratios: vec![r],
        });
        track_reports(sensors.clone(), reports.clone(), 40, &config).expect("runs")
    };
    let plain = run(None);
    assert_eq!(plain.tracks.len(), 1);
    // A ratio of 0 everywhere is the unscored posterior, to the bit.
    assert_eq!(run(Some(0.0)).tracks, plain.tracks);
    // Every peak e⁻⁵⁰ times likelier to be clutter than a vehicle: no track is worth it.
    assert!(run(Some(-50.0)).tracks.is_empty());
    // The contrast is the peak's value over the grid's mean (the grid sums to 1): an edge
    // just below the weakest peak's contrast puts every peak in the upper bin (ratio 0, the
    // plain output), an edge just above the strongest's puts every peak in the lower (−50).
    let contrasts: Vec<f64> = plain
        .scans
        .iter()
        .flat_map(|s| {
            let cells = s.grid.values().len() as f64;
            s.peaks.iter().map(move |p| p.value * cells)
        })
        .collect();
    let weakest = contrasts.iter().copied().fold(f64::INFINITY, f64::min);
    let strongest = contrasts.iter().copied().fold(0.0, f64::max);
    assert!(weakest > 1.0, "a peak stands above the grid's mean");
    let with_edge = |edge: f64| {
        let mut config = av_config(FusionRule::Product { floor: 0.05 });
        config.tracker.peak_scores = Some(PeakScores {
            contrast_edges: vec![edge],
            log_ratios: vec![-50.0, 0.0],
        });
        track_reports(sensors.clone(), reports.clone(), 40, &config).expect("runs")
    };
    assert_eq!(with_edge(0.99 * weakest).tracks, plain.tracks);
    assert!(with_edge(1.01 * strongest).tracks.is_empty());
}

#[test]
fn the_tracker_period_must_match_the_scheduler() {
    let mut config = av_config(FusionRule::WeightedSum {
        scaling: SumScaling::Max,
    });
    config.scheduler.rate_hz = 5.0;
    assert!(matches!(
        AvPipeline::new(road_sensors(), &config),
        Err(Error::PeriodMismatch { .. })
    ));
    let mut p = AvPipeline::new(
        road_sensors(),
        &av_config(FusionRule::WeightedSum {
            scaling: SumScaling::Max,
        }),
    )
    .expect("valid pipeline");
    p.process(3).expect("ok");
    assert!(matches!(p.process(2), Err(Error::TickOutOfOrder { .. })));
}

#[test]
fn the_exponent_sharpens_a_profile_in_closed_form() {
    // exp(−½(θ/σ)²)^4 = exp(−½(θ/(σ/2))²): a Gaussian bump raised to γ = 4 is the bump of half
    // the width.
    let mut node = SensorNode::audio("a", pose(0.0, 0.0, 10.0), 36);
    let broad = bump(&node, 40.0 * DEG, 30.0 * DEG);
    let narrow = bump(&node, 40.0 * DEG, 15.0 * DEG);
    node.exponent = 4.0;
    node.check().expect("a valid node");
    let profile = node.profile(broad.clone()).expect("a valid profile");
    for (got, want) in profile.values().iter().zip(&narrow) {
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
    // γ = 1 leaves the values as reported.
    node.exponent = 1.0;
    assert_eq!(
        node.profile(broad.clone()).expect("valid").values(),
        &broad[..]
    );
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        node.exponent = bad;
        assert!(node.check().is_err(), "exponent {bad} accepted");
    }
}

#[test]
fn lobe_equalisation_lifts_each_lobe_to_the_maximum_by_hand() {
    // Two lobes on a circle of 8 bins: peaks 4 (bin 1) and 1 (bin 5). Steepest ascent: the
    // valley bin 3 (0.5) has neighbours 1.0 (bin 2) and 0.8 (bin 4), so it climbs to bin 2
    // and belongs to the first lobe; bin 7 (0.1) climbs to bin 0 (2.0), the first lobe too.
    let values = [2.0, 4.0, 1.0, 0.5, 0.8, 1.0, 0.6, 0.1];
    // Lobes: bins 7, 0, 1, 2, 3 → peak 4; bins 4, 5, 6 → peak 1. With η = 0.2 (floor 0.8)
    // and β = 1 the second lobe is scaled by 4/1, the first by 1.
    let l = LobeEqualisation {
        min_fraction: 0.2,
        power: 1.0,
    };
    l.check().expect("valid");
    let mut v = values;
    l.apply(&mut v, true);
    let want = [2.0, 4.0, 1.0, 0.5, 3.2, 4.0, 2.4, 0.1];
    for (g, w) in v.iter().zip(&want) {
        assert!((g - w).abs() < 1e-12, "{v:?} vs {want:?}");
    }
    // η = 0.5 (floor 2): the second lobe is scaled by 4/2 only; β = 0.5 by (4/1)^0.5 = 2 too.
    for l in [
        LobeEqualisation {
            min_fraction: 0.5,
            power: 1.0,
        },
        LobeEqualisation {
            min_fraction: 0.2,
            power: 0.5,
        },
    ] {
        let mut v = values;
        l.apply(&mut v, true);
        let want = [2.0, 4.0, 1.0, 0.5, 1.6, 2.0, 1.2, 0.1];
        for (g, w) in v.iter().zip(&want) {
            assert!((g - w).abs() < 1e-12, "{l:?}: {v:?} vs {want:?}");
        }
    }
    // Not circular: bin 7 (0.1) has only bin 6 (0.6) beside it, so it climbs into the
    // second lobe and is scaled by 4/1; bin 0 has only bin 1 and stays in the first.
    let mut v = values;
    l.apply(&mut v, false);
    assert!(
        (v[7] - 0.4).abs() < 1e-12 && (v[0] - 2.0).abs() < 1e-12,
        "{v:?}"
    );
    // A single lobe is unchanged; an all-zero profile stays zero; bad η, β are rejected.
    let one = [0.0, 1.0, 3.0, 1.0, 0.0];
    let mut v = one;
    l.apply(&mut v, false);
    assert!(
        v.iter().zip(&one).all(|(a, b)| a.to_bits() == b.to_bits()),
        "{v:?}"
    );
    let mut z = [0.0; 4];
    l.apply(&mut z, true);
    assert!(z.iter().all(|x| x.to_bits() == 0), "{z:?}");
    for (eta, beta) in [
        (0.0, 1.0),
        (1.5, 1.0),
        (0.3, -0.1),
        (0.3, 1.5),
        (f64::NAN, 1.0),
    ] {
        let bad = LobeEqualisation {
            min_fraction: eta,
            power: beta,
        };
        assert!(bad.check().is_err(), "η {eta}, β {beta} accepted");
    }
}

#[test]
fn explaining_away_finds_the_second_target_with_the_first_removed() {
    // Three nodes, two targets, the second at 0.4 of the first's amplitude in every profile
    // (Gaussian beams of 4°). After the first peak (the strong target) is explained away, the
    // strongest residual peak is the weak target; plain NMS with κ = 0.5 sees only the
    // strong one (the weak one's product is 0.4³ ≈ 0.06 of it).
    let sensors: Vec<SensorNode> = [(5.0, 4.0), (30.0, 4.0), (17.5, 16.0)]
        .iter()
        .enumerate()
        .map(|(i, &(x, y))| SensorNode::audio(format!("a{i}"), pose(x, y, 0.0), 360))
        .collect();
    let (strong, weak) = (Vec2::new(12.0, 9.0), Vec2::new(22.0, 11.0));
    let mut node = FusionNode::new(sensors.clone(), scheduler()).expect("valid node");
    for (i, s) in sensors.iter().enumerate() {
        let a = bump(s, bearing_to(s, strong), 4.0 * DEG);
        let b = bump(s, bearing_to(s, weak), 4.0 * DEG);
        let values = a.iter().zip(&b).map(|(x, y)| x + 0.4 * y).collect();
        node.receive(report(i, 0.0, values)).expect("ok");
    }
    let mut config = fusion_config(FusionRule::Product { floor: 0.01 });
    config.peaks.relative_threshold = 0.5;
    config.peaks.moment_fraction = 0.8;
    config.peaks.moment_radius_m = 1.0;
    let plain = fuse_snapshot(&sensors, &node.snapshot(0), &config).expect("fuses");
    assert_eq!(plain.peaks.len(), 1, "{:?}", plain.peaks);
    // The original-grid test needs κ below the weak target's 0.4³ relative value.
    config.peaks.relative_threshold = 0.03;
    config.peaks.explain_away_deg = 6.0;
    let fused = fuse_snapshot(&sensors, &node.snapshot(0), &config).expect("fuses");
    assert!(fused.peaks.len() >= 2, "{:?}", fused.peaks);
    let e1 = (fused.peaks[0].position - strong).norm();
    let e2 = (fused.peaks[1].position - weak).norm();
    assert!(
        e1 < 0.5 && e2 < 0.5,
        "errors {e1} m, {e2} m: {:?}",
        fused.peaks
    );
    // The second peak's value is the fused grid's at its cell (about 0.4³ of the first's),
    // not the renormalised residual's, where it would be the residual's maximum.
    let (col, row) = fused
        .grid
        .cell_of(&fused.peaks[1].position)
        .expect("inside");
    let on_grid = fused.grid.value(col, row);
    assert_eq!(fused.peaks[1].value.to_bits(), on_grid.to_bits());
    assert!(
        fused.peaks[1].value < 0.5 * fused.peaks[0].value,
        "{:?}",
        fused.peaks
    );
    config.peaks.explain_away_deg = -1.0;
    assert!(config.check().is_err());
}

// ---------------------------------------------------------------- range fade

/// A 360-bin profile that is 1 on the bins `lo..=hi` (degrees) and `low` elsewhere.
fn plateau(lo: usize, hi: usize, low: f64) -> Vec<f64> {
    (0..360)
        .map(|b| if (lo..=hi).contains(&b) { 1.0 } else { low })
        .collect()
}

/// `values` with everything at or below 10⁻³ set to exactly 0 (a profile that vetoes under the
/// plain product).
fn zeroed(values: Vec<f64>) -> Vec<f64> {
    values
        .into_iter()
        .map(|x| if x > 1e-3 { x } else { 0.0 })
        .collect()
}

#[test]
fn range_fade_weighs_each_sensor_by_distance_by_hand() {
    // Two cells of 1 m, centres c1 = (0.5, 0.5) and c2 = (1.5, 0.5). Sensor a at (0.5, −3.5)
    // sees c1 at 90° and c2 at atan2(4, 1) = 75.96°; its plateau on 70..=80° gives c1 the low
    // value 0.2 and c2 the full 1. Sensor b at (1.5, 4.5) sees c1 at 255.96° and c2 at 270°;
    // its plateau on 250..=260° gives c1 1 and c2 0.2. Distances: a–c1 = b–c2 = 4,
    // a–c2 = b–c1 = √17. Fade r₀ = 1 m, q = 2: g = 1/r².
    let mut a = SensorNode::audio("a", pose(0.5, -3.5, 0.0), 360);
    let mut b = SensorNode::audio("b", pose(1.5, 4.5, 0.0), 360);
    a.weight = 1.0;
    b.weight = 0.5;
    let mut node = FusionNode::new(vec![a, b], scheduler()).expect("valid node");
    node.receive(report(0, 0.0, plateau(70, 80, 0.2)))
        .expect("ok");
    node.receive(report(1, 0.0, plateau(250, 260, 0.2)))
        .expect("ok");
    let fade = RangeFade {
        full_weight_m: 1.0,
        power: 2.0,
    };
    let (near, far) = (1.0 / 16.0, 1.0 / 17.0);
    let (w_a, w_b) = (1.0, 0.5);
    let (l_a, l_b) = ([0.2, 1.0], [1.0, 0.2]); // scaled values at c1, c2
    let (g_a, g_b) = ([near, far], [far, near]);
    let normalised = |x: [f64; 2]| [x[0] / (x[0] + x[1]), x[1] / (x[0] + x[1])];
    let fused = |rule: FusionRule| {
        let mut config = fusion_config(rule);
        config.region = Region2::new(Vec2::zeros(), Vec2::new(2.0, 1.0)).expect("region");
        config.cell_size_m = 1.0;
        config.peaks.border_cells = 0;
        config.range_fade = Some(fade);
        let scan = fuse_snapshot(node.sensors(), &node.snapshot(0), &config).expect("fuses");
        [scan.grid.value(0, 0), scan.grid.value(1, 0)]
    };
    // Product, ε = 0.1: t = ε + (1 − ε) L; each sensor adds g w (ln t − mean ln t).
    let eps = 0.1;
    let log_term = |l: [f64; 2], g: [f64; 2], w: f64, i: usize| {
        let t = [eps + (1.0 - eps) * l[0], eps + (1.0 - eps) * l[1]];
        let mean = (t[0].ln() + t[1].ln()) / 2.0;
        g[i] * w * (t[i].ln() - mean)
    };
    let want =
        normalised([0, 1].map(|i| (log_term(l_a, g_a, w_a, i) + log_term(l_b, g_b, w_b, i)).exp()));
    let got = fused(FusionRule::Product { floor: eps });
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() < 1e-12, "product {got:?} against {want:?}");
    }
    // Unfaded, b's half weight leaves c2 (the cell a supports) the stronger by
    // (1 / 0.28)^½ ≈ 1.89; faded, each sensor's vote against a cell is the nearer one (g = 1/16
    // against 1/17), which pulls the two cells together: c2 still wins, by much less.
    assert!(got[1] > got[0]);
    let unfaded_ratio = (1.0 / (eps + (1.0 - eps) * 0.2)).sqrt();
    assert!(got[1] / got[0] < 1.1 && unfaded_ratio > 1.8);
    // Weighted sum (max scaling): each sensor adds w (m + g (L − m)), m the mean scaled value.
    let sum_term = |l: [f64; 2], g: [f64; 2], w: f64, i: usize| {
        let m = (l[0] + l[1]) / 2.0;
        w * (m + g[i] * (l[i] - m))
    };
    let want = normalised([0, 1].map(|i| sum_term(l_a, g_a, w_a, i) + sum_term(l_b, g_b, w_b, i)));
    let got = fused(FusionRule::WeightedSum {
        scaling: SumScaling::Max,
    });
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() < 1e-12, "sum {got:?} against {want:?}");
    }
}

#[test]
fn a_fade_that_covers_the_region_changes_nothing() {
    // r₀ beyond every cell: g = 1 everywhere, and the per-sensor mean is a shift of every
    // cell alike, so the fused grid is the unfaded one.
    let s1 = SensorNode::audio("a", pose(2.0, 1.0, 0.0), 360);
    let s2 = SensorNode::audio("b", pose(33.0, 1.5, 0.0), 360);
    let mut node = FusionNode::new(vec![s1.clone(), s2.clone()], scheduler()).expect("node");
    node.receive(report(0, 0.0, bump(&s1, 30.0 * DEG, 5.0 * DEG)))
        .expect("ok");
    node.receive(report(1, 0.0, bump(&s2, 150.0 * DEG, 5.0 * DEG)))
        .expect("ok");
    for rule in [
        FusionRule::Product { floor: 0.05 },
        FusionRule::WeightedSum {
            scaling: SumScaling::Max,
        },
    ] {
        let plain = fusion_config(rule);
        let faded = FusionConfig {
            range_fade: Some(RangeFade {
                full_weight_m: 100.0,
                power: 3.0,
            }),
            ..plain.clone()
        };
        let x = fuse_snapshot(node.sensors(), &node.snapshot(0), &plain).expect("fuses");
        let y = fuse_snapshot(node.sensors(), &node.snapshot(0), &faded).expect("fuses");
        // Equal to rounding: the sum adds and removes the mean, so the error is relative to
        // the grid's largest value, not to each cell's.
        let top = x.grid.values().iter().copied().fold(0.0, f64::max);
        for (p, q) in x.grid.values().iter().zip(y.grid.values()) {
            assert!((p - q).abs() <= 1e-12 * top, "{rule:?}: {p} against {q}");
        }
        assert_eq!(x.peaks.len(), y.peaks.len());
    }
}

#[test]
fn range_fade_factor_and_bad_settings() {
    let f = RangeFade {
        full_weight_m: 8.0,
        power: 0.5,
    };
    assert!((f.factor(0.0) - 1.0).abs() < 1e-15);
    assert!((f.factor(3.0) - 1.0).abs() < 1e-15);
    assert!((f.factor(8.0) - 1.0).abs() < 1e-15);
    assert!((f.factor(32.0) - 0.5).abs() < 1e-15); // (8/32)^½
    for (r0, q) in [
        (0.0, 1.0),
        (-1.0, 1.0),
        (f64::NAN, 1.0),
        (5.0, 0.0),
        (5.0, f64::INFINITY),
    ] {
        let mut config = fusion_config(FusionRule::Product { floor: 0.1 });
        config.range_fade = Some(RangeFade {
            full_weight_m: r0,
            power: q,
        });
        assert!(config.check().is_err(), "r₀ {r0}, q {q} accepted");
    }
}

#[test]
fn a_fade_keeps_the_plain_products_veto_and_stays_finite() {
    // ε = 0: a cell where a sensor's profile is exactly 0 has ln t = −∞. The sensor's mean is
    // taken over its finite logarithms (a mean of −∞ would turn every cell into NaN), and a
    // −∞ stays −∞ where g underflows to 0 (r₀ = 1 m, q = 300: 0 · −∞ would be NaN).
    let s1 = SensorNode::audio("a", pose(2.0, 1.0, 0.0), 360);
    let s2 = SensorNode::audio("b", pose(33.0, 1.5, 0.0), 360);
    let (t1, t2) = (30.0 * DEG, 150.0 * DEG);
    let truth = intersection(s1.pose.position, t1, s2.pose.position, t2);
    let mut node = FusionNode::new(vec![s1.clone(), s2.clone()], scheduler()).expect("node");
    node.receive(report(0, 0.0, zeroed(bump(&s1, t1, 2.0 * DEG))))
        .expect("ok");
    node.receive(report(1, 0.0, zeroed(bump(&s2, t2, 2.0 * DEG))))
        .expect("ok");
    for (full_weight_m, power) in [(8.0, 1.0), (1.0, 300.0)] {
        let mut config = fusion_config(FusionRule::Product { floor: 0.0 });
        config.range_fade = Some(RangeFade {
            full_weight_m,
            power,
        });
        let fused = fuse_snapshot(node.sensors(), &node.snapshot(0), &config).expect("fuses");
        let values = fused.grid.values();
        assert!(values.iter().all(|v| v.is_finite()), "r₀ {full_weight_m}");
        assert!((values.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        // Far from both rays every cell is vetoed.
        let corner = fused.grid.cell_of(&Vec2::new(34.0, 19.0)).expect("inside");
        assert!(fused.grid.value(corner.0, corner.1) < 1e-300);
        if full_weight_m > 1.0 {
            let best = fused.peaks.first().expect("a peak");
            assert!((best.position - truth).norm() < 0.5, "{:?}", best.position);
        }
    }
}

#[test]
fn the_pipeline_fades_as_fuse_snapshot_does() {
    // AvPipeline builds the fade maps once; fuse_snapshot builds them per call.
    let sensors = road_sensors();
    let mut reports = noise_free_reports(&sensors, 1.5).into_iter().peekable();
    let mut config = av_config(FusionRule::Product { floor: 0.05 });
    config.fusion.range_fade = Some(RangeFade {
        full_weight_m: 8.0,
        power: 0.5,
    });
    let mut pipeline = AvPipeline::new(sensors.clone(), &config).expect("pipeline");
    let mut node = FusionNode::new(sensors.clone(), config.scheduler).expect("node");
    let mut peaks = 0;
    for k in 0..15 {
        let due = config.scheduler.tick_time_s(k) + config.scheduler.staleness_s;
        while let Some(r) = reports.next_if(|r| r.local_time_s <= due) {
            pipeline.receive(r.clone()).expect("ok");
            node.receive(r).expect("ok");
        }
        let (scan, _) = pipeline.process(k).expect("processes");
        let direct = fuse_snapshot(&sensors, &node.snapshot(k), &config.fusion).expect("fuses");
        assert_eq!(scan.grid.values(), direct.grid.values());
        peaks += scan.peaks.len();
    }
    assert!(peaks >= 10, "{peaks} peaks in 15 ticks");
}
