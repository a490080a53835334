//! Beamforming benchmarks: one 512-sample frame of 4 channels (the default 10 cm × 6 cm
//! array, a white-noise source 20 m away at 40° with diffuse noise at 10 dB, fixed seed)
//! into 36 beam energies, in the frequency domain (plain and PHAT), in the time domain, and by
//! MVDR (its running covariance updated by the same frame at every iteration).
//! The recording is simulated outside the timed closure; the beamformer reuses its buffers.
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sensors_audio::{
    BackgroundNoise, BeamformConfig, Method, MicArray, NoiseField, SensorPose, SimulationConfig,
    Source, SourcePath, SourceSignal, Weighting, simulate,
};
use tracker_model::Vec2;

fn bench(c: &mut Criterion) {
    let array = MicArray::default();
    let bearing = 40_f64.to_radians();
    let source = Source {
        path: SourcePath::Fixed {
            position: Vec2::new(20.0 * bearing.cos(), 20.0 * bearing.sin()),
        },
        height_m: 1.0,
        level: 1.0,
        signal: SourceSignal::WhiteNoise,
    };
    let config = SimulationConfig {
        noise: Some(BackgroundNoise {
            snr_db: 10.0,
            field: NoiseField::Diffuse { n_directions: 16 },
        }),
        ..SimulationConfig::default()
    };
    let pose = SensorPose {
        position: Vec2::new(0.0, 0.0),
        heading_rad: 0.0,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let rec = simulate(&array, &pose, &[source], 0.1, &config, &mut rng).unwrap();
    let frame: Vec<&[f32]> = rec.channels.iter().map(|ch| &ch[..512]).collect();
    for (name, method, weighting) in [
        (
            "beamform_freq_4ch_36beams_512",
            Method::FrequencyDomain,
            Weighting::Plain,
        ),
        (
            "beamform_freq_phat_4ch_36beams_512",
            Method::FrequencyDomain,
            Weighting::Phat,
        ),
        (
            "beamform_time_4ch_36beams_512",
            Method::TimeDomain,
            Weighting::Plain,
        ),
        (
            "beamform_mvdr_4ch_36beams_512",
            Method::Mvdr,
            Weighting::Plain,
        ),
    ] {
        let mut bf = BeamformConfig {
            method,
            weighting,
            ..BeamformConfig::default()
        }
        .check(&array)
        .unwrap();
        let mut energies = Vec::new();
        c.bench_function(name, |b| {
            b.iter(|| {
                bf.frame_energies_into(black_box(&frame), &mut energies)
                    .unwrap();
                black_box(energies[0])
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
