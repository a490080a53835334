//! The SMC-PHD filter (Vo, Singh & Doucet 2005; Yoon, Hwang, Choi & Yoon 2016 eqs. 3-8) with
//! measurement-driven birth and grouping extraction (Ristic, Clark, Vo & Vo 2012).
//!
//! Persistent particles are predicted, weighted by survival, and updated with
//! w ← [1 − p_D + Σ_z p_D g(z|x) / L(z)] w, where L(z) = κ(z) + ν_b(z) ḡ_b(z) + Σ_i p_D g(z|x_i) w_i.
//! Each measurement z also spawns J_b newborn particles around it, with total weight ν_b(z)
//! (ν_b spread evenly over the frame's measurements), updated only by their own z (a newborn
//! is born detected). A measurement whose persistent weight W(z) = Σ_i p_D g(z|x_i) w_i / L(z)
//! exceeds the threshold yields an estimate, the W-weighted mean of the particles (eq. 8); its
//! identity is the label carrying most of that weight. Every particle keeps the label of the
//! newborn group it came from, so identities persist across frames and through resampling.
//!
//! Particle work runs on rayon in fixed chunks, each with its own generator stream, and sums are
//! reduced in chunk order: results depend on the seed only, not on the thread count.

use std::collections::BTreeMap;

use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use tracker_model::BoundingBox;

use crate::config::{
    BoxMeasurement, BoxState, Likelihood, Motion, PhdConfig, measurement_from_box, power_sums,
    state_box,
};
use crate::error::Result;

/// Particles per parallel work item (and per generator stream).
const CHUNK: usize = 2048;

/// Particles per parallel work item of the likelihoods and the update, which draw nothing:
/// smaller than [`CHUNK`] so that the 2,000-4,000 particles of a frame split evenly over two
/// threads (their per-measurement sums are still reduced in chunk order).
const SUM_CHUNK: usize = 512;

/// One weighted particle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle {
    /// Box state.
    pub x: BoxState,
    /// PHD weight.
    pub w: f64,
    /// Identity of the newborn group it descends from.
    pub label: u64,
}

/// A reported target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Persistent identity.
    pub label: u64,
    /// The estimated state.
    pub state: BoxState,
    /// Its box.
    pub bbox: BoundingBox,
    /// W(z) (SMC) or the component weight (GM): the estimate's existence mass.
    pub weight: f64,
    /// Index of the measurement it was extracted from, in the input slice (GM-PHD: none).
    pub measurement: Option<usize>,
}

/// The outcome of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PhdStep {
    /// Reported targets.
    pub estimates: Vec<Estimate>,
    /// N̂: the expected number of (persistent) targets after the update.
    pub expected_targets: f64,
    /// Input boxes skipped as degenerate (non-finite, zero or negative size).
    pub skipped: usize,
}

/// The SMC-PHD filter.
#[derive(Debug, Clone)]
pub struct SmcPhd {
    config: PhdConfig,
    likelihood: Likelihood,
    particles: Vec<Particle>,
    next_label: u64,
    rng: ChaCha8Rng,
}

fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// Moves a particle one frame.
pub(crate) fn propagate<R: Rng + ?Sized>(x: &mut BoxState, motion: &Motion, rng: &mut R) {
    match *motion {
        Motion::RandomWalk {
            position_std,
            size_std,
        } => {
            x[0] += position_std * normal(rng);
            x[1] += position_std * normal(rng);
            x[2] = (x[2] + size_std * normal(rng)).max(1.0);
            x[3] = (x[3] + size_std * normal(rng)).max(1.0);
        }
        Motion::ConstantVelocity {
            acceleration_std,
            size_std,
        } => {
            x[0] += x[4];
            x[1] += x[5];
            x[4] += acceleration_std * normal(rng);
            x[5] += acceleration_std * normal(rng);
            x[2] = (x[2] + size_std * normal(rng)).max(1.0);
            x[3] = (x[3] + size_std * normal(rng)).max(1.0);
        }
    }
}

/// Moves a particle `frames` frames in one draw from the exact `frames`-step transition
/// ([`Motion::transition`]): x ← F(k) x + w, w ~ N(0, Q(k)), then the sizes clamped to one
/// pixel (the one-frame model clamps after every frame; over a gap the clamp applies once, at
/// its end). One frame is [`propagate`] itself, so consecutive frames give the same draws as
/// before. The cost does not depend on k.
pub(crate) fn propagate_by<R: Rng + ?Sized>(
    x: &mut BoxState,
    motion: &Motion,
    frames: u64,
    rng: &mut R,
) {
    if frames <= 1 {
        propagate(x, motion, rng);
        return;
    }
    let k = frames as f64;
    let root_k = k.sqrt();
    match *motion {
        Motion::RandomWalk {
            position_std,
            size_std,
        } => {
            x[0] += position_std * root_k * normal(rng);
            x[1] += position_std * root_k * normal(rng);
            x[2] = (x[2] + size_std * root_k * normal(rng)).max(1.0);
            x[3] = (x[3] + size_std * root_k * normal(rng)).max(1.0);
        }
        Motion::ConstantVelocity {
            acceleration_std,
            size_std,
        } => {
            // Per axis, Q(k) = σ² [[S₂, S₁], [S₁, k]] (S₁ = Σj, S₂ = Σj², j < k) factors as
            // v = σ √k n₁, p = σ (S₁/√k) n₁ + σ √(S₂ − S₁²/k) n₂, with S₂ − S₁²/k = (k³ − k)/12.
            let (s1, _) = power_sums(frames);
            let along = acceleration_std * s1 / root_k;
            let apart = acceleration_std * ((k - 1.0) * k * (k + 1.0) / 12.0).sqrt();
            let velocity = acceleration_std * root_k;
            for axis in 0..2 {
                let (n1, n2) = (normal(rng), normal(rng));
                x[axis] += k * x[axis + 4] + along * n1 + apart * n2;
                x[axis + 4] += velocity * n1;
            }
            x[2] = (x[2] + size_std * root_k * normal(rng)).max(1.0);
            x[3] = (x[3] + size_std * root_k * normal(rng)).max(1.0);
        }
    }
}

/// The generator of work item `stream` of a frame.
fn stream_rng(seed: u64, stream: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream as u64);
    rng
}

/// The frame's measurements sorted by centre x, so that a particle visits only those within
/// the likelihood's reach instead of all of them.
struct SortedByX {
    xs: Vec<f64>,
    index: Vec<usize>,
    reach: f64,
}

impl SortedByX {
    fn new(zs: &[BoxMeasurement], reach: f64) -> Self {
        let mut index: Vec<usize> = (0..zs.len()).collect();
        index.sort_by(|&a, &b| zs[a][0].total_cmp(&zs[b][0]).then(a.cmp(&b)));
        Self {
            xs: index.iter().map(|&j| zs[j][0]).collect(),
            index,
            reach,
        }
    }

    /// Indices of the measurements whose c_x is within reach of `x`, in increasing c_x.
    fn near(&self, x: f64) -> impl Iterator<Item = usize> + '_ {
        let start = self.xs.partition_point(|&v| v < x - self.reach);
        self.xs[start..]
            .iter()
            .take_while(move |&&v| v <= x + self.reach)
            .zip(&self.index[start..])
            .map(|(_, &j)| j)
    }
}

/// One chunk's non-zero likelihoods as (particle in chunk, measurement, g), and per
/// measurement Σ p_D g w.
type ChunkDensities = (Vec<(u32, u32, f64)>, Vec<f64>);

/// The likelihoods of one frame and the normalisers L(z) they give.
struct Likelihoods {
    /// Per chunk of persistent particles: the non-zero g(z|x_i) and Σ p_D g w per z.
    persistent: Vec<ChunkDensities>,
    /// g(z|x) of each newborn group's particles under its own measurement.
    newborn: Vec<Vec<f64>>,
    /// L(z) per measurement.
    normaliser: Vec<f64>,
}

/// Per-measurement sums of one chunk of persistent particles.
#[derive(Clone, Default)]
struct Grouping {
    /// Σ p_D g w / L and Σ (p_D g w / L) x, per measurement.
    mass: Vec<f64>,
    mean: Vec<BoxState>,
    /// Mass per label, per measurement, as runs of (label, mass).
    labels: Vec<Vec<(u64, f64)>>,
}

impl SmcPhd {
    /// A filter with no targets; every random draw comes from ChaCha8 seeded with `seed`.
    pub fn new(config: PhdConfig, seed: u64) -> Result<Self> {
        config.check()?;
        Ok(Self {
            likelihood: Likelihood::new(&config.measurement_std),
            config,
            particles: Vec::new(),
            next_label: 0,
            rng: ChaCha8Rng::seed_from_u64(seed),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &PhdConfig {
        &self.config
    }

    /// The persistent particles (after the last resampling).
    pub fn particles(&self) -> &[Particle] {
        &self.particles
    }

    /// Runs one frame with the given detections: predict, draw the newborn groups, compute
    /// L(z), update, extract the estimates (eq. 8) and resample.
    pub fn step(&mut self, boxes: &[BoundingBox]) -> Result<PhdStep> {
        self.step_after(1, boxes)
    }

    /// Runs the frame `frames` frames after the last one, the `frames − 1` frames between
    /// having had no detection, as [`step`](Self::step) would after stepping each of them
    /// with no box, but in one prediction: every particle moves by the exact `frames`-step
    /// transition ([`Motion::transition`]) and its weight takes [`PhdConfig::gap_weight`]
    /// (p_Sᵏ (1 − p_D)ᵏ⁻¹). The frames between give no estimate (estimates come from
    /// measurements) and no birth; what is skipped is only their resampling, which leaves the
    /// PHD unchanged in expectation. The cost does not depend on `frames`.
    ///
    /// `frames = 1` is [`step`](Self::step); `frames = 0` is an error.
    pub fn step_after(&mut self, frames: u64, boxes: &[BoundingBox]) -> Result<PhdStep> {
        crate::config::check_frames_after(frames)?;
        let valid: Vec<(usize, BoxMeasurement)> = boxes
            .iter()
            .enumerate()
            .filter_map(|(i, b)| measurement_from_box(b).map(|z| (i, z)))
            .collect();
        let skipped = boxes.len() - valid.len();
        let zs: Vec<BoxMeasurement> = valid.iter().map(|v| v.1).collect();
        self.predict(frames);
        let nu = if zs.is_empty() {
            0.0
        } else {
            self.config.birth_rate / zs.len() as f64
        };
        let newborn = self.spawn_newborn(&zs, nu);
        let likelihoods = self.likelihoods(&zs, nu, &newborn);
        let groups = self.update(&likelihoods);
        let expected_targets: f64 = self.particles.iter().map(|p| p.w).sum();
        let estimates = self.extract(groups, &valid);
        self.resample_particles(expected_targets, newborn, &likelihoods);
        Ok(PhdStep {
            estimates,
            expected_targets,
            skipped,
        })
    }

    /// Predict over `frames` frames: moves every persistent particle by the exact transition
    /// and weights it by p_S per frame and 1 − p_D per empty frame between.
    fn predict(&mut self, frames: u64) {
        let cfg = self.config;
        let survive = cfg.gap_weight(frames);
        let seed: u64 = self.rng.random();
        self.particles
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                let mut rng = stream_rng(seed, c);
                for p in chunk {
                    propagate_by(&mut p.x, &cfg.motion, frames, &mut rng);
                    p.w *= survive;
                }
            });
    }

    /// Newborn groups, one per measurement, drawn around it, each of total weight `nu` and
    /// with a fresh label.
    fn spawn_newborn(&mut self, zs: &[BoxMeasurement], nu: f64) -> Vec<Vec<Particle>> {
        let cfg = self.config;
        let birth_seed: u64 = self.rng.random();
        let first_label = self.next_label;
        self.next_label += zs.len() as u64;
        zs.par_iter()
            .enumerate()
            .map(|(j, z)| {
                let mut rng = stream_rng(birth_seed, j);
                (0..cfg.birth_particles)
                    .map(|_| {
                        let mut x = [0.0; 6];
                        for k in 0..4 {
                            x[k] = z[k] + cfg.measurement_std[k] * normal(&mut rng);
                        }
                        x[2] = x[2].max(1.0);
                        x[3] = x[3].max(1.0);
                        if let Motion::ConstantVelocity { .. } = cfg.motion {
                            x[4] = cfg.birth_velocity_std * normal(&mut rng);
                            x[5] = cfg.birth_velocity_std * normal(&mut rng);
                        }
                        Particle {
                            x,
                            w: nu / cfg.birth_particles as f64,
                            label: first_label + j as u64,
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// L(z) = κ + ν_b(z) ḡ_b(z) + Σ_i p_D g(z|x_i) w_i, with the likelihoods it is made of.
    fn likelihoods(
        &self,
        zs: &[BoxMeasurement],
        nu: f64,
        newborn: &[Vec<Particle>],
    ) -> Likelihoods {
        let cfg = self.config;
        let lik = self.likelihood;
        let p_d = cfg.p_detect;
        let n_z = zs.len();
        let sorted = SortedByX::new(zs, lik.reach_x());
        // One pass computes every non-zero g(z|x_i) once, per chunk as (particle, z, g), and
        // the chunk's sums; the update pass reuses them.
        let persistent: Vec<ChunkDensities> = self
            .particles
            .par_chunks(SUM_CHUNK)
            .map(|chunk| {
                let mut sums = vec![0.0; n_z];
                // About one measurement within reach per particle: room for that up front.
                let mut pairs = Vec::with_capacity(chunk.len());
                for (i, p) in chunk.iter().enumerate() {
                    for j in sorted.near(p.x[0]) {
                        let d = lik.density(&zs[j], &p.x);
                        if d > 0.0 {
                            sums[j] += p_d * d * p.w;
                            pairs.push((i as u32, j as u32, d));
                        }
                    }
                }
                (pairs, sums)
            })
            .collect();
        let mut persistent_sum = vec![0.0; n_z];
        for (_, sums) in &persistent {
            persistent_sum
                .iter_mut()
                .zip(sums)
                .for_each(|(a, b)| *a += b);
        }
        let kappa = cfg.clutter_intensity();
        let newborn: Vec<Vec<f64>> = newborn
            .par_iter()
            .zip(zs)
            .map(|(group, z)| group.iter().map(|p| lik.density(z, &p.x)).collect())
            .collect();
        let normaliser: Vec<f64> = (0..n_z)
            .map(|j| {
                let mean_g = newborn[j].iter().sum::<f64>() / newborn[j].len().max(1) as f64;
                kappa + nu * mean_g + persistent_sum[j]
            })
            .collect();
        Likelihoods {
            persistent,
            newborn,
            normaliser,
        }
    }

    /// Updates the persistent particles and accumulates the grouping sums, per chunk.
    fn update(&mut self, likelihoods: &Likelihoods) -> Vec<Grouping> {
        let p_d = self.config.p_detect;
        let big_l = &likelihoods.normaliser;
        let n_z = big_l.len();
        self.particles
            .par_chunks_mut(SUM_CHUNK)
            .zip(&likelihoods.persistent)
            .map(|(chunk, (pairs, _))| {
                let mut g = Grouping {
                    mass: vec![0.0; n_z],
                    mean: vec![[0.0; 6]; n_z],
                    labels: vec![Vec::new(); n_z],
                };
                let mut factor = vec![1.0 - p_d; chunk.len()];
                for &(i, j, d) in pairs {
                    let (i, j) = (i as usize, j as usize);
                    let p = &chunk[i];
                    let share = p_d * d / big_l[j];
                    factor[i] += share;
                    let m = share * p.w;
                    g.mass[j] += m;
                    for k in 0..6 {
                        g.mean[j][k] += m * p.x[k];
                    }
                    // Particles of one target are mostly adjacent: extend the last run.
                    match g.labels[j].last_mut() {
                        Some((l, acc)) if *l == p.label => *acc += m,
                        _ => g.labels[j].push((p.label, m)),
                    }
                }
                for (p, f) in chunk.iter_mut().zip(factor) {
                    p.w *= f;
                }
                g
            })
            .collect()
    }

    /// Grouping extraction (eq. 8), larger W first so a contested label goes to it.
    fn extract(
        &mut self,
        groups: Vec<Grouping>,
        valid: &[(usize, BoxMeasurement)],
    ) -> Vec<Estimate> {
        let cfg = self.config;
        let n_z = valid.len();
        let mut mass = vec![0.0; n_z];
        let mut mean = vec![[0.0; 6]; n_z];
        let mut labels: Vec<BTreeMap<u64, f64>> = vec![BTreeMap::new(); n_z];
        for g in groups {
            for j in 0..n_z {
                mass[j] += g.mass[j];
                for (a, b) in mean[j].iter_mut().zip(&g.mean[j]) {
                    *a += b;
                }
                for (l, m) in &g.labels[j] {
                    *labels[j].entry(*l).or_default() += m;
                }
            }
        }
        let mut order: Vec<usize> = (0..n_z)
            .filter(|&j| mass[j] > cfg.extraction_threshold)
            .collect();
        order.sort_by(|&a, &b| mass[b].total_cmp(&mass[a]).then(a.cmp(&b)));
        let mut used_labels: Vec<u64> = Vec::new();
        let mut estimates = Vec::with_capacity(order.len());
        for j in order {
            let w = mass[j];
            let state = mean[j].map(|v| v / w);
            // The oldest label with a fair share of W(z): a target that faded after a missed
            // detection and was re-born from the next one keeps its identity.
            let share = cfg.label_min_share * w;
            let label = labels[j]
                .iter()
                .filter(|(_, m)| **m >= share)
                .map(|(l, _)| *l)
                .find(|l| !used_labels.contains(l))
                .unwrap_or_else(|| {
                    self.next_label += 1;
                    self.next_label - 1
                });
            used_labels.push(label);
            estimates.push(Estimate {
                label,
                state,
                bbox: state_box(&state),
                weight: w,
                measurement: Some(valid[j].0),
            });
        }
        estimates
    }

    /// Resamples the persistent particles to ρ N̂; each newborn group, updated by its own
    /// measurement only, is resampled to J_b particles and joins them (Ristic et al. 2012).
    fn resample_particles(
        &mut self,
        expected_targets: f64,
        newborn: Vec<Vec<Particle>>,
        likelihoods: &Likelihoods,
    ) {
        let cfg = self.config;
        let persistent = std::mem::take(&mut self.particles);
        let target = (expected_targets * cfg.particles_per_target as f64).ceil() as usize;
        let target = target.min(cfg.max_particles);
        // One allocation for the persistent and every newborn group's particles (growing the
        // vector group by group took about a quarter of this thread's share of a frame).
        let mut out = Vec::with_capacity(target + newborn.len() * cfg.birth_particles);
        resample_into(&persistent, target, &mut self.rng, &mut out);
        let mut weighted: Vec<Particle> = Vec::with_capacity(cfg.birth_particles);
        for ((group, g), l) in newborn
            .into_iter()
            .zip(&likelihoods.newborn)
            .zip(&likelihoods.normaliser)
        {
            weighted.clear();
            weighted.extend(group.into_iter().zip(g).map(|(p, d)| Particle {
                w: p.w * d / l,
                ..p
            }));
            resample_into(&weighted, cfg.birth_particles, &mut self.rng, &mut out);
        }
        self.particles = out;
    }
}

/// Systematic resampling of `particles` to `n` particles of equal weight (their total),
/// appended to `out`; an empty or weightless set adds nothing.
fn resample_into<R: Rng + ?Sized>(
    particles: &[Particle],
    n: usize,
    rng: &mut R,
    out: &mut Vec<Particle>,
) {
    let total: f64 = particles.iter().map(|p| p.w).sum();
    if !(total.is_finite() && total > 1e-12) || n == 0 {
        return;
    }
    let step = total / n as f64;
    let mut u = rng.random::<f64>() * step;
    let start = out.len();
    let end = start + n;
    let mut acc = 0.0;
    for p in particles {
        acc += p.w;
        while u < acc && out.len() < end {
            out.push(Particle { w: step, ..*p });
            u += step;
        }
    }
    // Rounding can leave the last slots unfilled; they go to the last particle.
    if let Some(last) = particles.last() {
        out.resize(end, Particle { w: step, ..*last });
    }
}
