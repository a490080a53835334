//! Tests of air-traffic against closed forms, hand-written collections and seeded statistics.

use approx::assert_relative_eq;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::*;

const A: f64 = 6_378_137.0;
const F: f64 = 1.0 / 298.257_223_563;

/// Small offsets move along the ellipsoid's meridian and prime-vertical radii:
/// M = a(1 − e²)/(1 − e² sin²φ)^{3/2}, N = a/(1 − e² sin²φ)^{1/2}.
#[test]
fn enu_offsets_follow_the_radii_of_curvature() {
    let frame = EnuFrame::new(48.5, 2.5).unwrap();
    let origin = frame.to_enu(48.5, 2.5, 0.0).unwrap();
    assert!(origin.iter().all(|v| v.abs() < 1e-6), "{origin:?}");
    let e2 = F * (2.0 - F);
    let s2 = 48.5f64.to_radians().sin().powi(2);
    let m = A * (1.0 - e2) / (1.0 - e2 * s2).powf(1.5);
    let n = A / (1.0 - e2 * s2).sqrt();
    let d = 1e-3f64; // degrees: ~100 m, where the curvature's own error is below a millimetre
    let north = frame.to_enu(48.5 + d, 2.5, 0.0).unwrap();
    assert_relative_eq!(north[1], m * d.to_radians(), max_relative = 1e-5);
    assert!(north[0].abs() < 1e-6);
    let east = frame.to_enu(48.5, 2.5 + d, 0.0).unwrap();
    assert_relative_eq!(
        east[0],
        n * 48.5f64.to_radians().cos() * d.to_radians(),
        max_relative = 1e-5
    );
    let up = frame.to_enu(48.5, 2.5, 1000.0).unwrap();
    assert_relative_eq!(up[2], 1000.0, epsilon = 1e-6);
    // 100 km north the surface has dropped by about d²/(2R).
    let far = frame.to_enu(48.5 + 0.9, 2.5, 0.0).unwrap();
    let drop = far[1].powi(2) / (2.0 * (m * n).sqrt());
    assert_relative_eq!(-far[2], drop, max_relative = 0.01);
}

const COLLECTION: &str = r#"[
 {"icao24":"abc123","timestamp":1000000,"latitude":48.5,"longitude":2.5,"groundspeed":100.0,"track":90.0,"onground":false,"altitude":1000.0},
 {"icao24":"abc123","timestamp":1001000,"latitude":48.5,"longitude":2.5007,"groundspeed":100.0,"track":90.0,"onground":false,"altitude":null},
 {"icao24":"abc123","timestamp":1001000,"latitude":48.6,"longitude":2.6,"groundspeed":1.0,"track":0.0,"onground":false},
 {"icao24":"abc123","timestamp":1002000,"latitude":48.5,"longitude":2.5014,"groundspeed":null,"track":null,"onground":false},
 {"icao24":"abc123","timestamp":1100000,"latitude":48.5,"longitude":2.6,"groundspeed":100.0,"track":90.0,"onground":false},
 {"icao24":"abc123","timestamp":1101000,"latitude":48.5,"longitude":2.6007,"groundspeed":100.0,"track":90.0,"onground":false},
 {"icao24":"def456","timestamp":1000500,"latitude":48.4,"longitude":2.4,"groundspeed":0.0,"track":0.0,"onground":true},
 {"icao24":"def456","timestamp":1001500,"latitude":null,"longitude":null,"groundspeed":200.0,"track":0.0,"onground":false}
]"#;

fn read_config() -> ReadConfig {
    ReadConfig {
        frame: EnuFrame::new(48.5, 2.5).unwrap(),
        max_gap_s: 20.0,
        min_duration_s: 0.0,
    }
}

/// The gap of 98 s splits abc123 in two; the repeated time stamp keeps its first report; the
/// report on the ground and the one without a position are dropped, so def456 is gone.
#[test]
fn a_hand_written_collection_becomes_its_trajectories() {
    let trajectories = read_collection(COLLECTION, &read_config()).unwrap();
    assert_eq!(trajectories.len(), 2);
    assert!(trajectories.iter().all(|t| t.label() == "abc123"));
    let first = &trajectories[0];
    assert_eq!(first.samples().len(), 3);
    assert_eq!(first.span(), (0.0, 2.0));
    // 100 kt due east (track 90° clockwise from north).
    let v = first.samples()[0].velocity;
    assert_relative_eq!(v[0], 100.0 * 1852.0 / 3600.0, epsilon = 1e-9);
    assert!(v[1].abs() < 1e-9);
    // The last sample has no ground speed: its velocity is the positions' difference.
    let s = first.samples();
    let dv = (s[2].position[0] - s[1].position[0]) / 1.0;
    assert_relative_eq!(s[2].velocity[0], dv, epsilon = 1e-9);
    assert_eq!(trajectories[1].span(), (100.0, 101.0));
}

#[test]
fn bad_collections_are_errors() {
    for bad in [
        "",
        "{}",
        "[{\"icao24\": 3}]",
        "[{\"icao24\":\"a\",\"timestamp\":\"x\"}]",
    ] {
        assert!(read_collection(bad, &read_config()).is_err(), "{bad}");
    }
    let config = ReadConfig {
        max_gap_s: 0.0,
        ..read_config()
    };
    assert!(read_collection(COLLECTION, &config).is_err());
}

/// A circle at 2°/s sampled every second: positions interpolate on the chords, and the turn
/// rate reads 2°/s.
#[test]
fn a_sampled_circle_has_its_turn_rate() {
    let (rate, speed) = (2f64.to_radians(), 200.0);
    let r = speed / rate;
    let samples: Vec<Sample> = (0..120)
        .map(|k| {
            let a = rate * k as f64;
            Sample {
                time_s: k as f64,
                position: [r * a.sin(), r * (1.0 - a.cos())],
                velocity: [speed * a.cos(), speed * a.sin()],
            }
        })
        .collect();
    let t = Trajectory::new("circle".into(), samples).unwrap();
    assert_relative_eq!(
        t.turn_rate_at(60.0, 5.0).unwrap(),
        rate,
        max_relative = 1e-9
    );
    let mid = t.at(10.5).unwrap();
    let a = t.at(10.0).unwrap();
    let b = t.at(11.0).unwrap();
    assert_relative_eq!(
        mid.position[0],
        0.5 * (a.position[0] + b.position[0]),
        epsilon = 1e-9
    );
    assert!(t.at(-1.0).is_none() && t.at(119.5).is_none());
    assert!(t.turn_rate_at(2.0, 5.0).is_none());
}

fn standin() -> StandinConfig {
    StandinConfig {
        aircraft: 20,
        duration_s: 1800.0,
        half_width_m: 80_000.0,
        speed_m_s: [150.0, 250.0],
        leg_s: [60.0, 240.0],
        turn_deg_s: [1.5, 3.0],
        turn_change_deg: [30.0, 120.0],
        life_s: [600.0, 1800.0],
    }
}

#[test]
fn the_standin_is_reproducible_and_keeps_its_limits() {
    let a = standin()
        .generate(&mut ChaCha8Rng::seed_from_u64(3))
        .unwrap();
    let b = standin()
        .generate(&mut ChaCha8Rng::seed_from_u64(3))
        .unwrap();
    assert_eq!(a, b);
    assert!(a.len() >= 15);
    let mut turning = 0;
    for t in &a {
        for s in t.samples() {
            assert!(s.position.iter().all(|c| c.abs() <= 80_000.0 * 1.0001));
            let speed = s.velocity[0].hypot(s.velocity[1]);
            assert!((150.0..=250.0).contains(&speed), "{speed}");
        }
        let (start, end) = t.span();
        let mut time = start + 5.0;
        while time < end - 5.0 {
            let w = t.turn_rate_at(time, 0.5).unwrap().to_degrees().abs();
            assert!(w < 3.0 + 1e-6, "{w} deg/s");
            turning += usize::from(w > 1.0);
            time += 10.0;
        }
    }
    assert!(turning > 20, "only {turning} turning samples");
}

fn radar() -> RotatingRadar {
    RotatingRadar {
        position: [1000.0, -2000.0],
        period_s: 10.0,
        dwells: 12,
        min_range_m: 1000.0,
        max_range_m: 150_000.0,
        sigma_range_m: 50.0,
        sigma_bearing_rad: 0.002,
        p_detect: 0.8,
        clutter_per_revolution: 30.0,
    }
}

#[test]
fn views_wrap_at_the_bearing_cut() {
    let r = radar();
    let z = |range: f64, b: f64| nalgebra::SVector::<f64, 2>::new(range, b);
    let pi = std::f64::consts::PI;
    assert!(r.in_view(pi, &z(5000.0, -pi + 0.1)));
    assert!(!r.in_view(pi, &z(5000.0, -pi + 0.3)));
    assert!(!r.in_view(0.0, &z(500.0, 0.0)));
    assert!(!r.in_view(0.0, &z(200_000.0, 0.0)));
}

/// Detections, clutter and noise have the rates and spreads asked for, within four standard
/// errors over 2000 revolutions.
#[test]
fn simulated_plots_have_the_configured_statistics() {
    let r = radar();
    // A slow aircraft circling 40 km from the radar: every revolution sees it once.
    let samples: Vec<Sample> = (0..20_001)
        .map(|k| {
            let a = 1e-4 * k as f64;
            Sample {
                time_s: k as f64,
                position: [1000.0 + 40_000.0 * a.cos(), -2000.0 + 40_000.0 * a.sin()],
                velocity: [-4.0 * a.sin(), 4.0 * a.cos()],
            }
        })
        .collect();
    let t = vec![Trajectory::new("slow".into(), samples).unwrap()];
    let dwells = r
        .simulate(&t, 0.0, 20_000.0, &mut ChaCha8Rng::seed_from_u64(5))
        .unwrap();
    let revolutions = 2000.0;
    let hits: Vec<(f64, nalgebra::SVector<f64, 2>)> = dwells
        .iter()
        .flat_map(|d| {
            d.plots
                .iter()
                .zip(&d.origins)
                .filter(|(_, o)| o.is_some())
                .map(|(z, _)| (d.time_s, *z))
        })
        .collect();
    let p = hits.len() as f64 / revolutions;
    assert!(
        (p - 0.8).abs() < 4.0 * (0.8f64 * 0.2 / revolutions).sqrt(),
        "p_d {p}"
    );
    let clutter: usize = dwells
        .iter()
        .map(|d| d.origins.iter().filter(|o| o.is_none()).count())
        .sum();
    let per_rev = clutter as f64 / revolutions;
    assert!(
        (per_rev - 30.0).abs() < 4.0 * (30.0f64 / revolutions).sqrt(),
        "clutter {per_rev}"
    );
    let errors: Vec<f64> = hits
        .iter()
        .map(|(time, z)| {
            let s = t[0].at(*time).unwrap();
            z[0] - (s.position[0] - 1000.0).hypot(s.position[1] + 2000.0)
        })
        .collect();
    let sd = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    assert!(
        (sd - 50.0).abs() < 4.0 * 50.0 / (2.0 * errors.len() as f64).sqrt(),
        "σ_r {sd}"
    );
}

#[test]
fn bad_radars_and_standins_are_errors() {
    let bad = [
        RotatingRadar {
            dwells: 0,
            ..radar()
        },
        RotatingRadar {
            p_detect: 1.5,
            ..radar()
        },
        RotatingRadar {
            max_range_m: 500.0,
            ..radar()
        },
        RotatingRadar {
            sigma_bearing_rad: 0.0,
            ..radar()
        },
        RotatingRadar {
            position: [f64::NAN, 0.0],
            ..radar()
        },
    ];
    for r in bad {
        assert!(r.check().is_err(), "{r:?}");
    }
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    assert!(radar().simulate(&[], 0.0, 1e12, &mut rng).is_err());
    for s in [
        StandinConfig {
            aircraft: 0,
            ..standin()
        },
        StandinConfig {
            speed_m_s: [300.0, 100.0],
            ..standin()
        },
        StandinConfig {
            duration_s: 1e9,
            ..standin()
        },
    ] {
        assert!(s.generate(&mut rng).is_err(), "{s:?}");
    }
}

fn circle_trajectory() -> Vec<Trajectory> {
    // 200 m/s on a 2°/s circle around a point 30 km east of the radar, for 600 s.
    let (rate, speed) = (2f64.to_radians(), 200.0);
    let r = speed / rate;
    let samples = (0..=600)
        .map(|k| {
            let a = rate * k as f64;
            Sample {
                time_s: k as f64,
                position: [30_000.0 + r * a.sin(), r * (1.0 - a.cos())],
                velocity: [speed * a.cos(), speed * a.sin()],
            }
        })
        .collect();
    vec![Trajectory::new("circle".into(), samples).unwrap()]
}

/// 200 m/s due east along y = 20 km for 600 s.
fn straight_trajectory() -> Vec<Trajectory> {
    let samples = (0..=600)
        .map(|k| Sample {
            time_s: k as f64,
            position: [-30_000.0 + 200.0 * k as f64, 20_000.0],
            velocity: [200.0, 0.0],
        })
        .collect();
    vec![Trajectory::new("straight".into(), samples).unwrap()]
}

fn score_config() -> ScoreConfig {
    ScoreConfig {
        match_distance_m: 1000.0,
        turn_rate_rad_s: 1f64.to_radians(),
        turn_half_window_s: 5.0,
    }
}

/// A "tracker" that reports the truth itself scores zero error and no break; the same with its
/// id changed once at revolution 20 scores one break in the 2°/s turn.
#[test]
fn scores_of_hand_built_runs() {
    let r = RotatingRadar {
        p_detect: 1.0,
        clutter_per_revolution: 0.0,
        ..radar()
    };
    let trajectories = circle_trajectory();
    let dwells = r
        .simulate(&trajectories, 0.0, 600.0, &mut ChaCha8Rng::seed_from_u64(1))
        .unwrap();
    let points = truth_points(&r, &trajectories, &dwells).unwrap();
    assert!(points.len() >= 58, "{} revolutions seen", points.len());
    let run_with = |switch_at: u32| RadarRun::<4> {
        states: points
            .iter()
            .map(|p| {
                let k = trajectories[0].at(p.time_s).unwrap();
                let mean = nalgebra::Vector4::new(
                    k.position[0],
                    k.position[1],
                    k.velocity[0],
                    k.velocity[1],
                );
                let id = tracker_model::TrackId(if p.frame < switch_at { 1 } else { 2 });
                let state = mcmcda::PlotTrackState {
                    id,
                    time_s: p.time_s,
                    estimate: tracker_model::Gaussian::new(mean, nalgebra::Matrix4::identity())
                        .unwrap(),
                    hit: true,
                };
                (p.frame, state)
            })
            .collect(),
        births_refused: 0,
    };
    let clean = score(&trajectories, &points, &run_with(u32::MAX), &score_config());
    assert_eq!((clean.position_rmse_m, clean.velocity_rmse_m_s), (0.0, 0.0));
    assert_eq!(clean.turning_breaks, 0);
    assert!(clean.turning_chances >= 50);
    let switched = score(&trajectories, &points, &run_with(20), &score_config());
    assert_eq!(switched.turning_breaks, 1);
    assert_eq!(switched.turning_chances, clean.turning_chances);
    let truth = truth_set(&trajectories, &points).unwrap();
    assert_eq!(truth.tracks().len(), 1);
    assert_eq!(track_set(&run_with(20)).unwrap().tracks().len(), 2);
}

/// The CV Kalman filter through the radar on an aircraft flying straight at 200 m/s: one
/// track, errors of the order of the plots' own (50 m in range, 0.002 rad ≈ 60-100 m across at
/// 30-50 km).
#[test]
fn a_tracker_over_the_dwells_follows_the_aircraft() {
    let r = radar();
    let trajectories = straight_trajectory();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let dwells = r.simulate(&trajectories, 0.0, 600.0, &mut rng).unwrap();
    let estimator = tracker_model::SingleModel {
        motion: tracker_model::ConstantVelocity2::new(
            1.0,
            tracker_model::CvNoise::WhiteAcceleration { q: 10.0 },
        )
        .unwrap(),
        filter: tracker_model::GaussianFilter::Extended,
    };
    let config = mcmcda::PlotGnnConfig {
        gate_chi2: 16.0,
        clutter_log_density: r.clutter_log_density(),
        confirm_hits: 3,
        confirm_window: 4,
        max_misses: 3,
        max_tracks: 1000,
    };
    let mut gnn = mcmcda::PlotGnn::new(estimator, config).unwrap();
    let birth = BirthPrior {
        sigma_speed_m_s: 250.0,
        sigma_turn_rad_s: 0.02,
    };
    let run = track_dwells(&mut gnn, &r, &dwells, birth).unwrap();
    let points = truth_points(&r, &trajectories, &dwells).unwrap();
    let s = score(&trajectories, &points, &run, &score_config());
    assert!(s.matched as f64 >= 0.8 * points.len() as f64, "{s:?}");
    assert!(s.position_rmse_m < 150.0, "{s:?}");
}

const PLOTS: &str = "time_s,sensor,sensor_x,sensor_y,range,bearing,sigma_range,sigma_bearing\n\
    10,1,0,0,1000,0.5,20,0.01\n\
    \n\
    0,1,0,0,1000,0.4,20,0.01\n";

#[test]
fn plot_files_parse_in_either_layout_and_sort_by_time() {
    let rows = parse_plots(PLOTS).unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0].time_s.to_bits(), 0f64.to_bits());
    assert_eq!(rows[0].value, PlotValue::RangeBearing([1000.0, 0.4]));
    assert_eq!(rows[0].sigma, Some([20.0, 0.01]));
    let xy = parse_plots("x,y,time_s,sensor,sensor_x,sensor_y,extra\n5,6,1.5,2,0,0,zzz\n").unwrap();
    assert_eq!(xy[0].value, PlotValue::Position([5.0, 6.0]));
    assert_eq!((xy[0].sensor, xy[0].sigma), (2, None));
}

#[test]
fn bad_plot_files_name_their_line() {
    let cases = [
        ("", "empty"),
        (
            "time_s,sensor,sensor_x,sensor_y\n1,1,0,0\n",
            "x,y or range,bearing",
        ),
        (
            "time_s,sensor,sensor_x,sensor_y,x,y\n1,1,0,0,5,abc\n",
            "line 2",
        ),
        (
            "time_s,sensor,sensor_x,sensor_y,x,y\n1,1,0,0,5,6\n1,-3,0,0,5,6\n",
            "line 3",
        ),
        (
            "time_s,sensor,sensor_x,sensor_y,x,y,sigma_x,sigma_y\n1,1,0,0,5,6,0,1\n",
            "positive",
        ),
        (
            "time_s,sensor,sensor_x,sensor_y,x,y\n1,1,0,0,inf,6\n",
            "not finite",
        ),
    ];
    for (text, want) in cases {
        let err = parse_plots(text).unwrap_err().to_string();
        assert!(err.contains(want), "{text:?}: {err}");
    }
    let err = track_plots(
        &parse_plots(PLOTS).unwrap(),
        PlotFilter::Kf,
        &PlotTrackConfig::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("range-bearing plots need"), "{err}");
    assert!("abc".parse::<PlotFilter>().is_err());
}

/// A radar's plots of an aircraft flying straight, written as a plot file, tracked with each
/// filter and scored against the truth written as a point file: one track, and MOTA ≥ 0.9 at
/// 1 km (the two revolutions before confirmation are misses: 2 of 61).
#[test]
fn a_plot_file_round_trip_tracks_and_scores() {
    let r = RotatingRadar {
        dwells: 1,
        clutter_per_revolution: 5.0,
        ..radar()
    };
    let trajectories = straight_trajectory();
    let dwells = r
        .simulate(&trajectories, 0.0, 600.0, &mut ChaCha8Rng::seed_from_u64(4))
        .unwrap();
    let mut plots = String::from("time_s,sensor,sensor_x,sensor_y,range,bearing\n");
    let mut truth = String::from("time_s,id,x,y\n");
    for d in &dwells {
        for z in &d.plots {
            plots.push_str(&format!(
                "{},7,{},{},{},{}\n",
                d.time_s, r.position[0], r.position[1], z[0], z[1]
            ));
        }
        let k = trajectories[0].at(d.time_s).unwrap();
        truth.push_str(&format!(
            "{},1,{},{}\n",
            d.time_s, k.position[0], k.position[1]
        ));
    }
    let rows = parse_plots(&plots).unwrap();
    let config = PlotTrackConfig {
        sigma_range_m: 50.0,
        sigma_bearing_rad: 0.002,
        clutter_log_density: r.clutter_log_density(),
        ..PlotTrackConfig::default()
    };
    for filter in [PlotFilter::Ekf, PlotFilter::Ukf, PlotFilter::Imm] {
        let tracks = track_plots(&rows, filter, &config).unwrap();
        let (gt, pred) = point_track_sets(&truth, &format_tracks(&tracks)).unwrap();
        let eval = eval_metrics_free_mota(&gt, &pred, 1000.0);
        assert_eq!(pred.tracks().len(), 1, "{filter:?}");
        assert!(eval >= 0.9, "{filter:?}: MOTA {eval}");
    }
}

/// MOTA at a distance threshold without eval-metrics (not a dependency here): one truth track,
/// so a frame is a hit when some estimate lies within `d` (a second one is a false positive).
fn eval_metrics_free_mota(
    gt: &tracker_model::TrackSet,
    pred: &tracker_model::TrackSet,
    d: f64,
) -> f64 {
    let truth = &gt.tracks()[0];
    let (mut errors, mut n) = (0usize, 0usize);
    for p in truth.points() {
        n += 1;
        let near = pred
            .tracks()
            .iter()
            .filter_map(|t| t.at(p.frame))
            .filter(|q| (q.location.position() - p.location.position()).norm() <= d)
            .count();
        let all = pred
            .tracks()
            .iter()
            .filter(|t| t.at(p.frame).is_some())
            .count();
        errors += if near == 0 { 1 + all } else { all - 1 };
    }
    1.0 - errors as f64 / n as f64
}

/// A 12-dwell radar's run written by `format_radar_run` keeps its sectors: tracked from the
/// file, one track holds the straight aircraft through most of the run. Without the sector columns every
/// dwell that does not hold it counts a miss, and no track survives to confirmation.
#[test]
fn sector_columns_keep_a_rotating_radars_tracks() {
    let r = RotatingRadar {
        clutter_per_revolution: 5.0,
        ..radar()
    };
    let trajectories = straight_trajectory();
    let dwells = r
        .simulate(&trajectories, 0.0, 600.0, &mut ChaCha8Rng::seed_from_u64(6))
        .unwrap();
    let truth = truth_points(&r, &trajectories, &dwells).unwrap();
    let (plots, _) = format_radar_run(&r, &dwells, &trajectories, &truth);
    let config = PlotTrackConfig {
        clutter_log_density: r.clutter_log_density(),
        ..PlotTrackConfig::default()
    };
    let with = track_plots(&parse_plots(&plots).unwrap(), PlotFilter::Ekf, &config).unwrap();
    let longest = (1..=with.iter().map(|t| t.id).max().unwrap_or(0))
        .map(|id| with.iter().filter(|t| t.id == id && t.hit).count())
        .max()
        .unwrap_or(0);
    // p_D 0.8 over 60 revolutions: about 48 hits when one track holds it all the way.
    assert!(longest >= 35, "the longest track has {longest} hits");
    let stripped: String = plots
        .lines()
        .map(|l| l.splitn(7, ',').take(6).collect::<Vec<_>>().join(","))
        .collect::<Vec<_>>()
        .join("\n");
    let without = track_plots(&parse_plots(&stripped).unwrap(), PlotFilter::Ekf, &config).unwrap();
    assert!(without.is_empty(), "{} estimates", without.len());
}
