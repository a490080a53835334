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
//! reduced in chunk order: results depend on the seed only, not on the thread count. A frame
//! forks twice (the prediction with its likelihoods beside the newborn groups, then the
//! update). A caller stepping many small frames should step from a thread of rayon's pool
//! (inside `rayon::scope`, say): from outside it, each fork is handed to the pool and waited
//! for, which on frames of a few thousand particles costs about what the second thread saves.

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

// A predicted chunk's likelihoods are computed in the same work item, by sub-chunks that are
// the frame's `SUM_CHUNK` chunks.
const _: () = assert!(CHUNK.is_multiple_of(SUM_CHUNK));

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
    /// The previous frame's particle vector, empty, reused by the next resampling.
    spare: Vec<Particle>,
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
    /// The measurements in increasing c_x (copied, so that a particle's candidates are
    /// adjacent in memory).
    zs: Vec<BoxMeasurement>,
    /// Each one's index in the frame.
    index: Vec<u32>,
    reach: f64,
}

impl SortedByX {
    fn new(zs: &[BoxMeasurement], reach: f64) -> Self {
        let mut index: Vec<u32> = (0..zs.len() as u32).collect();
        index.sort_by(|&a, &b| {
            zs[a as usize][0]
                .total_cmp(&zs[b as usize][0])
                .then(a.cmp(&b))
        });
        Self {
            zs: index.iter().map(|&j| zs[j as usize]).collect(),
            index,
            reach,
        }
    }

    /// The first measurement whose c_x is at least `x − reach`, found by moving from `from`
    /// (the previous particle's answer) rather than by a binary search: the particles of one
    /// target are adjacent and close, so the answer rarely moves. (For a NaN `x` the answer
    /// is `from`, and no measurement is within reach of it anyway.)
    fn first_within(&self, x: f64, from: usize) -> usize {
        let lo = x - self.reach;
        let mut s = from.min(self.zs.len());
        while s > 0 && self.zs[s - 1][0] >= lo {
            s -= 1;
        }
        while s < self.zs.len() && self.zs[s][0] < lo {
            s += 1;
        }
        s
    }
}

/// One chunk's non-zero likelihoods as (particle in chunk, measurement, g), and per
/// measurement Σ p_D g w.
type ChunkDensities = (Vec<(u32, u32, f64)>, Vec<f64>);

/// The likelihoods of one frame and the normalisers L(z) they give.
struct Likelihoods {
    /// Per chunk of persistent particles: the non-zero g(z|x_i) and Σ p_D g w per z.
    persistent: Vec<ChunkDensities>,
    /// L(z) per measurement.
    normaliser: Vec<f64>,
}

/// The frame's newborn groups: J_b particles per measurement, in measurement order, each
/// with g(z|x) under its own measurement z (a newborn is updated by that z only).
struct Newborn {
    particles: Vec<Particle>,
    density: Vec<f64>,
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
            spare: Vec::new(),
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
        let nu = if zs.is_empty() {
            0.0
        } else {
            self.config.birth_rate / zs.len() as f64
        };
        let (newborn, likelihoods) = self.predict_and_weigh(frames, &zs, nu);
        let groups = self.update(&likelihoods);
        let expected_targets: f64 = self.particles.iter().map(|p| p.w).sum();
        let estimates = self.extract(groups, &valid);
        self.resample_particles(expected_targets, &newborn, &likelihoods);
        Ok(PhdStep {
            estimates,
            expected_targets,
            skipped,
        })
    }

    /// Predicts the persistent particles over `frames` frames (the exact transition, weight
    /// p_S per frame and 1 − p_D per empty frame between), draws the newborn groups (one per
    /// measurement, around it, of total weight `nu`, with a fresh label), and computes every
    /// likelihood and L(z) = κ + ν_b(z) ḡ_b(z) + Σ_i p_D g(z|x_i) w_i.
    ///
    /// One parallel pass: each chunk of persistent particles is weighed as soon as it is
    /// predicted, while the newborn groups are drawn and weighed beside it (the two need
    /// nothing from each other), so that a frame waits for its threads twice (here and in the
    /// update) rather than at every step.
    fn predict_and_weigh(
        &mut self,
        frames: u64,
        zs: &[BoxMeasurement],
        nu: f64,
    ) -> (Newborn, Likelihoods) {
        let cfg = self.config;
        let lik = self.likelihood;
        let p_d = cfg.p_detect;
        let survive = cfg.gap_weight(frames);
        // Drawn in this order whatever runs first: the streams do not depend on the threads.
        let seed: u64 = self.rng.random();
        let birth_seed: u64 = self.rng.random();
        let first_label = self.next_label;
        self.next_label += zs.len() as u64;
        let sorted = SortedByX::new(zs, lik.reach_x());
        let (persistent, newborn) = rayon::join(
            || {
                // The non-zero g(z|x_i), per chunk as (particle, z, g), and the chunk's
                // sums: computed once, and reused by the update pass.
                let per_chunk: Vec<Vec<ChunkDensities>> = self
                    .particles
                    .par_chunks_mut(CHUNK)
                    .enumerate()
                    .map(|(c, chunk)| {
                        predict_chunk(chunk, &cfg.motion, frames, survive, stream_rng(seed, c));
                        chunk
                            .par_chunks(SUM_CHUNK)
                            .map(|sub| chunk_densities(sub, &sorted, &lik, p_d))
                            .collect()
                    })
                    .collect();
                per_chunk.into_iter().flatten().collect::<Vec<_>>()
            },
            || spawn_newborn(&cfg, &lik, zs, nu, birth_seed, first_label),
        );
        let mut persistent_sum = vec![0.0; zs.len()];
        for (_, sums) in &persistent {
            persistent_sum
                .iter_mut()
                .zip(sums)
                .for_each(|(a, b)| *a += b);
        }
        let kappa = cfg.clutter_intensity();
        let per_group = cfg.birth_particles;
        let normaliser: Vec<f64> = newborn
            .density
            .chunks(per_group)
            .zip(&persistent_sum)
            .map(|(g, persistent)| {
                let mean_g = g.iter().sum::<f64>() / per_group as f64;
                kappa + nu * mean_g + persistent
            })
            .collect();
        (
            newborn,
            Likelihoods {
                persistent,
                normaliser,
            },
        )
    }

    /// Updates the persistent particles and accumulates the grouping sums, per chunk.
    fn update(&mut self, likelihoods: &Likelihoods) -> Vec<Grouping> {
        let p_d = self.config.p_detect;
        let big_l = &likelihoods.normaliser;
        self.particles
            .par_chunks_mut(SUM_CHUNK)
            .zip(&likelihoods.persistent)
            .map(|(chunk, (pairs, _))| update_chunk(chunk, pairs, big_l, p_d))
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
    /// `expected_targets` is the persistent particles' total weight.
    fn resample_particles(
        &mut self,
        expected_targets: f64,
        newborn: &Newborn,
        likelihoods: &Likelihoods,
    ) {
        let cfg = self.config;
        let per_group = cfg.birth_particles;
        let target = (expected_targets * cfg.particles_per_target as f64).ceil() as usize;
        let target = target.min(cfg.max_particles);
        // The persistent and every newborn group's particles go into one vector, reserved
        // once (growing it group by group took about a quarter of this thread's share of a
        // frame), and that vector is the last frame's, reused: a frame allocates no vector
        // of particles (on the realistic files, half the bytes the PHD tracker allocated).
        let persistent = std::mem::take(&mut self.particles);
        let mut out = std::mem::take(&mut self.spare);
        out.clear();
        out.reserve(target + newborn.particles.len());
        resample_into(
            &persistent,
            expected_targets,
            target,
            &mut self.rng,
            &mut out,
        );
        let mut weighted: Vec<Particle> = Vec::with_capacity(per_group);
        for ((group, g), l) in newborn
            .particles
            .chunks(per_group)
            .zip(newborn.density.chunks(per_group))
            .zip(&likelihoods.normaliser)
        {
            weighted.clear();
            weighted.extend(group.iter().zip(g).map(|(p, d)| Particle {
                w: p.w * d / l,
                ..*p
            }));
            let total = weighted.iter().map(|p| p.w).sum();
            resample_into(&weighted, total, per_group, &mut self.rng, &mut out);
        }
        self.particles = out;
        self.spare = persistent;
    }
}

/// The newborn groups of a frame, `J_b` particles per measurement drawn around it (group j
/// from stream j of `seed`, label `first_label + j`), each of total weight `nu`, and their
/// likelihoods under their own measurement.
fn spawn_newborn(
    cfg: &PhdConfig,
    lik: &Likelihood,
    zs: &[BoxMeasurement],
    nu: f64,
    seed: u64,
    first_label: u64,
) -> Newborn {
    let per_group = cfg.birth_particles;
    let blank = Particle {
        x: [0.0; 6],
        w: 0.0,
        label: 0,
    };
    let mut newborn = Newborn {
        particles: vec![blank; zs.len() * per_group],
        density: vec![0.0; zs.len() * per_group],
    };
    newborn
        .particles
        .par_chunks_mut(per_group)
        .zip(newborn.density.par_chunks_mut(per_group))
        .zip(zs)
        .enumerate()
        .for_each(|(j, ((group, density), z))| {
            let mut rng = stream_rng(seed, j);
            for (p, d) in group.iter_mut().zip(density) {
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
                *p = Particle {
                    x,
                    w: nu / per_group as f64,
                    label: first_label + j as u64,
                };
                *d = lik.density(z, &x);
            }
        });
    newborn
}

/// Moves one chunk of persistent particles by `frames` frames with the chunk's own
/// generator, and weights them by `survive`.
fn predict_chunk(
    chunk: &mut [Particle],
    motion: &Motion,
    frames: u64,
    survive: f64,
    mut rng: ChaCha8Rng,
) {
    for p in chunk {
        propagate_by(&mut p.x, motion, frames, &mut rng);
        p.w *= survive;
    }
}

/// The non-zero g(z|x) of one chunk of persistent particles, in particle order and, per
/// particle, in increasing c_x of z, and per measurement Σ p_D g w.
fn chunk_densities(
    chunk: &[Particle],
    sorted: &SortedByX,
    lik: &Likelihood,
    p_d: f64,
) -> ChunkDensities {
    let mut sums = vec![0.0; sorted.zs.len()];
    // About one measurement within reach per particle: room for that up front.
    let mut pairs = Vec::with_capacity(chunk.len());
    let zs = &sorted.zs[..];
    let mut start = 0;
    for (i, p) in chunk.iter().enumerate() {
        let x = p.x[0];
        start = sorted.first_within(x, start);
        let hi = x + sorted.reach;
        // The measurements with c_x in [x − reach, x + reach], in increasing c_x.
        let mut k = start;
        while k < zs.len() && zs[k][0] <= hi {
            let d = lik.density(&zs[k], &p.x);
            if d > 0.0 {
                let j = sorted.index[k];
                sums[j as usize] += p_d * d * p.w;
                pairs.push((i as u32, j, d));
            }
            k += 1;
        }
    }
    (pairs, sums)
}

/// The update of one chunk of persistent particles, w ← [1 − p_D + Σ_z p_D g(z|x) / L(z)] w,
/// and its grouping sums per measurement.
fn update_chunk(
    chunk: &mut [Particle],
    pairs: &[(u32, u32, f64)],
    big_l: &[f64],
    p_d: f64,
) -> Grouping {
    let n_z = big_l.len();
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
}

/// Systematic resampling of `particles`, of total weight `total`, to `n` particles of equal
/// weight (their total), appended to `out`; an empty or weightless set adds nothing.
fn resample_into<R: Rng + ?Sized>(
    particles: &[Particle],
    total: f64,
    n: usize,
    rng: &mut R,
    out: &mut Vec<Particle>,
) {
    if !(total.is_finite() && total > 1e-12) || n == 0 {
        return;
    }
    let step = total / n as f64;
    let mut u = rng.random::<f64>() * step;
    let mut left = n;
    let mut acc = 0.0;
    for p in particles {
        acc += p.w;
        while u < acc && left > 0 {
            out.push(Particle { w: step, ..*p });
            u += step;
            left -= 1;
        }
    }
    // Rounding can leave the last slots unfilled; they go to the last particle.
    if let Some(last) = particles.last() {
        out.extend(std::iter::repeat_n(Particle { w: step, ..*last }, left));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The measurements a particle visits (from `first_within`, moved on from any previous
    /// answer) are exactly those whose c_x lies in [x − reach, x + reach], by brute force over
    /// all of them, in increasing c_x; none for a NaN x.
    #[test]
    fn a_particle_visits_exactly_the_measurements_in_reach_from_any_start() {
        // Unsorted, with repeated, negative and far-apart centres.
        let xs = [7.0, -40.0, 0.0, 31.0, 2.5, 0.0, 90.0, -3.0, 7.0, 30.0];
        let zs: Vec<BoxMeasurement> = xs.iter().map(|&x| [x, 1.0, 10.0, 20.0]).collect();
        let reach = 5.0;
        let sorted = SortedByX::new(&zs, reach);
        let particles = [
            -100.0,
            -45.0,
            -35.0,
            -3.0,
            0.0,
            2.0,
            2.5,
            4.5,
            12.0,
            25.0,
            33.0,
            85.0,
            95.0,
            200.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for &x in &particles {
            let mut expected: Vec<(f64, u32)> = (0..zs.len())
                .filter(|&j| zs[j][0] >= x - reach && zs[j][0] <= x + reach)
                .map(|j| (zs[j][0], j as u32))
                .collect();
            expected.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            for from in 0..=zs.len() + 2 {
                let start = sorted.first_within(x, from);
                let visited: Vec<(f64, u32)> = (start..zs.len())
                    .take_while(|&k| sorted.zs[k][0] <= x + reach)
                    .map(|k| (sorted.zs[k][0], sorted.index[k]))
                    .collect();
                assert_eq!(visited, expected, "x = {x}, from = {from}");
            }
        }
    }
}
