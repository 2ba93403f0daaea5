//! From a configuration to a running tracker.

use crate::api::Tracker;
use crate::config::TrackerConfig;
use crate::engine::ParticleTracker;
use crate::working_scale::ScaledTracker;
use crate::{Preset, Result};

/// Builds the tracker a configuration describes.
///
/// # Errors
/// An invalid configuration.
pub fn build(config: TrackerConfig) -> Result<Box<dyn Tracker>> {
    Ok(Box::new(ScaledTracker::new(config)?))
}

/// Builds the tracker a configuration describes, with `terms` of your own added to its
/// likelihood (see [`crate::observation::ObservationTerm`]). The terms see the frames and
/// particles in the tracker's working pixels ([`crate::working_scale`]).
///
/// # Errors
/// An invalid configuration.
pub fn build_with_terms(
    config: TrackerConfig,
    terms: Vec<Box<dyn crate::ObservationTerm>>,
) -> Result<Box<dyn Tracker>> {
    let mut inner = ParticleTracker::new(config)?;
    for term in terms {
        inner.push_term(term);
    }
    Ok(Box::new(ScaledTracker::from_tracker(inner)))
}

/// Builds a preset by name with `particles` particles and `seed`.
///
/// # Errors
/// [`crate::Error::UnknownPreset`] or an invalid configuration.
pub fn build_preset(name: &str, particles: usize, seed: u64) -> Result<Box<dyn Tracker>> {
    build(Preset::from_name(name)?.config(particles, seed))
}
