//! Tests of the PHD filters, fusion and detector management.
#![expect(clippy::float_cmp, reason = "hand-computed values are exact in binary")]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use tracker_model::{BoundingBox, Frame, LocalDetector};

use crate::fusion::{DetectorBank, FusionConfig, Source, fuse, updated_confidence};
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
    let config = FusionConfig::default();
    let mut bank = DetectorBank::default();
    let a = bx(0.0, 0.0, 10.0, 20.0);
    let b = bx(200.0, 0.0, 10.0, 20.0);
    bank.add(1, Box::new(Fixed(a)), a, &config);
    bank.add(2, Box::new(Fixed(b)), b, &config);
    // Global box overlapping `a` with IoU exactly 0.5 confirms it (eq. 9 needs ≥ 0.5);
    // nothing confirms `b`.
    let global = [bx(0.0, 0.0, 10.0, 10.0)];
    let found = bank.detect(0);
    assert_eq!(found.len(), 2);
    let removed = bank.update_confidence(&found, &global, &config);
    assert!(removed.is_empty());
    assert_eq!(
        bank.detectors()[0].confidence,
        updated_confidence(0.5, true, &config)
    );
    assert_eq!(bank.detectors()[1].confidence, 0.25);
    // Unconfirmed again: 0.25 → 0.075 / (0.075 + 0.675) = 0.1 (up to rounding), then
    // 0.1 → 0.03 / (0.03 + 0.81) ≈ 0.036 ≤ 0.1: removed.
    let found = bank.detect(1);
    bank.update_confidence(&found, &global, &config);
    let c = bank
        .detectors()
        .iter()
        .find(|d| d.label == 2)
        .map(|d| d.confidence);
    assert!(
        c.is_none() || (c.unwrap_or(0.0) - 0.1).abs() < 1e-12,
        "{c:?}"
    );
    let found = bank.detect(2);
    bank.update_confidence(&found, &global, &config);
    assert!(!bank.has(2));
    assert!(bank.has(1));
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
    let (b, pb) = run(2);
    assert_eq!(a, b);
    assert!(
        pa.len() > 4096,
        "{} particles: too few to span chunks",
        pa.len()
    );
    assert_eq!(pa, pb);
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
        Err(Error::InvalidParameter { name, .. })
        | Err(Error::Model(tracker_model::Error::InvalidParameter { name, .. })) => name,
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
                p_lost: 0.7,
                p_relock: 0.5,
                ..LocalDetectorSim::default()
            }
            .check()
        ),
        "p_lost"
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
