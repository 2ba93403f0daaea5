//! The components a particle can be drawn from, each with its density so that every weight is
//! prior × likelihood / proposal (Odobez Eq. 3):
//!
//! - the transition prior itself (`dynamics`, as `smc_core::Bootstrap`): the Gaussian or
//!   Cauchy AR2 kinematics and the hidden processes;
//! - Odobez's motion proposal (Eq. 16, [`motion`]): around each cluster's robust affine motion;
//! - the reacquisition component of the prior (`crate::dynamics::reacquisition`): a share of the
//!   particles drawn around the remembered pose, or the appearance's best detection, while the
//!   track is not locked; every proposal carries it, as part of the model;
//! - hidden-chain exploration ([`explore`]): the hidden chains drawn from an exploring transition.

pub mod explore;
pub mod motion;

pub use explore::ExploringPrior;
pub use motion::{ClusterMotion, MotionProposal, state_increment};
