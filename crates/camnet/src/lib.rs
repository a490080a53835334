//! # camnet
//!
//! Camera-network localisation from object image tracks (Meingast, Oh & Sastry, ICCV 2007,
//! §§3-4; choices in `docs/camnet.md`). Each camera tracks
//! moving objects in its own image with MCMCDA; the image tracks are the features matched
//! between cameras; the matched, time-aligned points give each pair's relative pose; a
//! spanning tree of the view graph and scales from points seen by three cameras put every
//! camera in camera 0's frame, up to one global scale.
//!
//! * [`image_tracks`] / [`image_tracks_from_mot`]: per-camera MCMCDA on blob centroids;
//! * two views: [`eight_point`] (normalised, projected onto essential matrices),
//!   [`sampson_distance`], [`ransac_essential`], [`decompose_essential`] and [`select_pose`]
//!   (cheirality), [`refine_two_view`] (Levenberg-Marquardt on reprojection error), all in
//!   [`estimate_relative_pose`];
//! * [`match_tracks`]: which tracks of two cameras are the same objects;
//!   [`match_tracks_guided`]: the same from a known approximate pose;
//! * [`localise`]: the network, with a pose and its [`PoseRoute`] for every pair of placed
//!   cameras and an optional joint refinement ([`bundle_adjust`]);
//! * [`umeyama`]: similarity alignment, for scoring against the truth;
//! * [`scene`]: the simulated scene of the paper's experiment (people walking, cameras on a
//!   ring, a blob detector with pixel noise, misses and false blobs) and scoring against its
//!   truth.
//!
//! The step every camera pair runs: the relative pose of two cameras from points matched
//! between their images (here exact, so the pose is recovered to rounding):
//!
//! ```
//! use camnet::{EssentialConfig, Pose, angle_between_deg, estimate_relative_pose, project};
//! use nalgebra::{Rotation3, Vector3};
//! use rand::SeedableRng;
//!
//! let rotation = Rotation3::from_euler_angles(0.1, -0.3, 0.05);
//! let truth = Pose { rotation, translation: Vector3::new(1.0, 0.2, -0.1).normalize() };
//! // Matched points (normalised: pixels through K⁻¹); here a scene seen by both cameras.
//! let scene: Vec<_> =
//!     (0..30).map(|i| Vector3::new(i % 6 - 3, i / 6 - 2, 4 + i % 7).cast::<f64>()).collect();
//! let x1: Vec<_> = scene.iter().filter_map(project).collect();
//! let x2: Vec<_> = scene.iter().filter_map(|p| project(&truth.apply(p))).collect();
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1); // RANSAC's draws
//! let est = estimate_relative_pose(&x1, &x2, &EssentialConfig::default(), &mut rng)?;
//! assert!(camnet::rotation_error_deg(&est.pose.rotation, &truth.rotation) < 1e-6);
//! assert!(angle_between_deg(&est.pose.translation, &truth.translation) < 1e-6); // up to scale
//! # Ok::<(), camnet::Error>(())
//! ```
//!
//! [`localise`] runs it on the image tracks of every pair of cameras and places the network.

mod bundle;
mod correspondence;
mod error;
mod essential;
mod geometry;
mod network;
mod refine;
pub mod scene;
mod tracks;

#[cfg(test)]
mod tests;

pub use bundle::{Bundle, BundleObservation, bundle_adjust};
pub use correspondence::{
    CorrespondenceConfig, FeatureTrack, PairMatching, TrackMatch, match_tracks, match_tracks_guided,
};
pub use error::{Error, Result};
pub use essential::{
    COLLINEAR_RATIO, EssentialConfig, MIN_POINTS, RansacResult, TwoViewEstimate, count_in_front,
    decompose_essential, eight_point, eight_point_indices, estimate_relative_pose,
    estimate_relative_pose_from, fit_all_and_refit, polish_essential, project_to_essential,
    ransac_essential, ransac_essential_from, rotation_only_parallax, sampson_distance, select_pose,
};
pub use geometry::{
    Intrinsics, Pose, Similarity, angle_between_deg, project, rotation_error_deg, skew,
    triangulate, umeyama,
};
pub use network::{
    BundleSummary, CameraTracks, Network, NetworkConfig, PairResult, PoseRoute, localise,
};
pub use refine::{RefineConfig, Refined, refine_two_view};
pub use tracks::{
    Blob, Features, ImageTrack, ImageTrackConfig, image_tracks, image_tracks_from_mot,
};
