//! The particle every tracker carries: kinematic state (current and previous, for second-order
//! dynamics, Odobez's c_k = (α_k, α_{k−1})) and the hidden switching variables of Wu et al.

use dbn_switch::{ClutterState, StatusState, TrackStatus};

use crate::space::StateVector;

/// One hypothesis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle {
    /// The shape-space state at the current frame (α_k or X_k).
    pub now: StateVector,
    /// The state at the previous frame (α_{k−1}).
    pub prev: StateVector,
    /// Clutter class β and density λ (Wu §4); a fixed λ when the tracker does not switch.
    pub clutter: ClutterState,
    /// Status α and occlusion γ (Wu §5); γ = 0 and α = locked when occlusion is not modelled.
    pub status: StatusState,
    /// The motion cluster this particle was assigned to at the last step (Odobez §5), or
    /// `u32::MAX` when no motion was estimated.
    pub cluster: u32,
}

impl Particle {
    /// A particle at rest at `state` with the given hidden variables.
    pub fn at_rest(state: StateVector, clutter: ClutterState, status: StatusState) -> Self {
        Self {
            now: state,
            prev: state,
            clutter,
            status,
            cluster: NO_CLUSTER,
        }
    }

    /// The occlusion degree γ.
    pub fn gamma(&self) -> f64 {
        self.status.gamma
    }
}

/// Marker for "no motion cluster".
pub const NO_CLUSTER: u32 = u32::MAX;

/// The hidden variables of a tracker that models neither clutter switching nor occlusion.
pub fn default_status() -> StatusState {
    StatusState {
        alpha: TrackStatus::Locked,
        gamma: 0.0,
    }
}
