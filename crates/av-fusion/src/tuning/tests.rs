//! Unit tests of the searches' pieces: expected values by hand.

use super::search::fade_with;
use super::*;
use crate::RangeFade;
use crate::scene::ApproachSettings;

#[test]
fn score_table_by_hand() {
    // Contrasts 1..=6, the three largest near a vehicle; two bins split at the 3rd of
    // 6 sorted values (index 3: contrast 4): bin 0 = {1, 2, 3} all far, bin 1 = {4, 5, 6}
    // all near. With Laplace counts: near shares 1/5 and 4/5, far shares 4/5 and 1/5,
    // so ln f₁/f₀ = ln(1/4) and ln 4.
    let peaks: Vec<(f64, bool)> = (1..=6).map(|c| (f64::from(c), c > 3)).collect();
    let (table, counts) = score_table(&peaks, 2).expect("fits");
    assert_eq!(table.contrast_edges, vec![4.0]);
    assert_eq!(counts, vec![[3, 0], [0, 3]]);
    let want = [0.25f64.ln(), 4f64.ln()];
    for (got, want) in table.log_ratios.iter().zip(want) {
        assert!((got - want).abs() < 1e-12, "{got} against {want}");
    }
    // Ties merge edges: six equal contrasts leave one bin.
    let flat: Vec<(f64, bool)> = (0..6).map(|i| (2.0, i % 2 == 0)).collect();
    let (table, _) = score_table(&flat, 3).expect("fits");
    assert!(table.contrast_edges.is_empty());
    assert_eq!(table.log_ratios.len(), 1);
    assert!(score_table(&[], 3).is_err());
    assert!(score_table(&[(f64::NAN, true)], 3).is_err());
}

#[test]
fn fade_coordinates_turn_on_change_and_turn_off() {
    let on = fade_with(None, Some(8.0), None);
    assert_eq!(
        on,
        Some(RangeFade {
            full_weight_m: 8.0,
            power: 1.0
        })
    );
    let half = fade_with(on, None, Some(0.5));
    assert_eq!(half.map(|f| (f.full_weight_m, f.power)), Some((8.0, 0.5)));
    assert_eq!(fade_with(half, Some(0.0), None), None);
    assert_eq!(fade_with(None, None, Some(2.0)), None);
}

#[test]
fn approaches_are_all_or_valid_indices_or_keys() {
    assert_eq!(approaches_in("all").expect("all"), Approach::ALL.to_vec());
    assert_eq!(
        approaches_in("5, 2").expect("list"),
        vec![Approach::AudioVideoProduct, Approach::AudioVideoSum]
    );
    assert_eq!(
        approaches_in("video_product,0").expect("list"),
        vec![Approach::VideoProduct, Approach::AudioSum]
    );
    assert!(approaches_in("6").is_err());
    assert!(approaches_in("1,x").is_err());
    assert!(approaches_in("").is_err());
    let err = approaches_in("audio").expect_err("not a key").to_string();
    assert!(err.contains("audio_video_product"), "{err}");
}

/// Settings for the search tests: the committed count-aware multi-vehicle ones of an approach.
fn some_settings() -> ApproachSettings {
    let text = include_str!("../../../../fixtures/scenarios/av-fusion-road.toml");
    let table: toml::Table = toml::from_str(text).expect("the configuration parses");
    let p: Params = table["params"]["scene"]
        .clone()
        .try_into()
        .expect("its parameters parse");
    *p.count_aware.multi.get(Approach::AudioProduct)
}

#[test]
fn coordinate_search_finds_a_separable_optimum_and_keeps_ties() {
    use super::search::{Coordinate, coordinate_search};
    let coords: Vec<Coordinate> = vec![
        ("kappa", vec![0.1, 0.3, 0.5], |s, v| {
            s.relative_threshold = v
        }),
        ("p_d", vec![0.6, 0.8, 0.95], |s, v| s.p_detect = v),
    ];
    // Brute force over the 3 × 3 grid of a separable objective: κ = 0.3, p_d = 0.8.
    let j = |s: &ApproachSettings| -> Result<f64> {
        Ok(-(s.relative_threshold - 0.3).powi(2) - (s.p_detect - 0.8).powi(2))
    };
    let start = some_settings();
    let mut rows = Vec::new();
    let (end, score) = coordinate_search(
        Approach::AudioProduct,
        (start, j(&start).expect("j")),
        &coords,
        3,
        &j,
        &mut rows,
    )
    .expect("searches");
    assert_eq!((end.relative_threshold, end.p_detect), (0.3, 0.8));
    assert!(score.abs() < 1e-15, "{score}");
    // Round 1 moves both coordinates, round 2 confirms them and stops: 12 rows, one kept per
    // step, the kept ones the optimum's values.
    assert_eq!(rows.len(), 12);
    let kept: Vec<(usize, &str, f64)> = rows
        .iter()
        .filter(|r| r.kept)
        .map(|r| (r.round, r.coordinate, r.value))
        .collect();
    assert_eq!(
        kept,
        vec![
            (1, "kappa", 0.3),
            (1, "p_d", 0.8),
            (2, "kappa", 0.3),
            (2, "p_d", 0.8)
        ]
    );
    // A flat objective never moves the start.
    let flat = |_: &ApproachSettings| -> Result<f64> { Ok(1.0) };
    let mut rows = Vec::new();
    let (end, _) = coordinate_search(
        Approach::AudioProduct,
        (start, 1.0),
        &coords,
        3,
        &flat,
        &mut rows,
    )
    .expect("searches");
    assert_eq!(end, start);
    assert_eq!(rows.len(), 6, "one round: nothing changed");
}
