//! Which settings a configured tracker reads, and the refusal of an unread setting that is not
//! at the value its printed form leaves out ([`TrackerConfig::validate`]): a setting a tracker
//! cannot honour is refused by name, never ignored.

use super::{ClutterMode, MotionSettings, OcclusionMode, PoseEstimator, TrackerConfig};
use crate::dynamics::DynamicsSettings;
use crate::dynamics::reacquisition::ReacquisitionSettings;
use crate::{Error, Result};

/// Why `motion` is not read.
const NO_MOTION: &str = "this tracker has neither the motion proposal (`proposal = \"motion\"`) \
                         nor motion consistency (`likelihood.motion_consistency`)";

/// An unread setting: `name`, set to something other than what loading fills in.
fn unread(name: &'static str, why: &str) -> Error {
    Error::InvalidSetting {
        name,
        reason: format!("not read: {why}; remove it (or turn on what reads it)"),
    }
}

impl TrackerConfig {
    /// Whether Wu's likelihood is on, the only reader of `clutter`.
    pub(crate) fn reads_clutter(&self) -> bool {
        self.likelihood.clutter.is_some()
    }

    /// Whether the clutter class β switches, the only way a clutter class β̂ (and so
    /// `estimator`) means anything.
    pub(crate) fn has_clutter_switching(&self) -> bool {
        matches!(self.clutter, ClutterMode::Switching(_))
    }

    /// Whether the occlusion process is Wu's status HMM {α, γ}, the only reader of
    /// `dynamics.locked_gamma_rate`.
    pub(crate) fn has_status_hmm(&self) -> bool {
        matches!(self.occlusion, OcclusionMode::Status(_))
    }

    /// Whether a hidden chain (β, or α of the status HMM) is drawn, the only reader of
    /// `dynamics.hidden_exploration`.
    pub(crate) fn has_hidden_chains(&self) -> bool {
        self.has_clutter_switching() || self.has_status_hmm()
    }

    /// Refuses the first unread setting that is not at its default, by its dotted path.
    pub(super) fn check_unread(&self) -> Result<()> {
        if !self.needs_motion() {
            let MotionSettings {
                estimator,
                warm_start,
                fail_together,
                offset,
                min_clusters,
                clusters_per_particle,
                cluster_iterations,
                occlusion_aware,
                working_radius,
                frame_check_pixels,
            } = &self.motion;
            let d = MotionSettings::default();
            let changed = [
                ("motion.estimator", *estimator != d.estimator),
                ("motion.warm_start", *warm_start != d.warm_start),
                ("motion.fail_together", *fail_together != d.fail_together),
                ("motion.offset", *offset != d.offset),
                ("motion.min_clusters", *min_clusters != d.min_clusters),
                (
                    "motion.clusters_per_particle",
                    *clusters_per_particle != d.clusters_per_particle,
                ),
                (
                    "motion.cluster_iterations",
                    *cluster_iterations != d.cluster_iterations,
                ),
                (
                    "motion.occlusion_aware",
                    *occlusion_aware != d.occlusion_aware,
                ),
                ("motion.working_radius", *working_radius != d.working_radius),
                (
                    "motion.frame_check_pixels",
                    *frame_check_pixels != d.frame_check_pixels,
                ),
            ];
            if let Some((name, _)) = changed.into_iter().find(|(_, c)| *c) {
                return Err(unread(name, NO_MOTION));
            }
        }
        if !self.reads_clutter() && self.clutter != ClutterMode::default() {
            let name = match self.clutter {
                ClutterMode::Fixed { .. } => "clutter.lambda",
                ClutterMode::Switching(_) => "clutter",
            };
            return Err(unread(
                name,
                "the clutter process is read by Wu's likelihood only, and this tracker has none \
                 (`likelihood.clutter`)",
            ));
        }
        if !self.has_clutter_switching() && self.estimator != PoseEstimator::default() {
            return Err(unread(
                "estimator",
                "the class-conditional mean is the mean of the particles of the most probable \
                 clutter class β̂, and this tracker has no clutter switching \
                 (`clutter.switching`), so its pose is the weighted mean",
            ));
        }
        let d = DynamicsSettings::default();
        if !self.has_status_hmm() && self.dynamics.locked_gamma_rate != d.locked_gamma_rate {
            return Err(unread(
                "dynamics.locked_gamma_rate",
                "it shapes γ of the status HMM's locked state, and this tracker has no status \
                 HMM (`occlusion.status`)",
            ));
        }
        if !self.has_hidden_chains() && self.dynamics.hidden_exploration != d.hidden_exploration {
            return Err(unread(
                "dynamics.hidden_exploration",
                "it explores the hidden chains (clutter switching, the status HMM), and this \
                 tracker has neither",
            ));
        }
        let detection_share = self.reacquisition.map_or(0.0, |r| r.detection_share);
        if self.appearance.is_none()
            && detection_share != ReacquisitionSettings::default().detection_share
        {
            return Err(unread(
                "reacquisition.detection_share",
                "the abrupt-motion jump is drawn around the appearance's detection, and this \
                 tracker has no appearance model (`appearance`)",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::{ClutterMode, Error, PoseEstimator, Preset};

    fn refused_as(c: &crate::TrackerConfig) -> (&'static str, String) {
        match c.validate() {
            Err(Error::InvalidSetting { name, reason }) => (name, reason),
            other => panic!("{}: {other:?}", c.name),
        }
    }

    #[test]
    fn unread_settings_away_from_their_defaults_are_refused_by_name() {
        let mut c = Preset::M1.config(50, 1);
        c.motion.warm_start = false;
        let (name, reason) = refused_as(&c);
        assert_eq!(name, "motion.warm_start");
        assert!(reason.starts_with("not read: "), "{reason}");
        assert!(reason.contains("motion consistency"), "{reason}");

        let mut c = Preset::M2.config(50, 1);
        c.motion.estimator.max_iterations += 1;
        assert_eq!(refused_as(&c).0, "motion.estimator");

        let mut c = Preset::M1.config(50, 1);
        c.clutter = ClutterMode::Fixed { lambda: 0.2 };
        let (name, reason) = refused_as(&c);
        assert_eq!(name, "clutter.lambda");
        assert!(reason.contains("Wu's likelihood"), "{reason}");

        let mut c = Preset::WFixed.config(50, 1);
        c.estimator = PoseEstimator::ClassConditionalMean;
        assert_eq!(refused_as(&c).0, "estimator");

        let mut c = Preset::WOcc.config(50, 1);
        c.dynamics.locked_gamma_rate = 2.0;
        assert_eq!(refused_as(&c).0, "dynamics.locked_gamma_rate");

        let mut c = Preset::WFixed.config(50, 1);
        c.dynamics.hidden_exploration = 0.1;
        assert_eq!(refused_as(&c).0, "dynamics.hidden_exploration");

        let mut c = Preset::WOcc.config(50, 1);
        c.reacquisition.as_mut().unwrap().detection_share = 0.1;
        let (name, reason) = refused_as(&c);
        assert_eq!(name, "reacquisition.detection_share");
        assert!(reason.contains("appearance"), "{reason}");
    }

    #[test]
    fn the_same_settings_are_accepted_where_they_are_read() {
        let mut c = Preset::M3.config(50, 1);
        c.motion.warm_start = false;
        c.validate().unwrap();
        let mut c = Preset::WFixed.config(50, 1);
        c.clutter = ClutterMode::Fixed { lambda: 0.2 };
        c.validate().unwrap();
        let mut c = Preset::WHmm.config(50, 1);
        c.estimator = PoseEstimator::Mean;
        c.dynamics.hidden_exploration = 0.1;
        c.validate().unwrap();
        let mut c = Preset::WEval.config(50, 1);
        c.dynamics.locked_gamma_rate = 2.0;
        c.validate().unwrap();
        let mut c = Preset::Head.config(50, 1);
        c.reacquisition.as_mut().unwrap().detection_share = 0.1;
        c.validate().unwrap();
    }
}
