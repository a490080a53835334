//! The Gaussian-mixture PHD filter (Vo & Ma, IEEE TSP 54(11), 2006) over boxes, with the same
//! measurement-driven birth as the SMC filter so the two approximate the same recursion:
//! prediction, the missed-detection and per-measurement components, pruning (w < 1e-5),
//! merging (Mahalanobis distance ≤ U), capping at J_max, and extraction of every component of
//! weight above the threshold. Components carry labels: a detection-updated component keeps
//! its parent's, a merged one the heaviest member's.

use nalgebra::{Cholesky, SMatrix, SVector};
use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, LN_2PI, ensure_non_negative};

use crate::config::{Motion, PhdConfig, measurement_from_box, state_box};
use crate::error::{Error, Result, invalid_parameter};
use crate::smc::{Estimate, PhdStep};

type Vec6 = SVector<f64, 6>;
type Mat6 = SMatrix<f64, 6, 6>;
type Vec4 = SVector<f64, 4>;
type Mat4 = SMatrix<f64, 4, 4>;
type Mat64 = SMatrix<f64, 6, 4>;

/// Mixture management of the GM-PHD filter (Vo & Ma's values by default).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GmConfig {
    /// Components lighter than this are dropped (T).
    pub prune_below: f64,
    /// Components within this squared Mahalanobis distance of the heaviest are merged (U).
    pub merge_distance: f64,
    /// At most this many components are kept (J_max).
    pub max_components: usize,
}

impl GmConfig {
    /// Checks every field; [`GmPhd::new`] calls it.
    pub fn check(&self) -> Result<()> {
        ensure_non_negative(self.prune_below, "prune_below")?;
        ensure_non_negative(self.merge_distance, "merge_distance")?;
        if self.max_components == 0 {
            return Err(invalid_parameter(
                "max_components",
                "0; the mixture must keep at least one component".into(),
            ));
        }
        Ok(())
    }
}

impl Default for GmConfig {
    fn default() -> Self {
        Self {
            prune_below: 1e-5,
            merge_distance: 4.0,
            max_components: 100,
        }
    }
}

/// One weighted Gaussian component.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Component {
    /// Weight.
    pub w: f64,
    /// Mean state.
    pub m: Vec6,
    /// Covariance.
    pub p: Mat6,
    /// Identity.
    pub label: u64,
}

/// The GM-PHD filter.
#[derive(Debug, Clone)]
pub struct GmPhd {
    config: PhdConfig,
    gm: GmConfig,
    f: Mat6,
    q: Mat6,
    r: Mat4,
    birth_cov: Mat6,
    components: Vec<Component>,
    next_label: u64,
}

/// Squared Mahalanobis distance beyond which a (component, measurement) pair is ignored.
const GATE: f64 = 50.0;

/// Per-component quantities of the update that do not depend on the measurement.
struct Innovation {
    factor: Cholesky<f64, nalgebra::Const<4>>,
    log_norm: f64,
    gain: Mat64,
    cov: Mat6,
}

/// A gated (component, measurement) pair of one measurement: the component's index,
/// q = p_D w N(z; H m, S) and the residual z − H m.
type GatedPair = (usize, f64, Vec4);

/// log N(z; H m, S) of a component for a measurement, and the residual z − H m.
fn log_density(c: &Component, inn: &Innovation, z: &Vec4) -> (f64, Vec4) {
    let residual = z - c.m.fixed_rows::<4>(0);
    let maha = residual.dot(&inn.factor.solve(&residual));
    (inn.log_norm - 0.5 * maha, residual)
}

fn innovation(c: &Component, r: &Mat4) -> Result<Innovation> {
    let hp: SMatrix<f64, 4, 6> = c.p.fixed_rows::<4>(0).into_owned();
    let s: Mat4 = hp.fixed_columns::<4>(0).into_owned() + r;
    let factor =
        Cholesky::new(s).ok_or(Error::Model(tracker_model::Error::NotPositiveDefinite {
            what: "GM-PHD innovation covariance",
        }))?;
    let log_det: f64 = factor.l().diagonal().iter().map(|d| 2.0 * d.ln()).sum();
    // K = P Hᵀ S⁻¹ = (S⁻¹ H P)ᵀ.
    let gain: Mat64 = factor.solve(&hp).transpose();
    let cov = c.p - gain * hp;
    Ok(Innovation {
        factor,
        log_norm: -2.0 * LN_2PI - 0.5 * log_det,
        gain,
        cov: (cov + cov.transpose()) * 0.5,
    })
}

impl GmPhd {
    /// A filter with no targets.
    pub fn new(config: PhdConfig, gm: GmConfig) -> Result<Self> {
        config.check()?;
        gm.check()?;
        let mut f = Mat6::identity();
        let mut q = Mat6::zeros();
        let mut birth_cov = Mat6::zeros();
        for k in 0..4 {
            birth_cov[(k, k)] = config.measurement_std[k].powi(2);
        }
        match config.motion {
            Motion::RandomWalk {
                position_std,
                size_std,
            } => {
                q[(0, 0)] = position_std.powi(2);
                q[(1, 1)] = position_std.powi(2);
                q[(2, 2)] = size_std.powi(2);
                q[(3, 3)] = size_std.powi(2);
                // Velocities are not used; a unit variance keeps P invertible for merging.
                birth_cov[(4, 4)] = 1.0;
                birth_cov[(5, 5)] = 1.0;
            }
            Motion::ConstantVelocity {
                acceleration_std,
                size_std,
            } => {
                f[(0, 4)] = 1.0;
                f[(1, 5)] = 1.0;
                q[(2, 2)] = size_std.powi(2);
                q[(3, 3)] = size_std.powi(2);
                q[(4, 4)] = acceleration_std.powi(2);
                q[(5, 5)] = acceleration_std.powi(2);
                birth_cov[(4, 4)] = config.birth_velocity_std.powi(2);
                birth_cov[(5, 5)] = config.birth_velocity_std.powi(2);
            }
        }
        Ok(Self {
            r: Mat4::from_diagonal(&Vec4::from(config.measurement_std.map(|s| s * s))),
            config,
            gm,
            f,
            q,
            birth_cov,
            components: Vec::new(),
            next_label: 0,
        })
    }

    /// The mixture after the last frame.
    pub fn components(&self) -> &[Component] {
        &self.components
    }

    /// Runs one frame with the given detections: predict, add the newborns, update, reduce,
    /// extract the estimates, and reduce again with the updated newborns.
    pub fn step(&mut self, boxes: &[BoundingBox]) -> Result<PhdStep> {
        self.step_after(1, boxes)
    }

    /// Runs the frame `frames` frames after the last one, the frames between having had no
    /// detection, in one prediction by the exact transition ([`Motion::transition`]):
    /// m ← F(k) m, P ← F(k) P F(k)ᵀ + Q(k), w ← [`PhdConfig::gap_weight`] w. Stepping each
    /// empty frame would give the same mixture but for the pruning and merging between frames
    /// (weights scale alike, so pruning after the gap removes what pruning on the way would
    /// have). The cost does not depend on `frames`; `frames = 0` is an error.
    pub fn step_after(&mut self, frames: u64, boxes: &[BoundingBox]) -> Result<PhdStep> {
        crate::config::check_frames_after(frames)?;
        let zs: Vec<(usize, Vec4)> = boxes
            .iter()
            .enumerate()
            .filter_map(|(i, b)| measurement_from_box(b).map(|z| (i, SVector::from(z))))
            .collect();
        let skipped = boxes.len() - zs.len();
        let cfg = self.config;
        self.predict(frames);
        let innovations = self
            .components
            .iter()
            .map(|c| innovation(c, &self.r))
            .collect::<Result<Vec<_>>>()?;
        let nu = if zs.is_empty() {
            0.0
        } else {
            cfg.birth_rate / zs.len() as f64
        };
        let newborn = self.spawn_newborn(&zs, nu);
        let newborn_innovations = newborn
            .iter()
            .map(|c| innovation(c, &self.r))
            .collect::<Result<Vec<_>>>()?;
        let per_z = self.gate(&zs, &innovations);
        let (detected, updated_newborn) = self.update(
            &zs,
            &per_z,
            &innovations,
            &newborn,
            &newborn_innovations,
            nu,
        );
        for c in &mut self.components {
            c.w *= 1.0 - cfg.p_detect;
        }
        self.components.extend(detected);
        let expected_targets: f64 = self.components.iter().map(|c| c.w).sum();
        self.reduce()?;
        let estimates = self.extract();
        self.components.extend(updated_newborn);
        self.reduce()?;
        Ok(PhdStep {
            estimates,
            expected_targets,
            skipped,
        })
    }

    /// Predict over `frames` frames: every component moves by F(k), gains Q(k) and is
    /// weighted by p_S per frame and 1 − p_D per empty frame between.
    fn predict(&mut self, frames: u64) {
        let (f, q) = if frames == 1 {
            (self.f, self.q)
        } else {
            let (f, q) = self.config.motion.transition(frames);
            (Mat6::from_fn(|i, j| f[i][j]), Mat6::from_fn(|i, j| q[i][j]))
        };
        let survive = self.config.gap_weight(frames);
        for c in &mut self.components {
            c.w *= survive;
            c.m = f * c.m;
            c.p = f * c.p * f.transpose() + q;
        }
    }

    /// Newborns: one component per measurement, at the measurement, of weight `nu` and with a
    /// fresh label.
    fn spawn_newborn(&mut self, zs: &[(usize, Vec4)], nu: f64) -> Vec<Component> {
        let newborn: Vec<Component> = zs
            .iter()
            .enumerate()
            .map(|(j, (_, z))| {
                let mut m = Vec6::zeros();
                m.fixed_rows_mut::<4>(0).copy_from(z);
                Component {
                    w: nu,
                    m,
                    p: self.birth_cov,
                    label: self.next_label + j as u64,
                }
            })
            .collect();
        self.next_label += zs.len() as u64;
        newborn
    }

    /// The (component, measurement) pairs within the gate, per measurement.
    fn gate(&self, zs: &[(usize, Vec4)], innovations: &[Innovation]) -> Vec<Vec<GatedPair>> {
        let p_d = self.config.p_detect;
        let mut per_z: Vec<Vec<GatedPair>> = vec![Vec::new(); zs.len()];
        for (j, (_, z)) in zs.iter().enumerate() {
            for (i, (c, inn)) in self.components.iter().zip(innovations).enumerate() {
                let (ld, residual) = log_density(c, inn, z);
                // Pairs beyond the gate (the SMC likelihood's cut-off, χ² = 50) would only
                // add components that pruning removes.
                if ld < inn.log_norm - 0.5 * GATE {
                    continue;
                }
                let q = p_d * c.w * ld.exp();
                if q > 0.0 {
                    per_z[j].push((i, q, residual));
                }
            }
        }
        per_z
    }

    /// The update: per measurement, L(z) = κ + ν N(z; newborn) + Σ q, the detection-updated
    /// components (weights q / L) and the updated newborn. Returns both lists.
    fn update(
        &self,
        zs: &[(usize, Vec4)],
        per_z: &[Vec<GatedPair>],
        innovations: &[Innovation],
        newborn: &[Component],
        newborn_innovations: &[Innovation],
        nu: f64,
    ) -> (Vec<Component>, Vec<Component>) {
        let kappa = self.config.clutter_intensity();
        let mut detected: Vec<Component> = Vec::new();
        let mut updated_newborn: Vec<Component> = Vec::with_capacity(newborn.len());
        for (j, (_, z)) in zs.iter().enumerate() {
            let (nb_ld, nb_residual) = log_density(&newborn[j], &newborn_innovations[j], z);
            let birth_term = nu * nb_ld.exp();
            let l = kappa + birth_term + per_z[j].iter().map(|t| t.1).sum::<f64>();
            for (i, q, residual) in &per_z[j] {
                let c = &self.components[*i];
                let inn = &innovations[*i];
                detected.push(Component {
                    w: q / l,
                    m: c.m + inn.gain * residual,
                    p: inn.cov,
                    label: c.label,
                });
            }
            let inn = &newborn_innovations[j];
            updated_newborn.push(Component {
                w: birth_term / l,
                m: newborn[j].m + inn.gain * nb_residual,
                p: inn.cov,
                label: newborn[j].label,
            });
        }
        (detected, updated_newborn)
    }

    /// Extraction, heaviest first; a label already used goes to a new identity.
    fn extract(&mut self) -> Vec<Estimate> {
        let mut order: Vec<usize> = (0..self.components.len())
            .filter(|&i| self.components[i].w > self.config.extraction_threshold)
            .collect();
        order.sort_by(|&a, &b| {
            self.components[b]
                .w
                .total_cmp(&self.components[a].w)
                .then(a.cmp(&b))
        });
        let mut used: Vec<u64> = Vec::new();
        let mut estimates = Vec::with_capacity(order.len());
        for i in order {
            if used.contains(&self.components[i].label) {
                self.components[i].label = self.next_label;
                self.next_label += 1;
            }
            let c = &self.components[i];
            used.push(c.label);
            let state: [f64; 6] = c.m.into();
            estimates.push(Estimate {
                label: c.label,
                state,
                bbox: state_box(&state),
                weight: c.w,
                measurement: None,
            });
        }
        estimates
    }

    /// Pruning, merging and capping: components are visited by decreasing weight; each one not
    /// yet merged absorbs every later one within the merge distance (Vo & Ma's Table II).
    fn reduce(&mut self) -> Result<()> {
        let mut rest: Vec<Component> = self
            .components
            .drain(..)
            .filter(|c| c.w > self.gm.prune_below && c.w.is_finite())
            .collect();
        rest.sort_by(|a, b| b.w.total_cmp(&a.w));
        let u = self.gm.merge_distance;
        let mut taken = vec![false; rest.len()];
        let mut merged = Vec::new();
        for i in 0..rest.len() {
            if taken[i] {
                continue;
            }
            let anchor = rest[i];
            let factor = Cholesky::new(anchor.p).ok_or(Error::Model(
                tracker_model::Error::NotPositiveDefinite {
                    what: "GM-PHD component covariance",
                },
            ))?;
            let mut members = vec![i];
            for (k, c) in rest.iter().enumerate().skip(i + 1) {
                if taken[k] {
                    continue;
                }
                let d = c.m - anchor.m;
                // dᵀP⁻¹d ≥ d_k² / P_kk for every axis k (Cauchy-Schwarz in P's inner
                // product), so a component far along c_x or c_y is rejected without solving.
                if d[0] * d[0] > u * anchor.p[(0, 0)] || d[1] * d[1] > u * anchor.p[(1, 1)] {
                    continue;
                }
                if d.dot(&factor.solve(&d)) <= u {
                    taken[k] = true;
                    members.push(k);
                }
            }
            let w: f64 = members.iter().map(|&k| rest[k].w).sum();
            let m: Vec6 = members.iter().map(|&k| rest[k].m * rest[k].w).sum::<Vec6>() / w;
            let p: Mat6 = members
                .iter()
                .map(|&k| {
                    let c = &rest[k];
                    (c.p + (m - c.m) * (m - c.m).transpose()) * c.w
                })
                .sum::<Mat6>()
                / w;
            merged.push(Component {
                w,
                m,
                p: (p + p.transpose()) * 0.5,
                label: anchor.label,
            });
        }
        merged.sort_by(|a, b| b.w.total_cmp(&a.w));
        merged.truncate(self.gm.max_components);
        self.components = merged;
        Ok(())
    }
}
