//! Online MCMCDA over 10⁵ scans holds constant memory when it streams its committed history
//! out ([`OnlineTracker::drain_committed`] after every scan), and grows with the run when it
//! keeps everything (the default). Heap bytes come from a counting global allocator, so
//! this file is its own test binary with a single test (tests in one binary share the
//! allocator and run in parallel). The numbers it prints are recorded in
//! docs/reliability.md (`cargo test -p mcmcda --test online_memory -- --nocapture`).

use std::time::Instant;

use mcmcda::{McmcdaConfig, OnlineConfig, OnlineTracker};
use peak_alloc::PeakAlloc;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::Vec2;

#[global_allocator]
static HEAP: PeakAlloc = PeakAlloc;

const SHORT: usize = 10_000;
const LONG: usize = 100_000;
const SIDE: f64 = 1000.0;

/// Three targets moving at 20 per scan on slowly turning headings, bouncing off the walls
/// of [0, 1000]², each detected with probability 0.9 with σ = 10 noise, and Poisson(1)
/// false alarms: drawn scan by scan, so that the scene itself holds no history.
struct Scene {
    rng: ChaCha8Rng,
    /// x, y, heading.
    targets: Vec<[f64; 3]>,
}

impl Scene {
    fn new(seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let targets = (0..3)
            .map(|_| {
                [
                    rng.random_range(100.0..900.0),
                    rng.random_range(100.0..900.0),
                    rng.random_range(0.0..std::f64::consts::TAU),
                ]
            })
            .collect();
        Self { rng, targets }
    }

    fn normal(&mut self) -> f64 {
        // Box-Muller.
        let u: f64 = self.rng.random_range(f64::EPSILON..1.0);
        let v: f64 = self.rng.random();
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    fn next_scan(&mut self) -> Vec<Vec2> {
        let mut points = Vec::new();
        for k in 0..self.targets.len() {
            let turn = 0.05 * self.normal();
            let t = &mut self.targets[k];
            t[2] += turn;
            t[0] += 20.0 * t[2].cos();
            t[1] += 20.0 * t[2].sin();
            if !(0.0..=SIDE).contains(&t[0]) {
                t[0] = t[0].clamp(0.0, SIDE);
                t[2] = std::f64::consts::PI - t[2];
            }
            if !(0.0..=SIDE).contains(&t[1]) {
                t[1] = t[1].clamp(0.0, SIDE);
                t[2] = -t[2];
            }
            let (x, y) = (t[0], t[1]);
            if self.rng.random::<f64>() < 0.9 {
                let (nx, ny) = (self.normal(), self.normal());
                points.push(Vec2::new(x + 10.0 * nx, y + 10.0 * ny));
            }
        }
        // Poisson(1) by counting uniform products (Knuth).
        let mut product: f64 = self.rng.random();
        while product > (-1.0f64).exp() {
            points.push(Vec2::new(
                self.rng.random_range(0.0..SIDE),
                self.rng.random_range(0.0..SIDE),
            ));
            product *= self.rng.random::<f64>();
        }
        points
    }
}

/// Heap in use and the peak since the previous checkpoint, above what was in use before
/// the run; seconds per scan since the previous checkpoint.
#[derive(Debug, Clone, Copy)]
struct Checkpoint {
    in_use: usize,
    peak: usize,
    seconds_per_scan: f64,
}

struct Run {
    at_short: Checkpoint,
    at_long: Checkpoint,
    /// Measurements in final associations (drained pieces plus `finish`).
    associated: usize,
    /// Σ (label + 1)(id + 1) over the final associations (wrapping): equal checksums for
    /// equal associations, without holding them (that would grow with the run).
    checksum: u64,
}

fn run(streaming: bool) -> Run {
    let model = McmcdaConfig {
        measurement_noise: nalgebra::Matrix2::identity() * 100.0,
        ..McmcdaConfig::default()
    }
    .check()
    .expect("the default model is valid");
    let config = OnlineConfig {
        window: 8,
        samples_per_scan: 10,
        ..OnlineConfig::default()
    };
    let mut scene = Scene::new(17);
    let base = HEAP.current_usage();
    HEAP.reset_peak_usage();
    let mut tracker = OnlineTracker::new(model, 0, config, 5).expect("valid config");
    let mut associated = 0;
    let mut checksum = 0u64;
    let mut add = |label: u64, meas: &[u32]| {
        associated += meas.len();
        for &m in meas {
            checksum = checksum.wrapping_add((label + 1).wrapping_mul(u64::from(m) + 1));
        }
    };
    let mut checkpoints = Vec::new();
    let mut clock = Instant::now();
    for frame in 0..LONG {
        let points = scene.next_scan();
        tracker
            .push_scan(frame as u32, &points)
            .expect("frames increase");
        if streaming {
            // The output: a real run would write these rows out; the test counts them.
            for piece in tracker.drain_committed() {
                add(piece.label, &piece.measurements);
            }
        }
        if frame + 1 == SHORT || frame + 1 == LONG {
            let seconds = clock.elapsed().as_secs_f64();
            let scans = if frame + 1 == SHORT {
                SHORT
            } else {
                LONG - SHORT
            };
            checkpoints.push(Checkpoint {
                in_use: HEAP.current_usage().saturating_sub(base),
                peak: HEAP.peak_usage().saturating_sub(base),
                seconds_per_scan: seconds / scans as f64,
            });
            HEAP.reset_peak_usage();
            clock = Instant::now();
        }
    }
    let rest = tracker.finish().expect("the tracks smooth");
    for (label, meas) in &rest.associations {
        add(*label, meas);
    }
    Run {
        at_short: checkpoints[0],
        at_long: checkpoints[1],
        associated,
        checksum,
    }
}

#[test]
#[allow(clippy::print_stderr)]
fn streaming_online_mcmcda_holds_constant_memory_over_1e5_scans() {
    let streamed = run(true);
    let kept = run(false);
    for (name, r) in [("streaming", &streamed), ("keeping all", &kept)] {
        eprintln!(
            "{name}: heap in use {} B at 10^4 scans, {} B at 10^5 (peaks {} B, {} B); \
             {:.1} µs/scan over the first 10^4, {:.1} µs/scan over the rest; \
             {} associated measurements (checksum {})",
            r.at_short.in_use,
            r.at_long.in_use,
            r.at_short.peak,
            r.at_long.peak,
            r.at_short.seconds_per_scan * 1e6,
            r.at_long.seconds_per_scan * 1e6,
            r.associated,
            r.checksum,
        );
    }
    // Streaming: the heap after 10⁵ scans (and its peak over the last 9·10⁴) is within a
    // small factor of the heap after 10⁴.
    let ratio = |a: usize, b: usize| a as f64 / b.max(1) as f64;
    let s = (&streamed.at_short, &streamed.at_long);
    assert!(
        ratio(s.1.in_use, s.0.in_use) < 1.5 && ratio(s.1.peak, s.0.peak) < 1.5,
        "streaming grew: {s:?}"
    );
    // Keeping everything grows with the run: about 10× from 10⁴ to 10⁵ scans.
    let k = (&kept.at_short, &kept.at_long);
    assert!(ratio(k.1.in_use, k.0.in_use) > 7.0, "kept history: {k:?}");
    // And streaming is much smaller at 10⁵ scans.
    assert!(s.1.peak * 20 < k.1.in_use, "{s:?} vs {k:?}");
    // Both modes made the same final associations, at least in total (the unit test
    // `streaming_online_gives_the_same_associations` compares them one by one).
    assert_eq!(
        (streamed.associated, streamed.checksum),
        (kept.associated, kept.checksum)
    );
    assert!(streamed.associated > LONG * 2, "{}", streamed.associated);
}
