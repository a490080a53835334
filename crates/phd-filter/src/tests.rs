//! Tests of the PHD filters, fusion and detector management.
#![expect(clippy::float_cmp, reason = "hand-computed values are exact in binary")]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use tracker_model::{BoundingBox, Frame, LocalDetector};

use crate::fusion::{DetectorBank, FusionConfig, MAX_CONFIDENCE, Source, fuse, updated_confidence};
use crate::{GmConfig, GmPhd, PhdConfig, SmcPhd};

fn bx(left: f64, top: f64, width: f64, height: f64) -> BoundingBox {
    BoundingBox {
        left,
        top,
        width,
        height,
    }
}

/// Three people standing still, seen every frame with small noise and no clutter.
fn still_people(frames: usize, seed: u64) -> Vec<Vec<BoundingBox>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 1.0).unwrap();
    let people = [(100.0, 200.0), (300.0, 220.0), (500.0, 180.0)];
    (0..frames)
        .map(|_| {
            people
                .iter()
                .map(|&(x, y)| {
                    bx(
                        x + noise.sample(&mut rng),
                        y + noise.sample(&mut rng),
                        40.0 + noise.sample(&mut rng),
                        100.0 + noise.sample(&mut rng),
                    )
                })
                .collect()
        })
        .collect()
}

#[test]
fn smc_cardinality_converges_without_clutter_or_misses() {
    let config = PhdConfig {
        clutter_rate: 1e-3,
        particles_per_target: 500,
        ..PhdConfig::default()
    };
    let mut filter = SmcPhd::new(config, 3).unwrap();
    let frames = still_people(25, 1);
    let mut labels_at_end = Vec::new();
    for (t, boxes) in frames.iter().enumerate() {
        let out = filter.step(boxes).unwrap();
        assert!(
            filter
                .particles()
                .iter()
                .all(|p| p.w.is_finite() && p.w >= 0.0),
            "frame {t}: a weight is negative or not finite"
        );
        if t >= 5 {
            assert!(
                (out.expected_targets - 3.0).abs() < 0.2,
                "frame {t}: N̂ = {}",
                out.expected_targets
            );
            assert_eq!(out.estimates.len(), 3, "frame {t}");
        }
        if t == frames.len() - 1 {
            labels_at_end = out.estimates.iter().map(|e| e.label).collect();
        }
    }
    // Identities persist: the three labels of the last frame were those of frame 5 on.
    labels_at_end.sort_unstable();
    let mut filter = SmcPhd::new(config, 3).unwrap();
    let mut at_five = Vec::new();
    for (t, boxes) in frames.iter().enumerate().take(6) {
        let out = filter.step(boxes).unwrap();
        if t == 5 {
            at_five = out.estimates.iter().map(|e| e.label).collect();
        }
    }
    at_five.sort_unstable();
    assert_eq!(labels_at_end, at_five);
}

#[test]
fn gm_and_smc_expected_counts_agree() {
    // A linear-Gaussian case: random-walk boxes, Gaussian box noise, a little clutter, and
    // misses. Both filters approximate the same PHD recursion (same birth scheme).
    let config = PhdConfig {
        clutter_rate: 0.5,
        particles_per_target: 2000,
        birth_particles: 500,
        ..PhdConfig::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let noise = Normal::new(0.0, 1.0).unwrap();
    let mut frames = still_people(40, 2);
    // Drop some detections and add clutter boxes far from everyone.
    for (t, f) in frames.iter_mut().enumerate() {
        if t % 7 == 3 {
            f.remove(1);
        }
        if t % 5 == 0 {
            f.push(bx(50.0 + 10.0 * noise.sample(&mut rng), 400.0, 30.0, 70.0));
        }
    }
    let mut smc = SmcPhd::new(config, 4).unwrap();
    let mut gm = GmPhd::new(config, GmConfig::default()).unwrap();
    let mut worst: f64 = 0.0;
    let mut total = 0.0;
    for f in &frames {
        let a = smc.step(f).unwrap().expected_targets;
        let b = gm.step(f).unwrap().expected_targets;
        worst = worst.max((a - b).abs());
        total += (a - b).abs();
    }
    let mean = total / frames.len() as f64;
    // Stated tolerance: mean |ΔN̂| < 0.05 and worst < 0.25 targets.
    assert!(mean < 0.05, "mean |ΔN̂| = {mean}");
    assert!(worst < 0.25, "worst |ΔN̂| = {worst}");
}

#[test]
fn fusion_at_the_iou_threshold() {
    let config = FusionConfig::default();
    // IoU exactly 0.5 (100 / 200): not fused, both pass through.
    let g = bx(0.0, 0.0, 10.0, 10.0);
    let l = bx(0.0, 0.0, 10.0, 20.0);
    assert_eq!(g.iou(&l), 0.5);
    let out = fuse(&[g], &[l], &config);
    assert_eq!(out.len(), 2);
    assert_eq!(out[0].1, Source::Global(0));
    assert_eq!(out[1].1, Source::Local(0));
    // Just above: fused into the average (eq. 1-2 with weights 0.5 / 0.5).
    let l2 = bx(0.0, 0.0, 10.0, 19.0);
    assert!(g.iou(&l2) > 0.5);
    let out = fuse(&[g, bx(100.0, 100.0, 5.0, 5.0)], &[l2], &config);
    assert_eq!(out.len(), 2);
    assert_eq!(out[0].0, bx(0.0, 0.0, 10.0, 14.5));
    assert_eq!(
        out[0].1,
        Source::Fused {
            global: 0,
            local: 0
        }
    );
    assert_eq!(out[1].1, Source::Global(1));
    // Degenerate boxes never fuse.
    let nan = bx(f64::NAN, 0.0, 10.0, 10.0);
    let flat = bx(0.0, 0.0, 10.0, 0.0);
    assert_eq!(fuse(&[nan, flat], &[g], &config).len(), 3);
}

#[test]
fn confidence_follows_eqs_9_and_10() {
    let config = FusionConfig::default();
    // p_D = 0.7, p_FA = 0.1 from P = 0.5: eq. 9 gives 0.35 / 0.40, eq. 10 gives 0.15 / 0.60.
    assert!((updated_confidence(0.5, true, &config) - 0.875).abs() < 1e-15);
    assert!((updated_confidence(0.5, false, &config) - 0.25).abs() < 1e-15);
    // Yoon et al. 2016's p_D = 0.95 with p_FA = 0.3: one miss takes 0.5 to 0.025 / 0.375.
    let seed = FusionConfig {
        p_detect: 0.95,
        p_false_alarm: 0.3,
        ..config
    };
    assert!((updated_confidence(0.5, false, &seed) - 0.025 / 0.375).abs() < 1e-15);
    // A long-confirmed detector can still be removed: uncapped, f64 rounds the posterior to
    // exactly 1 after a few dozen confirmations and eq. 10 then keeps it at 1 for ever.
    let mut p = 0.5;
    for _ in 0..100 {
        p = updated_confidence(p, true, &seed);
    }
    assert_eq!(p, MAX_CONFIDENCE);
    // From odds 2⁵² each miss multiplies the odds by 0.05 / 0.7 = 1/14: 14¹⁴ ≈ 1.1e16 < 9·2⁵²
    // ≈ 4.1e16 < 14¹⁵ ≈ 1.6e17, so the 15th miss is the first to reach P ≤ 0.1.
    let mut misses = 0;
    while p > seed.removal_confidence {
        p = updated_confidence(p, false, &seed);
        misses += 1;
    }
    assert_eq!(misses, 15);
}

/// A detector that reports a fixed box.
struct Fixed(BoundingBox);

impl LocalDetector for Fixed {
    fn detect(&mut self, _frame: Frame, _around: &BoundingBox) -> Option<BoundingBox> {
        Some(self.0)
    }
}

#[test]
fn detectors_are_confirmed_at_iou_half_and_removed_at_one_tenth() {
    // p_D = 0.75, p_FA = 0.25 keep every step of eqs. 9-10 exact in binary, so the removal
    // boundary (confidence ≤ 0.1) has one answer. By hand, from P₀ = 0.5:
    // unconfirmed: 0.25·0.5 / (0.25·0.5 + 0.75·0.5) = 0.125 / 0.5 = 0.25, then
    // 0.25·0.25 / (0.0625 + 0.75·0.75) = 0.0625 / 0.625 = 0.1 (the double nearest 0.1, as the
    // literal; division is correctly rounded), so the detector goes at its second unconfirmed
    // frame, not its first; confirmed: 0.75·0.5 / (0.375 + 0.125) = 0.75.
    let config = FusionConfig {
        p_detect: 0.75,
        p_false_alarm: 0.25,
        ..FusionConfig::default()
    };
    assert_eq!(config.initial_confidence, 0.5);
    assert_eq!(config.removal_confidence, 0.1);
    let mut bank = DetectorBank::default();
    let a = bx(0.0, 0.0, 10.0, 20.0);
    let b = bx(200.0, 0.0, 10.0, 20.0);
    bank.add(1, Box::new(Fixed(a)), a, &config);
    bank.add(2, Box::new(Fixed(b)), b, &config);
    // A global box overlapping `a` with IoU exactly 0.5 confirms it (eq. 9 needs ≥ 0.5);
    // nothing confirms `b`.
    let global = [bx(0.0, 0.0, 10.0, 10.0)];
    let found = bank.detect(0);
    assert_eq!(found.len(), 2);
    let removed = bank.update_confidence(&found, &global, &config);
    assert!(removed.is_empty());
    assert_eq!(bank.detectors()[0].confidence, 0.75);
    assert_eq!(bank.detectors()[1].confidence, 0.25);
    let found = bank.detect(1);
    let removed = bank.update_confidence(&found, &global, &config);
    assert_eq!(
        removed,
        vec![2],
        "removed at exactly 0.1 on the second miss"
    );
    assert!(bank.has(1));
    // Just below the boundary it survives that frame with confidence 0.1 and goes at the third.
    let below = FusionConfig {
        removal_confidence: 0.1f64.next_down(),
        ..config
    };
    let mut bank = DetectorBank::default();
    bank.add(2, Box::new(Fixed(b)), b, &below);
    for frame in 0..2 {
        let found = bank.detect(frame);
        assert!(bank.update_confidence(&found, &global, &below).is_empty());
    }
    assert_eq!(bank.detectors()[0].confidence, 0.1);
    let found = bank.detect(2);
    assert_eq!(bank.update_confidence(&found, &global, &below), vec![2]);
}

#[test]
fn degenerate_input_is_skipped_not_a_panic() {
    let mut smc = SmcPhd::new(PhdConfig::default(), 1).unwrap();
    let mut gm = GmPhd::new(PhdConfig::default(), GmConfig::default()).unwrap();
    let frames = [
        vec![],
        vec![
            bx(f64::NAN, 1.0, 10.0, 10.0),
            bx(1.0, 1.0, 0.0, 10.0),
            bx(1.0, 1.0, 10.0, -3.0),
            bx(f64::INFINITY, 1.0, 10.0, 10.0),
        ],
        vec![],
        vec![bx(10.0, 10.0, 20.0, 50.0)],
    ];
    for f in &frames {
        let a = smc.step(f).unwrap();
        let b = gm.step(f).unwrap();
        assert_eq!(a.skipped, f.len().min(4) - usize::from(f.len() == 1));
        assert_eq!(a.skipped, b.skipped);
        assert!(a.expected_targets.is_finite() && b.expected_targets.is_finite());
    }
    for bad in [
        PhdConfig {
            p_detect: 1.0,
            ..PhdConfig::default()
        },
        PhdConfig {
            measurement_std: [1.0, f64::NAN, 1.0, 1.0],
            ..PhdConfig::default()
        },
        PhdConfig {
            birth_particles: 0,
            ..PhdConfig::default()
        },
        PhdConfig {
            birth_particles: usize::MAX,
            ..PhdConfig::default()
        },
    ] {
        assert!(SmcPhd::new(bad, 0).is_err());
        assert!(GmPhd::new(bad, GmConfig::default()).is_err());
    }
}

#[test]
fn smc_is_reproducible_whatever_the_thread_count() {
    let frames = still_people(8, 5);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let config = PhdConfig {
                    // Enough particles for several parallel chunks.
                    particles_per_target: 3000,
                    ..PhdConfig::default()
                };
                let mut f = SmcPhd::new(config, 11).unwrap();
                let outs: Vec<_> = frames.iter().map(|b| f.step(b).unwrap()).collect();
                (outs, f.particles().to_vec())
            })
    };
    let (a, pa) = run(1);
    assert!(
        pa.len() > 4096,
        "{} particles: too few to span chunks",
        pa.len()
    );
    // Two threads split the chunks evenly; three and five do not.
    for threads in [2, 3, 5] {
        let (b, pb) = run(threads);
        assert_eq!(a, b, "{threads} threads");
        assert_eq!(pa, pb, "{threads} threads");
    }
}

#[test]
fn constant_velocity_option_follows_moving_boxes() {
    use crate::Motion;
    let config = PhdConfig {
        clutter_rate: 1e-3,
        particles_per_target: 1000,
        motion: Motion::ConstantVelocity {
            acceleration_std: 0.5,
            size_std: 0.5,
        },
        birth_velocity_std: 4.0,
        ..PhdConfig::default()
    };
    let mut filter = SmcPhd::new(config, 6).unwrap();
    let mut gm = GmPhd::new(config, GmConfig::default()).unwrap();
    // Two boxes moving at (+3, +1) and (−2, 0) pixels per frame, seen exactly.
    let at = |t: f64| {
        vec![
            bx(100.0 + 3.0 * t, 200.0 + t, 40.0, 100.0),
            bx(500.0 - 2.0 * t, 150.0, 30.0, 80.0),
        ]
    };
    for t in 0..20 {
        let boxes = at(f64::from(t));
        let out = filter.step(&boxes).unwrap();
        let out_gm = gm.step(&boxes).unwrap();
        if t >= 10 {
            for o in [&out, &out_gm] {
                assert_eq!(o.estimates.len(), 2, "frame {t}");
                for e in &o.estimates {
                    let best = boxes.iter().map(|b| b.iou(&e.bbox)).fold(0.0, f64::max);
                    assert!(best > 0.8, "frame {t}: IoU {best}");
                }
            }
            // The velocity is learnt: each estimate moves like its box.
            for e in &out.estimates {
                let v = (e.state[4], e.state[5]);
                let ok = ((v.0 - 3.0).abs() < 1.0 && (v.1 - 1.0).abs() < 1.0)
                    || ((v.0 + 2.0).abs() < 1.0 && v.1.abs() < 1.0);
                assert!(ok, "frame {t}: velocity {v:?}");
            }
        }
    }
}

#[test]
fn bad_settings_are_errors_that_name_the_parameter() {
    use crate::Error;
    use crate::scene::{LocalDetectorSim, SceneConfig};
    let named = |r: crate::Result<()>| match r {
        Err(Error::Model(tracker_model::Error::InvalidParameter { name, .. })) => name,
        other => panic!("expected an invalid parameter, got {other:?}"),
    };
    assert_eq!(PhdConfig::for_boxes(&[]), Err(Error::NoBoxes));
    let phd = |c: PhdConfig| named(c.check());
    assert_eq!(
        phd(PhdConfig {
            max_particles: 0,
            ..PhdConfig::default()
        }),
        "max_particles"
    );
    assert_eq!(
        phd(PhdConfig {
            label_min_share: 1.5,
            ..PhdConfig::default()
        }),
        "label_min_share"
    );
    let gm = |c: GmConfig| named(GmPhd::new(PhdConfig::default(), c).map(|_| ()));
    assert_eq!(
        gm(GmConfig {
            prune_below: -1e-5,
            ..GmConfig::default()
        }),
        "prune_below"
    );
    assert_eq!(
        gm(GmConfig {
            max_components: 0,
            ..GmConfig::default()
        }),
        "max_components"
    );
    assert_eq!(
        named(
            SceneConfig {
                ground_rows: [300.0, 200.0],
                ..SceneConfig::default()
            }
            .check()
        ),
        "ground_rows"
    );
    assert_eq!(
        named(
            SceneConfig {
                speed: [2.0, 1.0],
                ..SceneConfig::default()
            }
            .check()
        ),
        "speed"
    );
    assert_eq!(
        named(
            LocalDetectorSim {
                p_drift: 1.5,
                ..LocalDetectorSim::default()
            }
            .check()
        ),
        "p_drift"
    );
    assert_eq!(
        named(
            LocalDetectorSim {
                search: 0.0,
                ..LocalDetectorSim::default()
            }
            .check()
        ),
        "search"
    );
    assert!(SceneConfig::default().check().is_ok());
    assert!(SceneConfig::pets_like().check().is_ok());
    assert!(LocalDetectorSim::default().check().is_ok());
}

#[test]
fn local_detectors_that_find_nothing_change_nothing() {
    use crate::{NoLocalDetectors, PhdTracker};
    let frames = still_people(6, 3);
    let config = PhdConfig {
        particles_per_target: 300,
        ..PhdConfig::default()
    };
    let mut alone = PhdTracker::global_only(SmcPhd::new(config, 2).unwrap());
    let mut with_local = PhdTracker::with_local_detectors(
        SmcPhd::new(config, 2).unwrap(),
        NoLocalDetectors,
        FusionConfig::default(),
    )
    .unwrap();
    for (frame, boxes) in (0..).zip(&frames) {
        let a = alone.step(frame, boxes).unwrap();
        let b = with_local.step(frame, boxes).unwrap();
        assert_eq!(a.estimates, b.estimates, "frame {frame}");
        assert_eq!(a.local_detectors, 0);
    }
    assert_eq!(alone.tracks().unwrap(), with_local.tracks().unwrap());
    assert_eq!(alone.tracks().unwrap().len(), 3);
}

/// The simulated local detectors of `scene.rs`: they see only what is inside their window and
/// fail at the rates their configuration states. Rates are checked against a binomial bound of
/// 4 standard deviations (a correct simulator fails one in ~16,000 seeds; the seeds are fixed).
mod simulated_detectors {
    use std::collections::BTreeMap;
    use std::sync::Arc;

    use tracker_model::{BoundingBox, Frame, LocalDetector, LocalDetectorFactory, TrackId};

    use super::bx;
    use crate::fusion::{DetectorBank, FusionConfig};
    use crate::scene::{FrameTruth, LocalDetectorSim, SimulatedDetectors, Template};

    /// A detector that always finds what it looks for, exactly, and reports nothing else.
    fn perfect() -> LocalDetectorSim {
        LocalDetectorSim {
            search: 0.5,
            p_detect: 1.0,
            p_detect_occluded: 1.0,
            occlusion: 0.5,
            noise: 0.0,
            noise_occluded: 0.0,
            p_drift: 0.0,
            p_stale: 0.0,
            spawn_iou: 0.3,
        }
    }

    /// The same people (id, box, hidden fraction) in frames 0..n.
    fn still(n: u32, people: &[(u64, BoundingBox, f64)]) -> Arc<BTreeMap<Frame, FrameTruth>> {
        let frame: FrameTruth = people.iter().map(|&(i, b, h)| (TrackId(i), b, h)).collect();
        Arc::new((0..n).map(|f| (f, frame.clone())).collect())
    }

    /// Whether k successes in n trials fit probability p within 4 standard deviations.
    fn binomial_ok(k: usize, n: usize, p: f64) -> bool {
        let (k, n) = (k as f64, n as f64);
        (k - n * p).abs() <= 4.0 * (n * p * (1.0 - p)).sqrt()
    }

    const A: BoundingBox = BoundingBox {
        left: 100.0,
        top: 200.0,
        width: 40.0,
        height: 100.0,
    };

    #[test]
    fn never_fires_for_a_person_outside_its_window() {
        let n = 2000;
        // Spawned on A at frame 0; from frame 1 on A stands 300 px to the right, far outside
        // the window (centre of `around` ± 50 px), and the detector is asked around A's old box.
        let far = bx(400.0, 200.0, 40.0, 100.0);
        let mut frames: BTreeMap<Frame, FrameTruth> = BTreeMap::new();
        frames.insert(0, vec![(TrackId(0), A, 0.0)]);
        for f in 1..=n {
            frames.insert(f, vec![(TrackId(0), far, 0.0)]);
        }
        let config = LocalDetectorSim {
            p_stale: 0.3,
            noise: 0.04,
            ..perfect()
        };
        let mut factory = SimulatedDetectors::over(Arc::new(frames), config, 5).unwrap();
        let mut d = factory.detector(0, &A);
        assert_eq!(d.template(), Template::Person(TrackId(0)));
        assert!(d.detect(0, &A).is_some_and(|b| b.iou(&A) > 0.3));
        let mut stale = 0;
        for f in 1..=n {
            if let Some(b) = d.detect(f, &A) {
                stale += 1;
                assert_eq!(b.intersection_area(&far), 0.0, "frame {f}: {b:?} reaches A");
            }
        }
        // What it does report there is its stale response, at the stated rate.
        assert!(binomial_ok(stale, n as usize, 0.3), "{stale} stale of {n}");
        // The same detector asked around A's new place finds A every time.
        assert!((1..=100).all(|f| d.detect(f, &far).is_some_and(|b| b.iou(&far) > 0.3)));
    }

    #[test]
    fn misses_and_box_noise_at_the_stated_rates() {
        let n = 5000;
        for (hidden, p, noise) in [(0.2, 0.8, 0.04), (0.7, 0.3, 0.08)] {
            let config = LocalDetectorSim {
                p_detect: 0.8,
                p_detect_occluded: 0.3,
                noise: 0.04,
                noise_occluded: 0.08,
                ..perfect()
            };
            let content = still(n, &[(3, A, hidden)]);
            let mut d = SimulatedDetectors::over(content, config, 11)
                .unwrap()
                .detector(0, &A);
            let errors: Vec<f64> = (0..n)
                .filter_map(|f| d.detect(f, &A))
                .map(|b| b.left - A.left)
                .collect();
            assert!(
                binomial_ok(errors.len(), n as usize, p),
                "hidden {hidden}: found {} of {n}, stated rate {p}",
                errors.len()
            );
            // The left edge's error has standard deviation noise × height; the sample's
            // relative standard error is 1/√(2m) ≈ 2-3 %, the bound 4 of those.
            let m = errors.len() as f64;
            let sd = (errors.iter().map(|e| e * e).sum::<f64>() / m).sqrt();
            let expected = noise * A.height;
            assert!(
                (sd / expected - 1.0).abs() < 4.0 / (2.0 * m).sqrt(),
                "hidden {hidden}: box noise {sd}, stated {expected}"
            );
        }
    }

    #[test]
    fn a_fully_hidden_person_is_never_found_nor_drifted_to() {
        // A detector spawned on A while it was visible, certain to find an occluded person,
        // never reports A once A is entirely hidden (hidden fraction 1) and does not stale.
        let n = 500;
        let mut frames: BTreeMap<Frame, FrameTruth> = BTreeMap::new();
        frames.insert(0, vec![(TrackId(0), A, 0.0)]);
        for f in 1..=n {
            frames.insert(f, vec![(TrackId(0), A, 1.0)]);
        }
        let mut d = SimulatedDetectors::over(Arc::new(frames), perfect(), 3)
            .unwrap()
            .detector(0, &A);
        assert!(d.detect(0, &A).is_some());
        assert!((1..=n).all(|f| d.detect(f, &A).is_none()));
        // Nine tenths hidden, the same detector finds A every time.
        let mut d = SimulatedDetectors::over(still(n, &[(0, A, 0.9)]), perfect(), 3)
            .unwrap()
            .detector(0, &A);
        assert!((0..n).all(|f| d.detect(f, &A).is_some()));
        // A detector on B, certain to drift to a neighbour in its window, never drifts to A
        // hidden entirely beside it.
        let b = bx(110.0, 200.0, 40.0, 100.0);
        let config = LocalDetectorSim {
            p_drift: 1.0,
            ..perfect()
        };
        let content = still(n, &[(0, A, 1.0), (1, b, 0.0)]);
        let mut d = SimulatedDetectors::over(content, config, 3)
            .unwrap()
            .detector(0, &b);
        assert!((0..n).all(|f| d.detect(f, &b).is_some()));
        assert_eq!(d.template(), Template::Person(TrackId(1)));
    }

    #[test]
    fn drifts_to_a_close_neighbour_at_the_stated_rate() {
        let n = 5000;
        // B's centre is 20 px from A's: each is inside the other's window.
        let b = bx(120.0, 200.0, 40.0, 100.0);
        for p_drift in [0.0, 0.1] {
            let config = LocalDetectorSim {
                p_drift,
                ..perfect()
            };
            let content = still(n, &[(0, A, 0.0), (1, b, 0.0)]);
            let mut factory = SimulatedDetectors::over(content, config, 17).unwrap();
            let stats = factory.stats();
            let mut d = factory.detector(0, &A);
            assert_eq!(d.template(), Template::Person(TrackId(0)));
            let mut around = A;
            let mut switches = 0;
            for f in 0..n {
                let before = d.template();
                let found = d.detect(f, &around).unwrap();
                // Noise 0: the report is exactly the box of whoever it now follows.
                let now = if found == A { 0 } else { 1 };
                assert!(found == A || found == b);
                assert_eq!(d.template(), Template::Person(TrackId(now)));
                if d.template() != before {
                    switches += 1;
                }
                around = found;
            }
            assert!(
                binomial_ok(switches, n as usize, p_drift),
                "{switches} switches in {n} frames at p_drift {p_drift}"
            );
            let counts = stats.counts();
            assert_eq!(counts.drifts, switches as u64);
            assert_eq!(counts.detector_frames, u64::from(n));
            assert_eq!((counts.spawned, counts.on_clutter), (1, 0));
        }
    }

    #[test]
    fn clutter_spawned_detector_fires_on_clutter_until_eqs_9_10_remove_it() {
        // Nobody overlaps C, so the detector learns background there. The global detector only
        // ever finds the person far away, so it never confirms C. With p_D = 0.6, p_FA = 0.5
        // each unconfirmed frame multiplies the odds P/(1−P) by 0.4/0.5 = 0.8 (eq. 10): from
        // 1 (P₀ = 0.5) the odds are 0.8^9 = 0.134 (P = 0.118) after 9 frames and
        // 0.8^10 = 0.107 (P = 0.097 ≤ 0.1) after 10, so it fires on frames 0..=9 and is then
        // removed.
        let c = bx(100.0, 200.0, 40.0, 100.0);
        let person = bx(400.0, 200.0, 40.0, 100.0);
        let content = still(30, &[(0, person, 0.0)]);
        let mut factory = SimulatedDetectors::over(content, perfect(), 23).unwrap();
        assert_eq!(factory.detector(0, &c).template(), Template::Background(c));
        let fusion = FusionConfig {
            p_detect: 0.6,
            p_false_alarm: 0.5,
            ..FusionConfig::default()
        };
        let mut bank = DetectorBank::default();
        bank.add(7, factory.spawn(0, &c), c, &fusion);
        let mut fired = 0;
        let mut removed_at = None;
        for frame in 0..30 {
            let found = bank.detect(frame);
            if bank.has(7) {
                assert_eq!(found.len(), 1, "frame {frame}: it keeps firing");
                assert_eq!(found[0].1, c, "frame {frame}: on the clutter");
                fired += 1;
            } else {
                assert!(found.is_empty());
            }
            if !bank
                .update_confidence(&found, &[person], &fusion)
                .is_empty()
            {
                removed_at.get_or_insert(frame);
            }
        }
        assert_eq!(fired, 10);
        assert_eq!(removed_at, Some(9));
    }

    #[test]
    fn spawned_on_a_person_it_learns_that_person() {
        let b = bx(300.0, 200.0, 40.0, 100.0);
        let content = still(1, &[(4, A, 0.0), (9, b, 0.0)]);
        let mut factory = SimulatedDetectors::over(content, perfect(), 1).unwrap();
        // Half a box off: IoU 1/3 ≥ 0.3, so it learns A.
        let shifted = bx(120.0, 200.0, 40.0, 100.0);
        assert_eq!(
            factory.detector(0, &shifted).template(),
            Template::Person(TrackId(4))
        );
        assert_eq!(
            factory.detector(0, &b).template(),
            Template::Person(TrackId(9))
        );
        // 30 px off: IoU 1/7 < 0.3, so it learns the background there.
        let off = bx(130.0, 200.0, 40.0, 100.0);
        assert_eq!(
            factory.detector(0, &off).template(),
            Template::Background(off)
        );
    }
}

/// Jumping a gap of empty frames in one prediction (sparse time).
mod gaps {
    use nalgebra::SMatrix;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::bx;
    use crate::smc::{propagate, propagate_by};
    use crate::{GmConfig, GmPhd, Motion, PhdConfig, SmcPhd};

    type Mat6 = SMatrix<f64, 6, 6>;

    fn cv() -> Motion {
        Motion::ConstantVelocity {
            acceleration_std: 1.5,
            size_std: 0.5,
        }
    }

    fn rw() -> Motion {
        Motion::RandomWalk {
            position_std: 3.0,
            size_std: 0.5,
        }
    }

    fn max_rel_diff(a: &Mat6, b: &Mat6) -> f64 {
        let scale = a.abs().max().max(b.abs().max()).max(1.0);
        (a - b).abs().max() / scale
    }

    #[test]
    fn one_k_step_prediction_is_k_single_steps() {
        // The independent route: compose the one-frame model k times by brute force,
        // F_k = F F_{k−1}, Q_k = F Q_{k−1} Fᵀ + Q, from the one-frame F and Q written out here.
        for motion in [cv(), rw()] {
            let mut f1 = Mat6::identity();
            let mut q1 = Mat6::zeros();
            match motion {
                Motion::ConstantVelocity {
                    acceleration_std: a,
                    size_std: s,
                } => {
                    f1[(0, 4)] = 1.0;
                    f1[(1, 5)] = 1.0;
                    q1[(4, 4)] = a * a;
                    q1[(5, 5)] = a * a;
                    q1[(2, 2)] = s * s;
                    q1[(3, 3)] = s * s;
                }
                Motion::RandomWalk {
                    position_std: p,
                    size_std: s,
                } => {
                    q1[(0, 0)] = p * p;
                    q1[(1, 1)] = p * p;
                    q1[(2, 2)] = s * s;
                    q1[(3, 3)] = s * s;
                }
            }
            let (mut fk, mut qk) = (Mat6::identity(), Mat6::zeros());
            for k in 1..=1000u64 {
                fk = f1 * fk;
                qk = f1 * qk * f1.transpose() + q1;
                if [1, 2, 3, 7, 50, 1000].contains(&k) {
                    let (f, q) = motion.transition(k);
                    let f = Mat6::from_fn(|i, j| f[i][j]);
                    let q = Mat6::from_fn(|i, j| q[i][j]);
                    assert!(max_rel_diff(&f, &fk) <= 1e-12, "{motion:?} k = {k}: F");
                    assert!(
                        max_rel_diff(&q, &qk) <= 1e-12,
                        "{motion:?} k = {k}: Q {q} vs {qk}"
                    );
                    let x = [10.0, -4.0, 40.0, 90.0, 2.5, -0.5];
                    let mean = motion.predict_mean(&x, k);
                    let brute = fk * nalgebra::SVector::<f64, 6>::from(x);
                    for i in 0..6 {
                        assert!((mean[i] - brute[i]).abs() <= 1e-12 * brute[i].abs().max(1.0));
                    }
                }
            }
        }
        // By hand, k = 4, σ_a² = 2.25: Σj² = 0 + 1 + 4 + 9 = 14, Σj = 6.
        let (_, q) = cv().transition(4);
        assert_eq!(
            (q[0][0], q[0][4], q[4][4]),
            (14.0 * 2.25, 6.0 * 2.25, 4.0 * 2.25)
        );
    }

    #[test]
    fn gap_weight_is_survival_per_frame_and_a_miss_per_empty_frame() {
        let config = PhdConfig {
            p_survive: 0.5,
            p_detect: 0.75,
            ..PhdConfig::default()
        };
        assert_eq!(config.gap_weight(1), 0.5);
        // 0.5³ · 0.25² = 1/128.
        assert!((config.gap_weight(3) - 1.0 / 128.0).abs() < 1e-15);
        assert_eq!(config.gap_weight(u64::from(u32::MAX)), 0.0);
    }

    #[test]
    fn particles_jump_with_the_moments_of_the_k_step_transition() {
        let mut a = ChaCha8Rng::seed_from_u64(1);
        let mut b = ChaCha8Rng::seed_from_u64(1);
        let x0 = [100.0, 50.0, 40.0, 90.0, 3.0, -1.0];
        // One frame is the one-frame model, draw for draw.
        for motion in [cv(), rw()] {
            let (mut x, mut y) = (x0, x0);
            propagate_by(&mut x, &motion, 1, &mut a);
            propagate(&mut y, &motion, &mut b);
            assert_eq!(x, y);
        }
        // k = 7 under constant velocity: sample mean and covariance of (c_x, v_x) against
        // F(7) x0 and Q(7) = 2.25 [[91, 21], [21, 7]] (Σj² = 91, Σj = 21 over j < 7).
        let n = 200_000;
        let (mut sp, mut sv, mut spp, mut spv, mut svv) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for _ in 0..n {
            let mut x = x0;
            propagate_by(&mut x, &cv(), 7, &mut a);
            let (p, v) = (x[0] - (100.0 + 7.0 * 3.0), x[4] - 3.0);
            sp += p;
            sv += v;
            spp += p * p;
            spv += p * v;
            svv += v * v;
        }
        let nf = f64::from(n);
        let (mp, mv) = (sp / nf, sv / nf);
        // Standard errors: √(204.75 / n) = 0.032 and √(15.75 / n) = 0.009; variances to 2 %
        // (their relative standard error is √(2/n) = 0.3 %).
        assert!(mp.abs() < 0.15 && mv.abs() < 0.05, "means {mp} {mv}");
        for (got, want) in [
            (spp / nf, 2.25 * 91.0),
            (spv / nf, 2.25 * 21.0),
            (svv / nf, 2.25 * 7.0),
        ] {
            assert!((got - want).abs() < 0.02 * want, "{got} vs {want}");
        }
    }

    fn config() -> PhdConfig {
        PhdConfig {
            p_detect: 0.1,
            motion: cv(),
            ..PhdConfig::default()
        }
    }

    #[test]
    fn gm_jump_equals_stepping_every_empty_frame() {
        let first = [bx(100.0, 200.0, 40.0, 100.0)];
        let after = [bx(130.0, 190.0, 41.0, 101.0)];
        let mut jump = GmPhd::new(config(), GmConfig::default()).unwrap();
        jump.step(&first).unwrap();
        let mut walk = jump.clone();
        // Six frames, the first five without a detection.
        let a = jump.step_after(6, &after).unwrap();
        for _ in 0..5 {
            walk.step(&[]).unwrap();
        }
        let b = walk.step(&after).unwrap();
        assert!((a.expected_targets - b.expected_targets).abs() < 1e-12);
        assert_eq!(jump.components().len(), walk.components().len());
        for (c, d) in jump.components().iter().zip(walk.components()) {
            assert!((c.w - d.w).abs() <= 1e-12 * d.w, "{} vs {}", c.w, d.w);
            assert!((c.m - d.m).abs().max() <= 1e-12 * d.m.abs().max());
            assert!(max_rel_diff(&c.p, &d.p) <= 1e-12, "{} vs {}", c.p, d.p);
        }
    }

    #[test]
    fn smc_jump_keeps_the_mass_of_stepping_every_empty_frame() {
        let first = [bx(100.0, 200.0, 40.0, 100.0), bx(300.0, 100.0, 30.0, 80.0)];
        let mut jump = SmcPhd::new(config(), 2).unwrap();
        jump.step(&first).unwrap();
        let mut walk = jump.clone();
        // Nine empty frames: N̂ is (p_S (1 − p_D))⁹ of what it was, either way (resampling
        // keeps the total weight).
        let before: f64 = jump.particles().iter().map(|p| p.w).sum();
        let a = jump.step_after(9, &[]).unwrap().expected_targets;
        let mut b = 0.0;
        for _ in 0..9 {
            b = walk.step(&[]).unwrap().expected_targets;
        }
        let want = before * (0.99f64 * 0.9).powi(9);
        assert!((a - want).abs() < 1e-12 * want, "{a} vs {want}");
        assert!((b - want).abs() < 1e-12 * want, "{b} vs {want}");
    }

    #[test]
    fn a_gap_of_four_billion_frames_costs_one_step() {
        let first = [bx(100.0, 200.0, 40.0, 100.0)];
        for gm in [false, true] {
            let start = std::time::Instant::now();
            let out = if gm {
                let mut f = GmPhd::new(config(), GmConfig::default()).unwrap();
                f.step(&first).unwrap();
                let out = f.step_after(4_000_000_000, &first).unwrap();
                assert!(f.components().iter().all(|c| c.w.is_finite()));
                out
            } else {
                let mut f = SmcPhd::new(config(), 2).unwrap();
                f.step(&first).unwrap();
                let out = f.step_after(4_000_000_000, &first).unwrap();
                assert!(f.particles().iter().all(|p| p.w.is_finite()));
                out
            };
            // Everything from before the gap is forgotten (weight 0): only the newborn is left.
            assert!(
                out.expected_targets.abs() < 1e-300,
                "{}",
                out.expected_targets
            );
            assert!(start.elapsed().as_secs_f64() < 2.0);
        }
        let mut f = SmcPhd::new(config(), 2).unwrap();
        assert!(matches!(
            f.step_after(0, &first),
            Err(crate::Error::Model(
                tracker_model::Error::InvalidParameter { name: "frames", .. }
            ))
        ));
    }
}
