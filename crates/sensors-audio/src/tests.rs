//! Tests: every expected value comes from a route independent of the code under test (the
//! simulator's geometric propagation for the beamformers, closed forms for the simulator, hand
//! calculations for peaks and projections).

use std::f64::consts::{FRAC_PI_2, TAU};
use std::io::Cursor;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracker_model::{FrameClock, Vec2};

use crate::*;

const FS: u32 = 16_000;

fn origin() -> SensorPose {
    SensorPose {
        position: Vec2::new(0.0, 0.0),
        heading_rad: 0.0,
    }
}

fn source_at(bearing_rad: f64, range_m: f64, signal: SourceSignal) -> Source {
    Source {
        path: SourcePath::Fixed {
            position: Vec2::new(range_m * bearing_rad.cos(), range_m * bearing_rad.sin()),
        },
        height_m: 1.0,
        level: 1.0,
        signal,
    }
}

/// Two white-noise sources 20 m away at bearings `a` and `b` (radians), recorded for
/// `duration_s` in a diffuse field of 16 directions at `snr_db`.
fn two_noise_sources(a: f64, b: f64, snr_db: f64, duration_s: f64, seed: u64) -> Recording {
    let sources = [
        source_at(a, 20.0, SourceSignal::WhiteNoise),
        source_at(b, 20.0, SourceSignal::WhiteNoise),
    ];
    let noise = BackgroundNoise {
        snr_db,
        field: NoiseField::Diffuse { n_directions: 16 },
    };
    record(&sources, duration_s, Some(noise), seed)
}

fn record(
    sources: &[Source],
    duration_s: f64,
    noise: Option<BackgroundNoise>,
    seed: u64,
) -> Recording {
    let config = SimulationConfig {
        noise,
        ..SimulationConfig::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    simulate(
        &MicArray::default(),
        &origin(),
        sources,
        duration_s,
        &config,
        &mut rng,
    )
    .unwrap()
}

fn config(method: Method, weighting: Weighting) -> BeamformConfig {
    BeamformConfig {
        method,
        weighting,
        ..BeamformConfig::default()
    }
}

/// Mean beamform over all frames of a recording.
fn mean_beamform(config: &BeamformConfig, rec: &Recording) -> Beamform {
    let mut bf = config.check(&MicArray::default()).unwrap();
    let frames = bf.beamform(rec).unwrap();
    let mut energies = vec![0.0; config.n_beams];
    for f in &frames {
        for (e, v) in energies.iter_mut().zip(&f.energies) {
            *e += v / frames.len() as f64;
        }
    }
    Beamform {
        time_s: 0.0,
        energies,
    }
}

fn argmax(v: &[f64]) -> usize {
    v.iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap()
        .0
}

fn angle_error_rad(a: f64, b: f64) -> f64 {
    tracker_model::wrap_angle_rad(a - b).abs()
}

#[test]
fn far_field_sources_at_every_beam_peak_in_that_beam_for_both_methods() {
    for b in 0..36 {
        let theta = TAU * b as f64 / 36.0;
        // 500 m: the wavefront's curvature over a 12 cm aperture is ~1e-5 m, i.e. far field.
        let rec = record(
            &[source_at(theta, 500.0, SourceSignal::WhiteNoise)],
            0.07,
            None,
            b as u64,
        );
        for method in [Method::TimeDomain, Method::FrequencyDomain] {
            let bf = mean_beamform(&config(method, Weighting::Plain), &rec);
            assert_eq!(
                argmax(&bf.energies),
                b,
                "{method:?}, source at beam {b}: {:?}",
                bf.energies
            );
            let doa = bf.doa().unwrap();
            assert!(
                angle_error_rad(doa.bearing_rad, theta) < 1f64.to_radians(),
                "{method:?} beam {b}: {doa:?}"
            );
        }
    }
}

#[test]
fn a_source_between_beams_splits_its_energy_between_the_two_neighbours() {
    for b in [0, 7, 13, 22, 31] {
        let theta = TAU * (b as f64 + 0.5) / 36.0;
        let rec = record(
            &[source_at(theta, 500.0, SourceSignal::WhiteNoise)],
            0.2,
            None,
            100 + b as u64,
        );
        for method in [Method::TimeDomain, Method::FrequencyDomain] {
            let bf = mean_beamform(&config(method, Weighting::Plain), &rec);
            let e = &bf.energies;
            let (lo, hi) = (e[b], e[(b + 1) % 36]);
            let mut sorted = e.clone();
            sorted.sort_by(|x, y| y.total_cmp(x));
            // The two neighbours are the two strongest beams, within 1 % of each other (the
            // beam pattern is symmetric to second order about the source direction).
            assert!(
                lo.min(hi) >= sorted[1] * (1.0 - 1e-12),
                "{method:?} {b}: {e:?}"
            );
            assert!(
                (lo - hi).abs() / lo.max(hi) < 0.01,
                "{method:?} {b}: {lo} vs {hi}"
            );
            let doa = bf.doa().unwrap();
            assert!(
                angle_error_rad(doa.bearing_rad, theta) < 1f64.to_radians(),
                "{method:?} {b}: {doa:?}"
            );
        }
    }
}

/// Band-limited: a sum of tones 600–3000 Hz, well inside the 200–4000 Hz band and away from
/// the FIR's transition bands. The two routes differ by (a) the time domain summing
/// 512 − 64 − 2·(margin) ≈ 430 samples where the frequency domain sums all 512 (circularly),
/// (b) the 65-tap FIR's pass-band ripple (< 0.1 %) and the 8-tap fractional-delay sinc's
/// amplitude error (< 1 % at 3 kHz), (c) the rectangular window's leakage. Each is at most a
/// few per cent, so normalised beam patterns must agree to 3 % of the maximum.
#[test]
fn time_and_frequency_domain_beamforms_agree_for_band_limited_signals() {
    let fs = f64::from(FS);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let tones: Vec<(f64, f64)> = (0..12)
        .map(|i| {
            (
                600.0 + 200.0 * i as f64 + 37.0,
                TAU * rand::RngExt::random::<f64>(&mut rng),
            )
        })
        .collect();
    let samples: Vec<f32> = (0..8000)
        .map(|k| {
            tones
                .iter()
                .map(|(f, p)| (TAU * f * k as f64 / fs + p).sin())
                .sum::<f64>() as f32
        })
        .collect();
    for bearing_deg in [0.0, 37.0, 125.0, 250.0] {
        let rec = record(
            &[source_at(
                f64::to_radians(bearing_deg),
                10.0,
                SourceSignal::User {
                    samples: samples.clone(),
                },
            )],
            0.45,
            None,
            1,
        );
        // Skip the first 0.1 s, before the tones reach the array.
        let rec = Recording::new(
            FS,
            0.1,
            rec.channels.iter().map(|c| c[1600..].to_vec()).collect(),
        )
        .unwrap();
        let td = mean_beamform(&config(Method::TimeDomain, Weighting::Plain), &rec);
        let fd = mean_beamform(
            &BeamformConfig {
                window: Window::Rectangular,
                ..config(Method::FrequencyDomain, Weighting::Plain)
            },
            &rec,
        );
        let (mt, mf) = (
            td.energies.iter().copied().fold(0.0, f64::max),
            fd.energies.iter().copied().fold(0.0, f64::max),
        );
        // Same absolute scale too (mean power), within the same budget.
        assert!(
            (mt - mf).abs() / mf < 0.03,
            "{bearing_deg}°: max {mt} vs {mf}"
        );
        for (b, (t, f)) in td.energies.iter().zip(&fd.energies).enumerate() {
            assert!(
                (t / mt - f / mf).abs() < 0.03,
                "{bearing_deg}° beam {b}: {} vs {}",
                t / mt,
                f / mf
            );
        }
    }
}

#[test]
fn fractional_delay_synthesis_matches_an_analytic_sinusoid() {
    let fs = f64::from(FS);
    let f = 1234.5;
    let samples: Vec<f32> = (0..4000)
        .map(|k| (TAU * f * k as f64 / fs).sin() as f32)
        .collect();
    // Same height as the array: the path is horizontal and the distance exact.
    let src = Source {
        path: SourcePath::Fixed {
            position: Vec2::new(3.7, 1.3),
        },
        height_m: 1.0,
        level: 1.0,
        signal: SourceSignal::User { samples },
    };
    let rec = record(&[src], 0.2, None, 0);
    let c = SOUND_SPEED_MPS;
    for (m, p) in MicArray::default().positions_m().iter().enumerate() {
        let r = (3.7 - p[0]).hypot(1.3 - p[1]);
        let arrival = r / c;
        for (i, &y) in rec.channels[m].iter().enumerate() {
            let t = i as f64 / fs;
            // Away from the onset, where the interpolator still sees the silence before it.
            if t > arrival + 20.0 / fs {
                let expected = (TAU * f * (t - arrival)).sin() / r;
                assert!(
                    (f64::from(y) - expected).abs() < 1e-3 / r,
                    "mic {m} sample {i}: {y} vs {expected}"
                );
            }
        }
    }
}

#[test]
fn ground_reflection_adds_an_image_source_arrival() {
    // A Gaussian-windowed 2 kHz burst (σ = 1 ms): band-limited, so its delayed copies have a
    // closed form. Direct path 10.0125 m and image path 10.1119 m differ by 4.6 samples.
    let fs = f64::from(FS);
    let (f, sigma, tc) = (2000.0, 1e-3, 0.01);
    let g = |t: f64| (-(t - tc).powi(2) / (2.0 * sigma * sigma)).exp() * (TAU * f * (t - tc)).sin();
    let samples: Vec<f32> = (0..400).map(|k| g(k as f64 / fs) as f32).collect();
    let src = Source {
        path: SourcePath::Fixed {
            position: Vec2::new(10.0, 0.0),
        },
        height_m: 0.5,
        level: 1.0,
        signal: SourceSignal::User { samples },
    };
    let config = SimulationConfig {
        ground_reflection: Some(0.6),
        ..SimulationConfig::default()
    };
    let array = MicArray::new(&[[0.0, 0.0]]).unwrap();
    let rec = simulate(
        &array,
        &origin(),
        &[src],
        0.1,
        &config,
        &mut ChaCha8Rng::seed_from_u64(0),
    )
    .unwrap();
    let d1 = (100.0_f64 + 0.25).sqrt(); // heights 0.5 (source) and 1.0 (array)
    let d2 = (100.0_f64 + 2.25).sqrt(); // the image at −0.5
    for (i, &y) in rec.channels[0].iter().enumerate() {
        let t = i as f64 / fs;
        let expected = g(t - d1 / SOUND_SPEED_MPS) / d1 + 0.6 * g(t - d2 / SOUND_SPEED_MPS) / d2;
        assert!(
            (f64::from(y) - expected).abs() < 1e-3 / d1,
            "sample {i}: {y} vs {expected}"
        );
    }
}

#[test]
fn a_moving_source_matches_the_closed_form_emission_time() {
    // A 900 Hz tone on a source passing a single microphone at 20 m/s, 5 m abeam, same height.
    // For straight-line motion the emission time solves a quadratic: with A = x0 + v·t and
    // u = t − t_e, (c² − v²)u² + 2vA·u − (A² + 25) = 0 (the Doppler shift comes with it).
    let fs = f64::from(FS);
    let (f, v, x0, c) = (900.0, 20.0, -8.0, SOUND_SPEED_MPS);
    let samples: Vec<f32> = (0..16_000)
        .map(|k| (TAU * f * k as f64 / fs).sin() as f32)
        .collect();
    let src = Source {
        path: SourcePath::Waypoints {
            times_s: vec![0.0, 10.0],
            positions: vec![Vec2::new(x0, 5.0), Vec2::new(x0 + 10.0 * v, 5.0)],
        },
        height_m: 1.0,
        level: 1.0,
        signal: SourceSignal::User { samples },
    };
    let array = MicArray::new(&[[0.0, 0.0]]).unwrap();
    let rec = simulate(
        &array,
        &origin(),
        &[src],
        0.8,
        &SimulationConfig::default(),
        &mut ChaCha8Rng::seed_from_u64(0),
    )
    .unwrap();
    for (i, &y) in rec.channels[0].iter().enumerate() {
        let t = i as f64 / fs;
        let a = x0 + v * t;
        let (qa, qb, qc) = (c * c - v * v, 2.0 * v * a, -(a * a + 25.0));
        let u = (-qb + (qb * qb - 4.0 * qa * qc).sqrt()) / (2.0 * qa);
        let (te, r) = (t - u, c * u);
        if te > 20.0 / fs {
            let expected = (TAU * f * te).sin() / r;
            assert!(
                (f64::from(y) - expected).abs() < 1e-3 / r,
                "sample {i}: {y} vs {expected}"
            );
        }
    }
}

#[test]
fn background_noise_has_the_requested_snr() {
    let src = [source_at(1.0, 15.0, SourceSignal::PinkNoise)];
    let clean = record(&src, 0.3, None, 9);
    for snr_db in [-5.0, 10.0, 30.0] {
        for field in [
            NoiseField::Uncorrelated,
            NoiseField::Diffuse { n_directions: 16 },
        ] {
            // The noise is drawn after the sources, so the same seed gives the same clean part.
            let noisy = record(&src, 0.3, Some(BackgroundNoise { snr_db, field }), 9);
            let noise: Vec<Vec<f32>> = noisy
                .channels
                .iter()
                .zip(&clean.channels)
                .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect())
                .collect();
            let got = 10.0
                * (simulate::mean_power(&clean.channels) / simulate::mean_power(&noise)).log10();
            assert!(
                (got - snr_db).abs() < 0.05,
                "{field:?}: {got} dB vs {snr_db} dB"
            );
        }
    }
}

#[test]
fn two_sources_sixty_degrees_apart_give_two_peaks_at_20_db() {
    let (a, b) = (30f64.to_radians(), 90f64.to_radians());
    for seed in 0..3 {
        let rec = two_noise_sources(a, b, 20.0, 0.25, 40 + seed);
        for (method, weighting) in [
            (Method::TimeDomain, Weighting::Plain),
            (Method::FrequencyDomain, Weighting::Plain),
            (Method::FrequencyDomain, Weighting::Phat),
        ] {
            let bf = mean_beamform(&config(method, weighting), &rec);
            let peaks = bf.peaks(&PeakSearch::default());
            assert!(
                peaks.len() >= 2,
                "{method:?} {weighting:?} seed {seed}: {:?}",
                bf.energies
            );
            let mut found: Vec<f64> = peaks[..2].iter().map(|p| p.bearing_rad).collect();
            found.sort_by(f64::total_cmp);
            assert!(
                angle_error_rad(found[0], a) < 8f64.to_radians(),
                "{method:?} {weighting:?}: {found:?}"
            );
            assert!(
                angle_error_rad(found[1], b) < 8f64.to_radians(),
                "{method:?} {weighting:?}: {found:?}"
            );
        }
    }
}

#[test]
fn uniform_circular_arrays_find_the_source() {
    let array = MicArray::uniform_circular(8, 0.2).unwrap();
    let theta = 200f64.to_radians();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let rec = simulate(
        &array,
        &origin(),
        &[source_at(theta, 30.0, SourceSignal::PinkNoise)],
        0.1,
        &SimulationConfig::default(),
        &mut rng,
    )
    .unwrap();
    for method in [Method::TimeDomain, Method::FrequencyDomain] {
        let mut bf = BeamformConfig {
            method,
            frame_len: 1024,
            hop: 1024,
            ..BeamformConfig::default()
        }
        .check(&array)
        .unwrap();
        let doa = bf.beamform(&rec).unwrap()[0].doa().unwrap();
        assert!(
            angle_error_rad(doa.bearing_rad, theta) < 2f64.to_radians(),
            "{method:?}: {doa:?}"
        );
    }
}

#[test]
fn a_rotated_node_reports_bearings_in_its_own_frame() {
    // Node facing 90°: a source at world bearing 120° is at 30° in the array frame.
    let pose = SensorPose {
        position: Vec2::new(5.0, -2.0),
        heading_rad: FRAC_PI_2,
    };
    let world = 120f64.to_radians();
    let src = Source {
        path: SourcePath::Fixed {
            position: pose.position + Vec2::new(world.cos(), world.sin()) * 25.0,
        },
        ..source_at(0.0, 1.0, SourceSignal::WhiteNoise)
    };
    let rec = simulate(
        &MicArray::default(),
        &pose,
        &[src],
        0.1,
        &SimulationConfig::default(),
        &mut ChaCha8Rng::seed_from_u64(2),
    )
    .unwrap();
    let bf = mean_beamform(&BeamformConfig::default(), &rec);
    let doa = bf.doa().unwrap();
    assert!(
        angle_error_rad(doa.bearing_rad, 30f64.to_radians()) < 2f64.to_radians(),
        "{doa:?}"
    );
    // The profile puts the evidence back at world 120°.
    let profile = bf
        .bearing_profile(pose, EnergyScaling::MinSubtracted)
        .unwrap();
    let best = (0..360)
        .map(|d| f64::from(d).to_radians())
        .max_by(|x, y| profile.value_at(*x).total_cmp(&profile.value_at(*y)))
        .unwrap();
    assert!(
        angle_error_rad(best, world) < 6f64.to_radians(),
        "{}",
        best.to_degrees()
    );
}

#[test]
fn parabolic_refinement_finds_the_vertex_of_a_sampled_parabola() {
    // E(x) = 10 − (x − 7.3)² around beam 7: the vertex is at 7.3 beams (hand calculation).
    let mut energies = vec![0.0; 36];
    for (b, e) in energies.iter_mut().enumerate().take(10).skip(5) {
        *e = 10.0 - (b as f64 - 7.3).powi(2);
    }
    let bf = Beamform {
        time_s: 0.0,
        energies,
    };
    let doa = bf.doa().unwrap();
    assert_eq!(doa.beam, 7);
    assert!((doa.bearing_rad - 7.3 * TAU / 36.0).abs() < 1e-12);
    // Wrap-around: a peak at beam 0 with a stronger left neighbour refines below 0 → near 2π.
    let mut energies = vec![0.0; 36];
    energies[35] = 8.0;
    energies[0] = 9.0;
    energies[1] = 4.0;
    let doa = Beamform {
        time_s: 0.0,
        energies,
    }
    .doa()
    .unwrap();
    let offset = 0.5 * (8.0 - 4.0) / (8.0 - 18.0 + 4.0); // = −1/3 beam
    assert!(
        (doa.bearing_rad - (TAU + offset * TAU / 36.0)).abs() < 1e-12,
        "{doa:?}"
    );
}

#[test]
fn peaks_are_local_maxima_above_the_floor_strongest_first() {
    let mut energies = vec![1.0; 36];
    energies[3] = 5.0;
    energies[20] = 9.0;
    energies[30] = 1.2; // below min + 0.1·(max − min) = 1.8
    let bf = Beamform {
        time_s: 0.0,
        energies,
    };
    let peaks = bf.peaks(&PeakSearch::default());
    assert_eq!(
        peaks.iter().map(|p| p.beam).collect::<Vec<_>>(),
        vec![20, 3]
    );
    assert!(
        Beamform {
            time_s: 0.0,
            energies: vec![2.0; 36]
        }
        .peaks(&PeakSearch::default())
        .is_empty()
    );
}

#[test]
fn beamforms_are_time_stamped_at_frame_centres() {
    let rec = Recording::new(FS, 10.0, vec![vec![0.1_f32; 2048]; 4]).unwrap();
    let mut bf = BeamformConfig {
        hop: 256,
        ..BeamformConfig::default()
    }
    .check(&MicArray::default())
    .unwrap();
    let out = bf.beamform(&rec).unwrap();
    // Frames start at 0, 256, …, 1536: seven of them, centred 256 samples after their start.
    assert_eq!(out.len(), 7);
    for (k, b) in out.iter().enumerate() {
        assert!((b.time_s - (10.0 + (256.0 * k as f64 + 256.0) / 16_000.0)).abs() < 1e-12);
    }
    let clock = FrameClock::new(10.0, 0.032).unwrap();
    // 10.032 s is frame 1's tick; 10.048 s lies halfway between ticks 1 and 2 and goes to 2.
    assert_eq!(out[1].frame(&clock).unwrap(), 1);
    assert_eq!(out[2].frame(&clock).unwrap(), 2);
}

#[test]
fn degenerate_input_gets_typed_errors() {
    let array = MicArray::default();
    for method in [Method::TimeDomain, Method::FrequencyDomain] {
        let mut bf = config(method, Weighting::Plain).check(&array).unwrap();
        let good = vec![0.0_f32; 512];
        assert!(matches!(bf.frame_energies(&[]), Err(Error::NoChannels)));
        assert!(matches!(
            bf.frame_energies(&[&good, &good, &good]),
            Err(Error::ChannelCountMismatch {
                expected: 4,
                got: 3
            })
        ));
        let mut bad = good.clone();
        bad[17] = f32::NAN;
        assert!(matches!(
            bf.frame_energies(&[&good, &good, &bad, &good]),
            Err(Error::NonFiniteSample {
                channel: 2,
                index: 17,
                ..
            })
        ));
        let short = vec![0.0_f32; 100];
        assert!(matches!(
            bf.frame_energies(&[&short, &short, &short, &short]),
            Err(Error::FrameTooShort {
                frame_len: 100,
                required: 512
            })
        ));
        // A frame shorter than the array's largest delay (~5.5 samples at 16 kHz).
        let tiny = BeamformConfig {
            frame_len: 5,
            hop: 5,
            ..config(method, Weighting::Plain)
        };
        assert!(matches!(
            tiny.check(&array),
            Err(Error::FrameTooShort { frame_len: 5, .. })
        ));
        let zero_rate = BeamformConfig {
            sample_rate_hz: 0,
            ..config(method, Weighting::Plain)
        };
        assert!(matches!(
            zero_rate.check(&array),
            Err(Error::ZeroSampleRate)
        ));
    }
    // A 10 m aperture needs ~470 samples of delay: a 512-sample time-domain frame is too short.
    let wide = MicArray::new(&[[0.0, 0.0], [10.0, 0.0]]).unwrap();
    assert!(matches!(
        config(Method::TimeDomain, Weighting::Plain).check(&wide),
        Err(Error::FrameTooShort { frame_len: 512, .. })
    ));
    assert!(matches!(
        Recording::new(0, 0.0, vec![vec![0.0; 4]]),
        Err(Error::ZeroSampleRate)
    ));
    assert!(matches!(
        Recording::new(FS, 0.0, vec![]),
        Err(Error::NoChannels)
    ));
    assert!(matches!(
        Recording::new(FS, 0.0, vec![vec![0.0; 4], vec![0.0; 3]]),
        Err(Error::ChannelLengthMismatch {
            channel: 1,
            expected: 4,
            got: 3
        })
    ));
    assert!(matches!(
        config(Method::TimeDomain, Weighting::Phat).check(&array),
        Err(Error::Unsupported(_))
    ));
    let rec = Recording::new(FS, 0.0, vec![vec![0.0; 1024]; 3]).unwrap();
    let mut bf = BeamformConfig::default().check(&array).unwrap();
    assert!(matches!(
        bf.beamform(&rec),
        Err(Error::ChannelCountMismatch {
            expected: 4,
            got: 3
        })
    ));
    assert!(MicArray::new(&[]).is_err());
    assert!(MicArray::new(&[[0.0, 0.0], [0.0, 0.0]]).is_err());
    // Simulated SNR without any signal is an error, not a division by zero.
    let silent = Source {
        level: 0.0,
        ..source_at(0.0, 5.0, SourceSignal::WhiteNoise)
    };
    let cfg = SimulationConfig {
        noise: Some(BackgroundNoise {
            snr_db: 10.0,
            field: NoiseField::Uncorrelated,
        }),
        ..SimulationConfig::default()
    };
    assert!(
        simulate(
            &array,
            &origin(),
            &[silent],
            0.1,
            &cfg,
            &mut ChaCha8Rng::seed_from_u64(0)
        )
        .is_err()
    );
}

#[test]
fn wav_round_trip_is_lossless_and_integer_pcm_is_scaled() {
    let rec = record(
        &[source_at(0.3, 5.0, SourceSignal::PinkNoise)],
        0.05,
        None,
        11,
    );
    let mut buf = Cursor::new(Vec::new());
    rec.write_wav(&mut buf).unwrap();
    let back = Recording::read_wav(Cursor::new(buf.into_inner()), 0.0).unwrap();
    assert_eq!(back, rec);

    // 16-bit PCM written by hound directly: 16384 is 0.5 of full scale.
    let spec = hound::WavSpec {
        channels: 2,
        sample_rate: 8000,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut buf = Cursor::new(Vec::new());
    {
        let mut w = hound::WavWriter::new(&mut buf, spec).unwrap();
        for s in [16384_i16, -32768, 0, 8192] {
            w.write_sample(s).unwrap();
        }
        w.finalize().unwrap();
    }
    let pcm = Recording::read_wav(Cursor::new(buf.into_inner()), 2.0).unwrap();
    assert_eq!(pcm.sample_rate_hz, 8000);
    assert_eq!(pcm.channels, vec![vec![0.5, 0.0], vec![-1.0, 0.25]]);
    assert!(matches!(
        Recording::read_wav(Cursor::new(b"not a wav".to_vec()), 0.0),
        Err(Error::Wav(_))
    ));
    // A sample rate whose byte rate overflows the header's 32 bits (found by the fuzzer: hound
    // multiplies unchecked) is a typed error, not a panic or a wrapped header.
    let fast = Recording::new(1_073_741_855, 0.0, vec![vec![0.0; 4]]).unwrap();
    assert!(matches!(
        fast.write_wav(Cursor::new(Vec::new())),
        Err(Error::Unsupported(_))
    ));
}

#[test]
fn configs_reject_unknown_fields() {
    let ok: BeamformConfig = toml::from_str("n_beams = 72\nmethod = \"time_domain\"").unwrap();
    assert_eq!(ok.n_beams, 72);
    assert!(toml::from_str::<BeamformConfig>("n_beam = 72").is_err());
    assert!(toml::from_str::<SimulationConfig>("snr = 3").is_err());
    assert!(toml::from_str::<MicArray>("positions_m = []").is_err());
}

/// MVDR against the closed form of its covariance: one frame of a pure tone on FFT bin k₀ from
/// a plane wave at θ₀ (rectangular window, so the bin holds x_m = (L/2) e^{j2πf₀τ_m} exactly
/// and every other bin nothing) makes R = p d₀d₀ᴴ with p = (L/2)², and with the loading
/// δ = ε p Sherman-Morrison gives dᴴ(R + δI)⁻¹d = (M − p|dᴴd₀|²/(δ + pM))/δ for every beam,
/// an independent route from the Cholesky solve. A second identical frame leaves the running
/// covariance, and so every energy, unchanged.
#[test]
fn mvdr_energies_equal_the_closed_form_of_a_rank_one_covariance() {
    let array = MicArray::default();
    let (l, k0) = (512usize, 64usize);
    let fs = f64::from(FS);
    let f0 = k0 as f64 * fs / l as f64;
    let theta0 = 50f64.to_radians();
    let config = BeamformConfig {
        method: Method::Mvdr,
        window: Window::Rectangular,
        band_hz: [1000.0, 3000.0],
        mvdr_loading: 0.05,
        ..BeamformConfig::default()
    };
    let advances = array.arrival_advances_s(theta0, config.sound_speed_mps);
    let channels: Vec<Vec<f32>> = advances
        .iter()
        .map(|tau| {
            (0..l)
                .map(|n| (TAU * f0 * (n as f64 / fs + tau)).cos() as f32)
                .collect()
        })
        .collect();
    let frame: Vec<&[f32]> = channels.iter().map(Vec::as_slice).collect();
    let mut bf = config.check(&array).unwrap();
    let first = bf.frame_energies(&frame).unwrap();
    let m = advances.len() as f64;
    let p = (l as f64 / 2.0).powi(2);
    let delta = config.mvdr_loading * p;
    let weight = 2.0 / (l * l) as f64;
    let phase = |tau: f64| realfft::num_complex::Complex::from_polar(1.0, TAU * f0 * tau);
    for (b, e) in first.iter().enumerate() {
        let theta = TAU * b as f64 / config.n_beams as f64;
        let inner: realfft::num_complex::Complex<f64> = array
            .arrival_advances_s(theta, config.sound_speed_mps)
            .iter()
            .zip(&advances)
            .map(|(t, t0)| phase(*t).conj() * phase(*t0))
            .sum();
        let q = (m - p * inner.norm_sqr() / (delta + p * m)) / delta;
        let want = weight * m * m / q;
        assert!(
            (e - want).abs() <= 1e-5 * want,
            "beam {b}: {e} against the closed form {want}"
        );
    }
    // The beam at θ₀ (beam 5 of 36) passes the wave whole: p (1 + ε/M), scaled by M².
    assert!((first[5] / (weight * m * m * p) - (1.0 + config.mvdr_loading / m)).abs() < 1e-5);
    let second = bf.frame_energies(&frame).unwrap();
    for (a, b) in first.iter().zip(&second) {
        assert!((a - b).abs() <= 1e-9 * a, "{a} then {b}");
    }
}

/// The running covariance against a direct solve: a frame of a tone from θ₀, then one from
/// θ₁ on the same bin, leave R = α p d₀d₀ᴴ + (1 − α) p d₁d₁ᴴ (α = `mvdr_forgetting`), whose
/// loaded inverse the test takes by LU (not the beamformer's Cholesky) at every beam; after
/// `reset`, the θ₁ frame alone gives the rank-one form of θ₁; and `beamform` starts afresh,
/// so two passes over one recording give the same bytes.
#[test]
fn mvdr_remembers_earlier_frames_by_its_forgetting_factor_and_reset_forgets_them() {
    use realfft::num_complex::Complex;
    let array = MicArray::default();
    let (l, k0) = (512usize, 64usize);
    let fs = f64::from(FS);
    let f0 = k0 as f64 * fs / l as f64;
    let config = BeamformConfig {
        method: Method::Mvdr,
        window: Window::Rectangular,
        band_hz: [1000.0, 3000.0],
        mvdr_forgetting: 0.7,
        mvdr_loading: 0.05,
        ..BeamformConfig::default()
    };
    let tone = |theta: f64| -> Vec<Vec<f32>> {
        array
            .arrival_advances_s(theta, config.sound_speed_mps)
            .iter()
            .map(|tau| {
                (0..l)
                    .map(|n| (TAU * f0 * (n as f64 / fs + tau)).cos() as f32)
                    .collect()
            })
            .collect()
    };
    let (theta0, theta1) = (50f64.to_radians(), 140f64.to_radians());
    let (a, b) = (tone(theta0), tone(theta1));
    let manifold = |theta: f64| -> nalgebra::DVector<Complex<f64>> {
        nalgebra::DVector::from_iterator(
            4,
            array
                .arrival_advances_s(theta, config.sound_speed_mps)
                .into_iter()
                .map(|tau| Complex::from_polar(1.0, TAU * f0 * tau)),
        )
    };
    let p = (l as f64 / 2.0).powi(2);
    let weight = 2.0 / (l * l) as f64;
    // Energies of covariance p·Σ wᵢ dᵢdᵢᴴ (loaded with ε·tr/M) by LU at every beam.
    let expected = |terms: &[(f64, f64)]| -> Vec<f64> {
        let mut r = nalgebra::DMatrix::<Complex<f64>>::zeros(4, 4);
        for &(w, theta) in terms {
            let d = manifold(theta);
            r += &d * d.adjoint() * Complex::new(w * p, 0.0);
        }
        let power = (0..4).map(|i| r[(i, i)].re).sum::<f64>() / 4.0;
        for i in 0..4 {
            r[(i, i)] += Complex::new(config.mvdr_loading * power, 0.0);
        }
        let lu = r.lu();
        (0..config.n_beams)
            .map(|beam| {
                let d = manifold(TAU * beam as f64 / config.n_beams as f64);
                let q = (d.adjoint() * lu.solve(&d).unwrap())[(0, 0)].re;
                weight * 16.0 / q
            })
            .collect()
    };
    let close = |got: &[f64], want: &[f64]| {
        for (beam, (g, w)) in got.iter().zip(want).enumerate() {
            assert!((g - w).abs() <= 1e-5 * w, "beam {beam}: {g} against {w}");
        }
    };
    let (a, b): (Vec<&[f32]>, Vec<&[f32]>) = (
        a.iter().map(Vec::as_slice).collect(),
        b.iter().map(Vec::as_slice).collect(),
    );
    let mut bf = config.check(&array).unwrap();
    bf.frame_energies(&a).unwrap();
    let both = bf.frame_energies(&b).unwrap();
    close(&both, &expected(&[(0.7, theta0), (0.3, theta1)]));
    bf.reset();
    close(&bf.frame_energies(&b).unwrap(), &expected(&[(1.0, theta1)]));
    let sources = [source_at(theta0, 20.0, SourceSignal::WhiteNoise)];
    let rec = record(&sources, 0.2, None, 5);
    assert_eq!(bf.beamform(&rec).unwrap(), bf.beamform(&rec).unwrap());
}

/// Two white-noise sources 25° apart at 30 dB, inside one of the 10 cm array's broad
/// delay-and-sum beams: delay-and-sum finds one peak between them, MVDR (its covariance
/// averaged over the recording's frames) one near each, within one beam (10°; the two peaks'
/// parabolic refinement leans towards each other on the 10° grid).
#[test]
fn mvdr_resolves_two_sources_that_delay_and_sum_merges() {
    let (a, b) = (40f64.to_radians(), 65f64.to_radians());
    for seed in 0..3 {
        let rec = two_noise_sources(a, b, 30.0, 0.5, 70 + seed);
        // Peaks within 30° of the sources' midpoint (the small array's side lobes lie
        // elsewhere).
        let near = |bf: &Beamform| -> Vec<f64> {
            let mut found: Vec<f64> = bf
                .peaks(&PeakSearch {
                    max_peaks: 8,
                    min_relative: 0.1,
                })
                .iter()
                .map(|p| p.bearing_rad)
                .filter(|&t| angle_error_rad(t, 0.5 * (a + b)) < 30f64.to_radians())
                .collect();
            found.sort_by(f64::total_cmp);
            found
        };
        let das = mean_beamform(&config(Method::FrequencyDomain, Weighting::Plain), &rec);
        assert_eq!(near(&das).len(), 1, "seed {seed}: {:?}", das.energies);
        let mut bf = config(Method::Mvdr, Weighting::Plain)
            .check(&MicArray::default())
            .unwrap();
        let last = bf.beamform(&rec).unwrap().pop().unwrap();
        let found = near(&last);
        assert!(
            found.len() == 2
                && angle_error_rad(found[0], a) < 10f64.to_radians()
                && angle_error_rad(found[1], b) < 10f64.to_radians(),
            "seed {seed}: {:?} in {:?}",
            found.iter().map(|t| t.to_degrees()).collect::<Vec<_>>(),
            last.energies
        );
    }
}

#[test]
fn mvdr_settings_are_checked() {
    let array = MicArray::default();
    for (forgetting, loading, name) in [
        (1.0, 0.01, "mvdr_forgetting"),
        (-0.1, 0.01, "mvdr_forgetting"),
        (f64::NAN, 0.01, "mvdr_forgetting"),
        (0.5, 0.0, "mvdr_loading"),
        (0.5, f64::INFINITY, "mvdr_loading"),
    ] {
        let err = BeamformConfig {
            method: Method::Mvdr,
            mvdr_forgetting: forgetting,
            mvdr_loading: loading,
            ..BeamformConfig::default()
        }
        .check(&array)
        .unwrap_err()
        .to_string();
        assert!(err.contains(name), "{err}");
    }
    let phat = BeamformConfig {
        method: Method::Mvdr,
        weighting: Weighting::Phat,
        ..BeamformConfig::default()
    };
    assert!(phat.check(&array).unwrap_err().to_string().contains("PHAT"));
}
