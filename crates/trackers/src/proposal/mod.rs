//! The components a particle can be drawn from, each with its density so that every weight is
//! prior × likelihood / proposal (Odobez Eq. 3):
//!
//! - the transition prior itself (`dynamics`, as `smc_core::Bootstrap`): the Gaussian or
//!   Cauchy AR2 kinematics and the hidden processes;
//! - Odobez's motion proposal (Eq. 16, [`motion`]): around each cluster's robust affine motion;
//! - the jump component of the prior (`crate::dynamics::reacquisition`): a share of the
//!   particles drawn around the remembered pose, or the appearance's best detection, while the
//!   track is not locked, and around the detection while it is (abrupt motion, when configured);
//!   every proposal carries it, as part of the model;
//! - the prior weighted by what it does not draw from itself ([`weighted_prior`]): hidden chains
//!   drawn from an exploring transition, and an abrupt-motion jump whose prior is uniform over the
//!   search window but which is drawn around the detection.

pub mod motion;
pub mod weighted_prior;

pub use motion::{ClusterMotion, MotionProposal, state_increment};
pub use weighted_prior::WeightedPrior;
