//! Unit tests of the scene's parameter checks, on the parameters of the committed road
//! configuration.

use sensors_audio::BeamformConfig;

use crate::Modalities;

use super::*;

/// The committed configuration's parameters.
fn committed() -> Params {
    let text = include_str!("../../../../fixtures/scenarios/av-fusion-road.toml");
    let table: toml::Table = toml::from_str(text).expect("the configuration parses");
    table["params"]["scene"]
        .clone()
        .try_into()
        .expect("its parameters parse")
}

/// The checks' message on `p` with reported seed `seed`.
fn rejected(p: &Params, seed: u64) -> String {
    check_params(p, seed).expect_err("rejected").to_string()
}

#[test]
fn the_committed_parameters_pass() {
    let p = committed();
    check_params(&p, 1801).expect("they pass");
    assert_eq!(
        run_specs(&p).expect("runs").len(),
        p.passes.len() + p.multi.len()
    );
    assert_eq!(Approach::AudioVideoSum.settings_key(), "audio_video_sum");
    assert_eq!(Approach::AudioProduct.settings_key(), "audio_product");
}

#[test]
fn huge_or_broken_durations_and_sizes_are_errors_before_any_run() {
    // pad_s = 1e300 panicked with "capacity overflow" and 1e6 aborted asking for 128 GB.
    for pad in [1e300, 1e6, f64::NAN, -1.0, f64::INFINITY] {
        let p = Params {
            pad_s: pad,
            ..committed()
        };
        assert!(rejected(&p, 1801).contains("pad_s"), "{pad}");
    }
    let mut p = committed();
    p.video.width = 0;
    assert!(rejected(&p, 1801).contains("video"));
    let mut p = committed();
    p.passes[0].duration_s = 1e9;
    assert!(rejected(&p, 1801).contains("duration_s"));
    let mut p = committed();
    if let Some(v) = p.multi.first_mut().and_then(|run| run.first_mut()) {
        v.enter_s = 1e7;
        assert!(rejected(&p, 1801).contains("enter_s"));
    }
}

#[test]
fn bad_score_settings_and_reused_seeds_are_rejected_before_any_run() {
    let good = committed();
    // A malformed table, even of an unscored approach.
    let mut p = good.clone();
    let table = p
        .multi_peak_scores
        .get_mut("audio_video_sum")
        .expect("the table exists");
    table.log_ratios.pop();
    let err = rejected(&p, 1801);
    assert!(err.contains("multi_peak_scores.audio_video_sum"), "{err}");
    // An unknown approach.
    let mut p = good.clone();
    let any = p
        .multi_peak_scores
        .values()
        .next()
        .expect("a table")
        .clone();
    p.multi_peak_scores.insert("audio_and_video".into(), any);
    let err = rejected(&p, 1801);
    assert!(err.contains("unknown approach"), "{err}");
    // Scores in the count-aware single-vehicle reference.
    let mut p = good.clone();
    p.count_aware
        .single
        .get_mut(Approach::AudioVideoProduct)
        .scored = true;
    let err = rejected(&p, 1801);
    assert!(err.contains("reference is unscored"), "{err}");
    // A multi-vehicle beamformer with other beams, or a bad one.
    let mut p = good.clone();
    p.audio.multi_beamform = Some(BeamformConfig {
        n_beams: 18,
        ..p.audio.beamform.clone()
    });
    let err = rejected(&p, 1801);
    assert!(err.contains("multi_beamform"), "{err}");
    p.audio.multi_beamform = Some(BeamformConfig {
        method: sensors_audio::Method::Mvdr,
        mvdr_forgetting: 1.5,
        ..p.audio.beamform.clone()
    });
    let err = rejected(&p, 1801);
    assert!(err.contains("mvdr_forgetting"), "{err}");
    // The reported seed among the tuning seeds, a fresh seed among them or reported.
    let err = rejected(&good, 2);
    assert!(
        err.contains("tuning and fitting seeds and the reported seed share seed 2"),
        "{err}"
    );
    let mut p = good.clone();
    p.fresh_seeds.push(3);
    let err = rejected(&p, 1801);
    assert!(err.contains("fresh_seeds share seed 3"), "{err}");
    let err = rejected(&good, good.fresh_seeds[0]);
    assert!(
        err.contains("the reported seed and fresh_seeds share"),
        "{err}"
    );
    // A search without rounds or with unbounded ones, or a non-finite error weight.
    for rounds in [0, 1000] {
        let mut p = good.clone();
        p.tuning.max_rounds = rounds;
        assert!(rejected(&p, 1801).contains("max_rounds"), "{rounds}");
    }
    let mut p = good.clone();
    p.tuning.error_weight_per_m = f64::NAN;
    assert!(rejected(&p, 1801).contains("error_weight_per_m"));
    let mut p = good.clone();
    p.tuning.p_detect = vec![0.5; 65];
    assert!(rejected(&p, 1801).contains("p_detect"));
    // No fresh seeds, or more than the bound.
    let mut p = good.clone();
    p.fresh_seeds.clear();
    assert!(rejected(&p, 1801).contains("fresh_seeds: 0 seeds"));
    p.fresh_seeds = (10_000..10_000 + MAX_SEEDS as u64 + 1).collect();
    assert!(rejected(&p, 1801).contains(&format!("{} seeds; 1 to {MAX_SEEDS}", MAX_SEEDS + 1)));
}

#[test]
fn vehicles_enter_the_region_on_their_lane_at_their_time() {
    // +x traffic on the lower lane (y = 10 − 1.5), −x traffic on the upper one.
    let v = Vehicle::new(10.0, 1, 0.6);
    assert!((v.at(0.6) - Vec2::new(0.0, 8.5)).norm() < 1e-12);
    let w = Vehicle::new(10.0, -1, 1.0);
    assert!((w.at(1.0) - Vec2::new(35.0, 11.5)).norm() < 1e-12);
    assert!((w.at(2.0) - Vec2::new(25.0, 11.5)).norm() < 1e-12);
}

#[test]
fn approaches_keep_their_names_keys_and_order() {
    // The names in reports and metric names, in the order of the report's columns.
    let table = [
        ("audio, sum", Modalities::Audio, false),
        ("video, sum", Modalities::Video, false),
        ("audio+video, sum", Modalities::Both, false),
        ("audio, product", Modalities::Audio, true),
        ("video, product", Modalities::Video, true),
        ("audio+video, product", Modalities::Both, true),
    ];
    for (i, (a, (name, modalities, product))) in Approach::ALL.into_iter().zip(table).enumerate() {
        assert_eq!(a.name(), name);
        assert_eq!(a.to_string(), name);
        assert_eq!(a.modalities(), modalities);
        assert_eq!(a.is_product(), product);
        assert_eq!(Approach::new(modalities, product), a);
        assert_eq!(a.index(), i);
        assert_eq!(Approach::from_index(i), Some(a));
        // The settings key is the name without punctuation, words joined by `_`.
        let key = name
            .replace([',', '+'], "")
            .replace(' ', "_")
            .replace("audiovideo", "audio_video");
        assert_eq!(a.settings_key(), key);
        assert_eq!(Approach::from_settings_key(&key), Some(a));
    }
    assert_eq!(Approach::from_index(6), None);
    assert_eq!(Approach::from_settings_key("audio"), None);
}

#[test]
fn per_approach_values_are_keyed_by_approach() {
    let names = PerApproach::from_fn(Approach::name);
    let mut order = Vec::new();
    let indices = PerApproach::from_fn(|a| {
        order.push(a);
        a.index()
    });
    assert_eq!(order, Approach::ALL.to_vec());
    for (a, i) in indices.iter() {
        assert_eq!(*i, a.index());
        assert_eq!(*names.get(a), a.name());
    }
    let mut doubled = indices.map(|_, i| 2 * i);
    *doubled.get_mut(Approach::VideoSum) = 7;
    assert_eq!(doubled.audio_video_product, 10);
    assert_eq!(doubled.video_sum, 7);
    let failed: Result<PerApproach<usize>, Approach> =
        PerApproach::try_from_fn(|a| if a.is_product() { Err(a) } else { Ok(0) });
    assert_eq!(failed, Err(Approach::AudioProduct));
    // The committed settings tables are keyed by the approaches' settings keys.
    let p = committed();
    let single = &p.count_aware.single;
    assert!(
        single
            .get(Approach::AudioVideoProduct)
            .product_floor
            .is_some()
    );
    assert!(single.get(Approach::AudioVideoSum).product_floor.is_none());
}

#[test]
fn settings_round_trip_through_toml() {
    // The one configuration's file is written by serialising a `Settings`; it must read back
    // to the same values, to the bit, with absent options left out.
    let p = committed();
    for settings in [&p.count_aware.single, &p.count_aware.multi] {
        let text =
            toml::to_string(&toml::Table::try_from(settings).expect("serialises")).expect("writes");
        let back: Settings = toml::from_str(&text).expect("reads back");
        assert_eq!(&back, settings, "{text}");
    }
}
