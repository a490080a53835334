//! Bearing-profile tests: expected values are hand calculations of bearings and linear
//! interpolation between bins.

use std::f64::consts::PI;

use super::*;

fn origin() -> SensorPose {
    SensorPose {
        position: Vec2::new(0.0, 0.0),
        heading_rad: 0.0,
    }
}

#[test]
fn projection_puts_the_profile_along_the_bearing_by_hand() {
    // Four bins (0°, 90°, 180°, 270°) from a sensor at (0, 0) facing +x: only 90° has evidence.
    let profile = BearingProfile::full_circle(origin(), vec![0.0, 2.0, 0.0, 0.0]).unwrap();
    // Halfway between bins 0 and 1 (45°) linear interpolation gives 1.0.
    assert!((profile.value_at(PI / 4.0) - 1.0).abs() < 1e-12);
    let region = Region2::new(Vec2::new(-2.0, -2.0), Vec2::new(2.0, 2.0)).unwrap();
    let grid = profile
        .project(
            region,
            1.0,
            &ProjectionConfig {
                normalisation: GridNormalisation::None,
                ..ProjectionConfig::default()
            },
        )
        .unwrap();
    // Cell centres ±0.5, ±1.5. (0.5, 1.5): bearing atan2(1.5, 0.5) = 71.57° → 2·71.57/90.
    let expected = 2.0 * 1.5_f64.atan2(0.5).to_degrees() / 90.0;
    assert!((grid.value(2, 3) - expected).abs() < 1e-12);
    // (−0.5, −1.5) is at 251.57°: between bins 2 and 3, both zero.
    assert!(grid.value(1, 0).abs() < 1e-12);
    // Range limit: (1.5, 1.5) is 2.12 m away, beyond 2 m.
    let limited = profile
        .project(
            region,
            1.0,
            &ProjectionConfig {
                normalisation: GridNormalisation::Max,
                max_range_m: Some(2.0),
                min_range_m: 0.0,
            },
        )
        .unwrap();
    assert!(limited.value(3, 3).abs() < 1e-12);
    let max = limited.values().iter().copied().fold(0.0, f64::max);
    assert!((max - 1.0).abs() < 1e-12);
    let summed = profile
        .project(region, 1.0, &ProjectionConfig::default())
        .unwrap();
    assert!((summed.values().iter().sum::<f64>() - 1.0).abs() < 1e-12);
    // A sector (camera) profile: 0 outside its field of view.
    let sector = BearingProfile::sector(origin(), -0.2, 0.1, vec![1.0; 5]).unwrap();
    assert!((sector.value_at(0.0) - 1.0).abs() < 1e-12);
    assert!(sector.value_at(0.3).abs() < 1e-12);
    assert!(sector.value_at(PI).abs() < 1e-12);
    assert!(BearingProfile::full_circle(origin(), vec![1.0, f64::NAN]).is_err());
    assert!(
        ProjectionConfig {
            max_range_m: Some(1.0),
            min_range_m: 2.0,
            ..ProjectionConfig::default()
        }
        .check()
        .is_err()
    );
}

#[test]
fn a_rotated_sensor_shifts_its_profile_and_configs_reject_unknown_fields() {
    // Heading 90°: bin 0 (the only non-zero one) now points along world +y.
    let pose = SensorPose {
        position: Vec2::new(1.0, 1.0),
        heading_rad: PI / 2.0,
    };
    let profile = BearingProfile::full_circle(pose, vec![1.0, 0.0, 0.0, 0.0]).unwrap();
    assert!((profile.value_at(PI / 2.0) - 1.0).abs() < 1e-12);
    assert!(profile.value_at(0.0).abs() < 1e-12);
    let cfg: ProjectionConfig =
        serde_json::from_str(r#"{"normalisation":"max","max_range_m":5.0,"min_range_m":0.5}"#)
            .unwrap();
    assert_eq!(cfg.normalisation, GridNormalisation::Max);
    assert!(
        serde_json::from_str::<ProjectionConfig>(
            r#"{"normalisation":"max","max_range":5.0,"min_range_m":0.5}"#
        )
        .is_err()
    );
}
