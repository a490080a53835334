//! The belief matrix: identities × tracks, b_ij = P(track j carries identity i) (Hwang,
//! Balakrishnan, Roy & Tomlin 2004). Columns are probability vectors; row i sums to the mass
//! of identity i held by this sensor (1 for every row in the square, doubly stochastic case
//! of a single sensor that sees every target).

use std::fmt;

use serde::{Deserialize, Serialize};
use tracker_model::TrackId;

use crate::error::{Error, Result};
use crate::fusion::{EntropyUnit, FusionConfig, check_probability, entropy, fuse};
use crate::mixing::Continuation;
use crate::scaling::{
    NotScalableRule, Scalability, ScalingConfig, SinkhornReport, check_entries, check_len,
    scalability_unchecked, scale_classified,
};

/// The identity of a target (an aircraft's call sign, say), as opposed to a track.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct IdentityId(pub u64);

impl fmt::Display for IdentityId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "identity {}", self.0)
    }
}

/// Largest deviation of a column sum from 1 accepted from a caller.
pub const COLUMN_TOLERANCE: f64 = 1e-6;

/// Identities × tracks belief matrix, stored row-major.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(try_from = "BeliefMatrixData")]
pub struct BeliefMatrix {
    identities: Vec<IdentityId>,
    tracks: Vec<TrackId>,
    data: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BeliefMatrixData {
    identities: Vec<IdentityId>,
    tracks: Vec<TrackId>,
    data: Vec<f64>,
}

impl TryFrom<BeliefMatrixData> for BeliefMatrix {
    type Error = Error;
    fn try_from(d: BeliefMatrixData) -> Result<Self> {
        BeliefMatrix::from_row_major(d.identities, d.tracks, d.data)
    }
}

/// What an update (local information or fusion) did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UpdateReport {
    /// The track whose column was replaced.
    pub track: TrackId,
    /// The scalability of the matrix with the new column (after softening, if any).
    pub scalability: Scalability,
    /// The entries forced to 0, by identity and track.
    pub forced_zero: Vec<(IdentityId, TrackId)>,
    /// Whether the new column was softened towards the old one.
    pub softened: bool,
    /// The Sinkhorn run.
    pub sinkhorn: SinkhornReport,
    /// H(B) before the update, nats.
    pub entropy_before_nats: f64,
    /// H(B) after the update, nats.
    pub entropy_after_nats: f64,
    /// ω of the geometric family, for fusion by Shannon, Chernoff or the geometric KL sum.
    pub omega: Option<f64>,
}

/// The most probable identity of one track.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ArgmaxIdentity {
    /// The track.
    pub track: TrackId,
    /// Its most probable identity (the first on ties; `None` with no identities).
    pub identity: Option<IdentityId>,
    /// That identity's probability.
    pub probability: f64,
}

impl BeliefMatrix {
    /// An empty matrix: no identities, no tracks.
    pub fn new() -> Self {
        Self::default()
    }

    /// Builds a matrix from row-major entries, checking ids are distinct, entries finite and
    /// non-negative, and columns sum to 1 within [`COLUMN_TOLERANCE`] (they are then
    /// renormalised exactly).
    pub fn from_row_major(
        identities: Vec<IdentityId>,
        tracks: Vec<TrackId>,
        data: Vec<f64>,
    ) -> Result<Self> {
        check_len("belief matrix", data.len(), identities.len() * tracks.len())?;
        check_entries("belief matrix", &data, tracks.len().max(1))?;
        for (k, id) in identities.iter().enumerate() {
            if identities[..k].contains(id) {
                return Err(Error::DuplicateIdentity { identity: *id });
            }
        }
        for (k, t) in tracks.iter().enumerate() {
            if tracks[..k].contains(t) {
                return Err(Error::DuplicateTrack { track: *t });
            }
        }
        let mut b = Self {
            identities,
            tracks,
            data,
        };
        for j in 0..b.tracks.len() {
            check_probability("belief column", &b.column_at(j))?;
        }
        b.normalise_columns();
        Ok(b)
    }

    /// Builds a matrix from rows (one per identity).
    pub fn from_rows(
        identities: Vec<IdentityId>,
        tracks: Vec<TrackId>,
        rows: &[Vec<f64>],
    ) -> Result<Self> {
        check_len("belief matrix rows", rows.len(), identities.len())?;
        for row in rows {
            check_len("belief matrix row", row.len(), tracks.len())?;
        }
        Self::from_row_major(identities, tracks, rows.concat())
    }

    /// Identities known with certainty: identity k on track k (B = I).
    pub fn known(pairs: &[(IdentityId, TrackId)]) -> Result<Self> {
        let n = pairs.len();
        let mut data = vec![0.0; n * n];
        for k in 0..n {
            data[k * n + k] = 1.0;
        }
        Self::from_row_major(
            pairs.iter().map(|p| p.0).collect(),
            pairs.iter().map(|p| p.1).collect(),
            data,
        )
    }

    /// Number of identities (rows).
    pub fn n_identities(&self) -> usize {
        self.identities.len()
    }

    /// Number of tracks (columns).
    pub fn n_tracks(&self) -> usize {
        self.tracks.len()
    }

    /// The identities, in row order.
    pub fn identities(&self) -> &[IdentityId] {
        &self.identities
    }

    /// The tracks, in column order.
    pub fn tracks(&self) -> &[TrackId] {
        &self.tracks
    }

    /// The row-major entries.
    pub fn as_row_major(&self) -> &[f64] {
        &self.data
    }

    /// The column index of `track`.
    pub fn track_index(&self, track: TrackId) -> Result<usize> {
        self.tracks
            .iter()
            .position(|&t| t == track)
            .ok_or(Error::UnknownTrack { track })
    }

    /// The row index of `identity`.
    pub fn identity_index(&self, identity: IdentityId) -> Result<usize> {
        self.identities
            .iter()
            .position(|&i| i == identity)
            .ok_or(Error::UnknownIdentity { identity })
    }

    /// P(track carries identity).
    pub fn probability(&self, identity: IdentityId, track: TrackId) -> Result<f64> {
        let i = self.identity_index(identity)?;
        let j = self.track_index(track)?;
        Ok(self.data[i * self.n_tracks() + j])
    }

    /// The identity distribution of `track`, in row order.
    pub fn column(&self, track: TrackId) -> Result<Vec<f64>> {
        Ok(self.column_at(self.track_index(track)?))
    }

    fn column_at(&self, j: usize) -> Vec<f64> {
        let n = self.n_tracks();
        (0..self.n_identities())
            .map(|i| self.data[i * n + j])
            .collect()
    }

    /// The distribution of `track` over another list of identities (another sensor's rows),
    /// for fusion; identities this matrix does not know get 0. Mass on an identity missing
    /// from `identities` is [`Error::UnknownIdentity`].
    pub fn column_over(&self, track: TrackId, identities: &[IdentityId]) -> Result<Vec<f64>> {
        let column = self.column(track)?;
        let mut out = vec![0.0; identities.len()];
        for (id, p) in self.identities.iter().zip(&column) {
            match identities.iter().position(|x| x == id) {
                Some(k) => out[k] = *p,
                None if *p > 0.0 => return Err(Error::UnknownIdentity { identity: *id }),
                None => {}
            }
        }
        Ok(out)
    }

    /// Row sums: the mass of each identity held by these tracks.
    pub fn row_sums(&self) -> Vec<f64> {
        let n = self.n_tracks();
        (0..self.n_identities())
            .map(|i| self.data[i * n..(i + 1) * n].iter().sum())
            .collect()
    }

    /// Adds an identity held by none of these tracks (a zero row), e.g. one learnt from a
    /// neighbour.
    pub fn add_identity(&mut self, identity: IdentityId) -> Result<()> {
        if self.identities.contains(&identity) {
            return Err(Error::DuplicateIdentity { identity });
        }
        self.identities.push(identity);
        self.data.extend(std::iter::repeat_n(0.0, self.n_tracks()));
        Ok(())
    }

    /// A new target appears: a new identity, carried with certainty by a new track.
    pub fn add_new_target(&mut self, identity: IdentityId, track: TrackId) -> Result<()> {
        if self.tracks.contains(&track) {
            return Err(Error::DuplicateTrack { track });
        }
        self.add_identity(identity)?;
        let mut column = vec![0.0; self.n_identities()];
        column[self.n_identities() - 1] = 1.0;
        self.add_track(track, &column)
    }

    /// Adds a track with the given identity distribution (in row order), e.g. one handed
    /// over by a neighbour.
    pub fn add_track(&mut self, track: TrackId, column: &[f64]) -> Result<()> {
        if self.tracks.contains(&track) {
            return Err(Error::DuplicateTrack { track });
        }
        check_len("new track's column", column.len(), self.n_identities())?;
        check_probability("new track's column", column)?;
        let n = self.n_tracks();
        let mut data = Vec::with_capacity(self.data.len() + column.len());
        for (i, v) in column.iter().enumerate() {
            data.extend_from_slice(&self.data[i * n..(i + 1) * n]);
            data.push(*v);
        }
        self.data = data;
        self.tracks.push(track);
        Ok(())
    }

    /// Removes a track (hand-over or termination) and returns its column.
    pub fn remove_track(&mut self, track: TrackId) -> Result<Vec<f64>> {
        let j = self.track_index(track)?;
        let column = self.column_at(j);
        let n = self.n_tracks();
        self.data = self
            .data
            .iter()
            .enumerate()
            .filter(|(k, _)| k % n != j)
            .map(|(_, v)| *v)
            .collect();
        self.tracks.remove(j);
        Ok(column)
    }

    /// Mixing after an interaction among `tracks`: their columns B_T become B_T·M, where
    /// m_lj = P(track `tracks[j]` after the interaction continues track `tracks[l]` before
    /// it). Columns are renormalised to remove rounding drift. A doubly stochastic M never
    /// lowers the entropy (each new column is a convex combination of old ones).
    pub fn mix(&mut self, tracks: &[TrackId], m: &Continuation) -> Result<()> {
        check_len("continuation matrix size", m.n(), tracks.len())?;
        let idx: Vec<usize> = tracks
            .iter()
            .map(|&t| self.track_index(t))
            .collect::<Result<_>>()?;
        for (k, t) in tracks.iter().enumerate() {
            if tracks[..k].contains(t) {
                return Err(Error::DuplicateTrack { track: *t });
            }
        }
        let n = self.n_tracks();
        let k = tracks.len();
        let mut new_row = vec![0.0; k];
        for i in 0..self.n_identities() {
            let row = &mut self.data[i * n..(i + 1) * n];
            for (j, out) in new_row.iter_mut().enumerate() {
                *out = idx
                    .iter()
                    .enumerate()
                    .map(|(l, &c)| row[c] * m.get(l, j))
                    .sum();
            }
            for (&c, v) in idx.iter().zip(&new_row) {
                row[c] = *v;
            }
        }
        self.normalise_columns();
        Ok(())
    }

    fn normalise_columns(&mut self) {
        let n = self.n_tracks();
        for j in 0..n {
            let s: f64 = (0..self.n_identities()).map(|i| self.data[i * n + j]).sum();
            if s > 0.0 {
                for i in 0..self.n_identities() {
                    self.data[i * n + j] /= s;
                }
            }
        }
    }

    /// Local information about `track` (a probability vector over the identities in row
    /// order; e_i if certain): replace its column and rescale so that every column sums to 1
    /// and every row keeps the identity mass it held, after the scalability test
    /// (`config` says what to do when almost or not scalable). On error the matrix is
    /// unchanged.
    ///
    /// ```
    /// use identity_mgmt::{BeliefMatrix, IdentityId, ScalingConfig};
    /// use tracker_model::TrackId;
    /// let t = 1.0 / 3.0;
    /// let ids = vec![IdentityId(0), IdentityId(1), IdentityId(2)];
    /// let tracks = vec![TrackId(0), TrackId(1), TrackId(2)];
    /// let mut b = BeliefMatrix::from_row_major(ids, tracks, vec![t; 9])?;
    /// let report = b.incorporate_local_information(TrackId(2), &[0.0, 0.0, 1.0], &ScalingConfig::default())?;
    /// assert!(report.entropy_after_nats < report.entropy_before_nats);
    /// assert!((b.probability(IdentityId(0), TrackId(0))? - 0.5).abs() < 1e-9);
    /// # Ok::<(), identity_mgmt::Error>(())
    /// ```
    pub fn incorporate_local_information(
        &mut self,
        track: TrackId,
        information: &[f64],
        config: &ScalingConfig,
    ) -> Result<UpdateReport> {
        config.check()?;
        check_len("local information", information.len(), self.n_identities())?;
        check_probability("local information", information)?;
        self.replace_and_rescale(track, information, config, None)
    }

    /// Fuses this matrix's belief about `track` with a neighbour's belief `other` about the
    /// same physical target (over this matrix's identities in row order; see
    /// [`Self::column_over`]), writes the fused column back and rescales as for local
    /// information.
    pub fn fuse_track(
        &mut self,
        track: TrackId,
        other: &[f64],
        fusion: &FusionConfig,
        config: &ScalingConfig,
    ) -> Result<UpdateReport> {
        config.check()?;
        let own = self.column(track)?;
        let fused = fuse(&own, other, fusion)?;
        self.replace_and_rescale(track, &fused.distribution, config, fused.omega)
    }

    fn replace_and_rescale(
        &mut self,
        track: TrackId,
        column: &[f64],
        config: &ScalingConfig,
        omega: Option<f64>,
    ) -> Result<UpdateReport> {
        let j = self.track_index(track)?;
        let (n_rows, n_cols) = (self.n_identities(), self.n_tracks());
        let row_targets = self.row_sums();
        let col_targets = vec![1.0; n_cols];
        let old = self.column_at(j);
        let entropy_before_nats = self.entropy(EntropyUnit::Nats);
        let mut candidate = self.data.clone();
        let put = |candidate: &mut Vec<f64>, col: &[f64]| {
            for (i, v) in col.iter().enumerate() {
                candidate[i * n_cols + j] = *v;
            }
        };
        put(&mut candidate, column);
        let mut scalability = scalability_unchecked(
            &candidate,
            n_rows,
            n_cols,
            &row_targets,
            &col_targets,
            config,
        )?;
        let mut softened = false;
        if let (Scalability::NotScalable { .. }, NotScalableRule::Soften { old_weight }) =
            (&scalability, config.not_scalable)
        {
            let soft: Vec<f64> = column
                .iter()
                .zip(&old)
                .map(|(l, o)| (1.0 - old_weight) * l + old_weight * o)
                .collect();
            put(&mut candidate, &soft);
            softened = true;
            scalability = scalability_unchecked(
                &candidate,
                n_rows,
                n_cols,
                &row_targets,
                &col_targets,
                config,
            )?;
        }
        let sinkhorn = scale_classified(
            &mut candidate,
            n_rows,
            n_cols,
            &row_targets,
            &col_targets,
            &scalability,
            config,
        )?;
        self.data = candidate;
        let forced_zero = match &scalability {
            Scalability::Almost { forced_zero } => forced_zero
                .iter()
                .map(|&(i, j)| (self.identities[i], self.tracks[j]))
                .collect(),
            _ => Vec::new(),
        };
        Ok(UpdateReport {
            track,
            scalability,
            forced_zero,
            softened,
            sinkhorn,
            entropy_before_nats,
            entropy_after_nats: self.entropy(EntropyUnit::Nats),
            omega,
        })
    }

    /// Entropy of one track's identity distribution.
    pub fn column_entropy(&self, track: TrackId, unit: EntropyUnit) -> Result<f64> {
        Ok(entropy(&self.column(track)?, unit))
    }

    /// H(B) = Σ_j H(b_j), the sum of the column entropies.
    pub fn entropy(&self, unit: EntropyUnit) -> f64 {
        (0..self.n_tracks())
            .map(|j| entropy(&self.column_at(j), unit))
            .sum()
    }

    /// The most probable identity of every track, in column order.
    pub fn argmax(&self) -> Vec<ArgmaxIdentity> {
        (0..self.n_tracks())
            .map(|j| {
                let column = self.column_at(j);
                let best =
                    column
                        .iter()
                        .enumerate()
                        .fold(None, |best: Option<(usize, f64)>, (i, &p)| match best {
                            Some((_, bp)) if bp >= p => best,
                            _ => Some((i, p)),
                        });
                ArgmaxIdentity {
                    track: self.tracks[j],
                    identity: best.map(|(i, _)| self.identities[i]),
                    probability: best.map_or(0.0, |(_, p)| p),
                }
            })
            .collect()
    }
}
