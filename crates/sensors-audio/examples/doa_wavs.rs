//! The Rust half of `docs/comparisons/pyroomacoustics_doa.py`: writes simulated recordings as
//! WAV files with their true bearings, or reads them back and times our three beamformers.
//!
//! ```text
//! cargo run --release -p sensors-audio --example doa_wavs -- simulate DIR [N_RUNS] [SNR_DB]
//! cargo run --release -p sensors-audio --example doa_wavs -- estimate DIR
//! ```
//!
//! `simulate` writes DIR/run_NNN.wav (4 channels, 16 kHz, 32-bit float, 0.5 s: a vehicle-like
//! source 20 m away at a random bearing, diffuse noise) and DIR/truth.csv (run, bearing_deg).
//! `estimate` beamforms every file (mean beam energies over its 512-sample frames, 36 beams,
//! 200–4000 Hz) and prints, per method, the mean absolute bearing error and the time per file.
#![expect(
    clippy::print_stdout,
    reason = "a command-line example reports on the terminal"
)]

use std::error::Error;
use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::Path;
use std::time::Instant;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sensors_audio::{
    BackgroundNoise, Beamform, BeamformConfig, Method, MicArray, NoiseField, Recording, SensorPose,
    SimulationConfig, Source, SourcePath, SourceSignal, Weighting, simulate,
};
use tracker_model::{Vec2, wrap_angle_rad};

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(mode), Some(dir)) = (args.get(1), args.get(2)) else {
        return Err("usage: doa_wavs simulate|estimate DIR [N_RUNS] [SNR_DB]".into());
    };
    let dir = Path::new(dir);
    match mode.as_str() {
        "simulate" => {
            let n_runs: usize = args.get(3).map_or(Ok(50), |s| s.parse())?;
            let snr_db: f64 = args.get(4).map_or(Ok(10.0), |s| s.parse())?;
            simulate_all(dir, n_runs, snr_db)
        }
        "estimate" => estimate_all(dir),
        other => Err(format!("unknown mode {other}").into()),
    }
}

fn simulate_all(dir: &Path, n_runs: usize, snr_db: f64) -> Result<(), Box<dyn Error>> {
    std::fs::create_dir_all(dir)?;
    let mut truth = BufWriter::new(File::create(dir.join("truth.csv"))?);
    writeln!(truth, "run,bearing_deg")?;
    let config = SimulationConfig {
        ground_reflection: Some(0.5),
        noise: Some(BackgroundNoise {
            snr_db,
            field: NoiseField::Diffuse { n_directions: 16 },
        }),
        ..SimulationConfig::default()
    };
    let pose = SensorPose {
        position: Vec2::new(0.0, 0.0),
        heading_rad: 0.0,
    };
    for run in 0..n_runs {
        let mut rng = ChaCha8Rng::seed_from_u64(1515);
        rng.set_stream(run as u64);
        let bearing = std::f64::consts::TAU * rng.random::<f64>();
        let source = Source {
            path: SourcePath::Fixed {
                position: Vec2::new(20.0 * bearing.cos(), 20.0 * bearing.sin()),
            },
            height_m: 0.5,
            level: 1.0,
            signal: SourceSignal::Vehicle {
                fundamental_hz: 45.0,
                n_harmonics: 60,
                rolloff: 0.7,
                noise_fraction: 0.3,
            },
        };
        let rec = simulate(
            &MicArray::default(),
            &pose,
            &[source],
            0.5,
            &config,
            &mut rng,
        )?;
        rec.write_wav(BufWriter::new(File::create(
            dir.join(format!("run_{run:03}.wav")),
        )?))?;
        writeln!(truth, "{run},{}", bearing.to_degrees())?;
    }
    Ok(())
}

fn estimate_all(dir: &Path) -> Result<(), Box<dyn Error>> {
    let truth = std::fs::read_to_string(dir.join("truth.csv"))?;
    let mut runs = Vec::new();
    for line in truth.lines().skip(1) {
        let (run, deg) = line.split_once(',').ok_or("bad truth.csv line")?;
        let run: usize = run.parse()?;
        let rec = Recording::read_wav(
            BufReader::new(File::open(dir.join(format!("run_{run:03}.wav")))?),
            0.0,
        )?;
        runs.push((rec, deg.parse::<f64>()?));
    }
    for (name, method, weighting) in [
        ("time-domain DS", Method::TimeDomain, Weighting::Plain),
        (
            "frequency-domain SRP",
            Method::FrequencyDomain,
            Weighting::Plain,
        ),
        ("SRP-PHAT", Method::FrequencyDomain, Weighting::Phat),
    ] {
        let mut bf = BeamformConfig {
            method,
            weighting,
            ..BeamformConfig::default()
        }
        .check(&MicArray::default())?;
        let mut errors = Vec::new();
        // Best of 5 passes over all files, as the Python side does.
        let mut best_s = f64::INFINITY;
        for pass in 0..5 {
            let start = Instant::now();
            for (rec, deg) in &runs {
                let frames = bf.beamform(rec)?;
                let mut energies = vec![0.0; 36];
                for f in &frames {
                    energies
                        .iter_mut()
                        .zip(&f.energies)
                        .for_each(|(e, v)| *e += v);
                }
                let doa = Beamform {
                    time_s: 0.0,
                    energies,
                }
                .doa()
                .ok_or("flat beamform")?;
                if pass == 0 {
                    errors.push(
                        wrap_angle_rad(doa.bearing_rad - deg.to_radians())
                            .abs()
                            .to_degrees(),
                    );
                }
            }
            best_s = best_s.min(start.elapsed().as_secs_f64());
        }
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        println!(
            "{name}: mean |error| {mean:.2}° over {} files, {:.3} ms per file (best of 5)",
            errors.len(),
            1e3 * best_s / runs.len() as f64
        );
    }
    Ok(())
}
