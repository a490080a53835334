//! Tests of the simulated scene: checked settings, reproducible draws, the detector's truth.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::tracks::ImageTrack;

/// A small scene: four cameras, three people, 40 frames.
fn config() -> SceneConfig {
    SceneConfig {
        n_cameras: 4,
        ring_radius_m: 15.0,
        camera_height_m: [3.5, 6.0],
        aim_offset_m: 3.0,
        aim_turn_deg: 10.0,
        image_size: [1280.0, 720.0],
        focal_px: 900.0,
        n_people: 3,
        area_half_m: 6.0,
        speed_m_per_frame: 0.1,
        person_height_m: [1.6, 1.9],
        n_frames: 40,
        p_detect: 0.9,
        false_blobs_per_frame: 0.5,
    }
}

/// A change to the settings.
type Edit = fn(&mut SceneConfig);

#[test]
fn bad_settings_are_errors_not_panics() {
    assert!(config().check().is_ok());
    let cases: [(&str, Edit); 6] = [
        ("camera_height_m", |c| c.camera_height_m = [6.0, 3.5]),
        ("person_height_m", |c| c.person_height_m = [1.9, 1.9]),
        ("image_size", |c| c.image_size = [0.0, 0.0]),
        ("n_frames", |c| c.n_frames = u32::MAX),
        ("n_people", |c| c.n_people = 0),
        ("aim_turn_deg", |c| c.aim_turn_deg = f64::NAN),
    ];
    for (name, set) in cases {
        let mut c = config();
        set(&mut c);
        let err = c.check().unwrap_err();
        assert!(err.to_string().contains(name), "{name}: {err}");
    }
}

#[test]
fn draws_are_reproducible_and_in_range() {
    let scene = config().check().unwrap();
    let draw = |seed: u64| {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let people = scene.walk(&mut rng);
        let cams = scene.cameras(&mut rng).unwrap();
        let seen = scene.detect(&cams[0], &people, 1.0, &mut rng).unwrap();
        (people, cams, seen)
    };
    let (people, cams, seen) = draw(3);
    assert_eq!((people, cams, seen.clone()), draw(3));
    let (people, cams, _) = draw(3);
    assert_eq!(cams.len(), 4);
    for p in &people {
        assert!(p.start < p.end && p.end <= 40 && (1.6..1.9).contains(&p.height));
        assert_eq!(p.ground.len(), (p.end - p.start) as usize);
    }
    assert_eq!(seen.scans.len(), 40);
    for ((_, blobs), labels) in seen.scans.iter().zip(&seen.labels) {
        assert_eq!(blobs.len(), labels.len());
    }
}

#[test]
fn a_blind_detector_reports_nothing() {
    let scene = SceneConfig {
        p_detect: 0.0,
        false_blobs_per_frame: 0.0,
        ..config()
    }
    .check()
    .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let people = scene.walk(&mut rng);
    let cams = scene.cameras(&mut rng).unwrap();
    let seen = scene.detect(&cams[1], &people, 2.0, &mut rng).unwrap();
    assert!(seen.scans.iter().all(|(_, b)| b.is_empty()));
}

#[test]
fn majority_and_overlap_read_the_truth() {
    let track = |frames: Vec<u32>, sources: Vec<(usize, usize)>| ImageTrack {
        id: 0,
        blobs: vec![Blob::point(Vec2::zeros()); frames.len()],
        frames,
        sources,
    };
    let labels = vec![vec![Some(2), None], vec![Some(2)], vec![None, None]];
    let a = track(vec![0, 1, 2], vec![(0, 0), (1, 0), (2, 1)]);
    assert_eq!(majority(&a, &labels), Some(2));
    let b = track(vec![1, 2, 5], vec![(0, 1), (2, 0), (9, 9)]);
    assert_eq!(majority(&b, &labels), None);
    assert_eq!(overlap(&a, &b), 2);
}
