//! Tests of the synthetic pedestrian scene: checked settings, reproducible walkers, gaps cut
//! from the truth and observed with noise, one window per scene.

use nalgebra::Vector2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::gap::WindowConfig;

/// A small scene in the shape of the PETS2009 S2L1 image.
fn config() -> SceneConfig {
    SceneConfig {
        width: 768.0,
        height: 576.0,
        n_walkers: 12,
        n_frames: 300,
        speed: 4.0,
        turn_noise: 0.01,
        speed_noise: 0.02,
        detection_sigma: 1.0,
    }
}

fn mask() -> Region2 {
    Region2::new(Vector2::new(334.0, 238.0), Vector2::new(434.0, 338.0)).unwrap()
}

/// A change to the settings.
type Edit = fn(&mut SceneConfig);

#[test]
fn bad_settings_are_errors_not_panics() {
    assert!(config().check().is_ok());
    let cases: [(&str, Edit); 4] = [
        ("n_frames", |c| c.n_frames = 1),
        ("width", |c| c.width = 0.0),
        ("speed", |c| c.speed = f64::NAN),
        ("detection_sigma", |c| c.detection_sigma = -1.0),
    ];
    for (name, set) in cases {
        let mut c = config();
        set(&mut c);
        let err = c.check().unwrap_err();
        assert!(err.to_string().contains(name), "{name}: {err}");
    }
}

#[test]
fn walkers_are_reproducible_and_observed_at_the_true_frames() {
    let scene = config().check().unwrap();
    let draw = |seed| {
        scene
            .simulate(&mut ChaCha8Rng::seed_from_u64(seed))
            .unwrap()
    };
    let (truth, seen) = draw(5);
    assert_eq!((truth.clone(), seen.clone()), draw(5));
    assert!(!truth.tracks().is_empty() && truth.len() == seen.len());
    for t in truth.tracks() {
        let s = seen.get(t.id()).unwrap();
        assert!(t.points().len() >= 3);
        for (a, b) in t.points().iter().zip(s.points()) {
            assert_eq!(a.frame, b.frame);
            assert!((a.location.position() - b.location.position()).norm() < 10.0);
        }
    }
}

#[test]
fn gaps_hide_the_truth_and_show_the_observations() {
    let scene = config().check().unwrap();
    let (truth, seen) = scene.simulate(&mut ChaCha8Rng::seed_from_u64(2)).unwrap();
    let gaps = cut_gaps(&truth, &seen, &mask());
    assert!(!gaps.is_empty());
    for g in &gaps {
        let frames = |o: &[Observation]| o.iter().map(|o| o.frame).collect::<Vec<_>>();
        assert_eq!(frames(&g.before), frames(&g.case.before));
        assert_eq!(frames(&g.after), frames(&g.case.after));
        assert_ne!(g.before, g.case.before, "observations carry detector noise");
    }
    let usable: Vec<ObservedGap> = gaps
        .into_iter()
        .filter(|g| g.before.len() >= 3 && g.after.len() >= 3)
        .collect();
    let window = WindowConfig {
        candidates: vec![3, 5, 8],
    };
    let chosen = scene_window(&usable, &Baseline::WindowCubic(window.clone())).unwrap();
    assert!(chosen.is_some_and(|n| window.candidates.contains(&n)));
    assert_eq!(
        scene_window(&[], &Baseline::WindowBSpline(window)).unwrap(),
        Some(3)
    );
    assert!(scene_window(&usable, &Baseline::Linear).is_err());
}
