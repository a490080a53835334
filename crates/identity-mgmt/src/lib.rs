//! Identity management for multi-target tracking (Hwang, Balakrishnan, Roy & Tomlin 2004;
//! Balakrishnan, Hwang & Tomlin 2004; Hwang, Roy, Balakrishnan & Tomlin 2004; used by Oh,
//! Hwang & Sastry's (2008) distributed multi-target tracking and identity management).
//!
//! A tracker keeps tracks; this crate keeps, beside them, a belief over which *identity*
//! each track carries:
//!
//! * [`BeliefMatrix`]: identities × tracks, b_ij = P(track j carries identity i). Columns
//!   are probability vectors; a row sums to the identity mass this sensor holds (the square,
//!   doubly stochastic case is one sensor that sees everything). Identities and tracks are
//!   added and removed as targets appear, are handed over and end.
//! * Mixing, B ← B·M ([`BeliefMatrix::mix`]), with M a doubly stochastic [`Continuation`]
//!   matrix of "piece i before the interaction continues as piece j" probabilities, built by
//!   the caller or from MCMC samples ([`Continuation::from_samples`]) given as plain data.
//! * Local information ([`BeliefMatrix::incorporate_local_information`]): replace a column,
//!   test scalability ([`scalability`]: exactly, almost or not scalable, by the assignment
//!   solver and alternating-graph components, or by a maximum flow), then Sinkhorn-scale
//!   ([`sinkhorn`], [`scale_to_marginals`]) back to the row and column targets.
//! * Fusion of two sensors' beliefs about one target ([`fuse`],
//!   [`BeliefMatrix::fuse_track`]) by one of the [`FusionCriterion`]s, then rescaling.
//! * Entropy ([`entropy`], [`BeliefMatrix::entropy`]; nats or bits, [`EntropyUnit`]) and the
//!   most probable identity per track ([`BeliefMatrix::argmax`]).
//!
//! Choices the papers leave open are configuration fields with documented defaults
//! (`docs/identity.md`). Invariants: after every successful update the columns sum to 1 and
//! the rows keep their mass, to the Sinkhorn tolerance; a failed update leaves the matrix
//! unchanged.
//!
//! Two aircraft cross; a transponder read then says which is which:
//!
//! ```
//! use identity_mgmt::{BeliefMatrix, Continuation, IdentityId, ScalingConfig};
//! use tracker_model::TrackId;
//!
//! // Aircraft 1 on track 10 and aircraft 2 on track 20, identities known.
//! let (a, b, t1, t2) = (IdentityId(1), IdentityId(2), TrackId(10), TrackId(20));
//! let mut beliefs = BeliefMatrix::known(&[(a, t1), (b, t2)])?;
//! // They cross; the tracker thinks a swap has probability 0.3.
//! beliefs.mix(&[t1, t2], &Continuation::new(2, vec![0.7, 0.3, 0.3, 0.7])?)?;
//! assert!((beliefs.probability(a, t1)? - 0.7).abs() < 1e-12);
//! // A transponder read says track 20 is aircraft 1, so track 10 must be aircraft 2.
//! let report = beliefs.incorporate_local_information(t2, &[1.0, 0.0], &ScalingConfig::default())?;
//! assert!(report.entropy_after_nats < report.entropy_before_nats);
//! assert!((beliefs.probability(b, t1)? - 1.0).abs() < 1e-9);
//! assert_eq!(beliefs.argmax()[0].identity, Some(b));
//! # Ok::<(), identity_mgmt::Error>(())
//! ```

mod belief;
mod error;
mod fusion;
mod mixing;
mod scaling;

#[cfg(test)]
mod tests;

pub use belief::{ArgmaxIdentity, BeliefMatrix, COLUMN_TOLERANCE, IdentityId, UpdateReport};
pub use error::{Error, Result};
pub use fusion::{
    EntropyUnit, Fused, FusionConfig, FusionCriterion, entropy, fuse, geometric_mixture,
    kl_divergence,
};
pub use mixing::{Continuation, DOUBLY_STOCHASTIC_TOLERANCE, FromSamplesConfig, UnjoinedRule};
pub use scaling::{
    AlmostScalableRule, NotScalableRule, Scalability, ScalabilityMethod, ScalingConfig,
    ScalingReport, SinkhornConfig, SinkhornReport, flow_scalability, scalability,
    scale_to_marginals, sinkhorn, square_scalability,
};
