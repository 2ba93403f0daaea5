//! The printed form of a [`TrackerConfig`] (`track config`, and every file a command writes): the
//! settings the configured tracker reads, and nothing else.
//!
//! A section or field the tracker does not read (see [`TrackerConfig::validate`]) is left out
//! when it holds the value loading fills in for it, which every valid configuration's unread
//! settings do; an unread setting at another value is printed, so that printing never loses a
//! value and loading the file refuses it by name. Left out, each way:
//!
//! - `motion` without the motion proposal or motion consistency ([`TrackerConfig::needs_motion`]);
//! - `clutter` without Wu's likelihood (`likelihood.clutter`), and in `likelihood` its
//!   `clutter_line_fraction` and `occlusion_form`;
//! - `likelihood`'s terms that are off, and `likelihood` itself when every term is off;
//! - `occlusion`, `reacquisition`, `working_radius`, `appearance` when off, as `filter.history`
//!   and `filter.min_ess_fraction` are;
//! - `estimator` without clutter switching (there is no clutter class β̂ to condition on);
//! - `dynamics.locked_gamma_rate` without the status HMM, `dynamics.hidden_exploration` without
//!   a hidden chain (clutter switching or the status HMM);
//! - `reacquisition.detection_share` without `appearance` (there is no detection to jump to).
//!
//! The fields are destructured exhaustively, so a field added to [`TrackerConfig`],
//! [`LikelihoodSettings`], [`DynamicsSettings`] or [`ReacquisitionSettings`] does not compile
//! until it is printed here.

use serde::ser::{Serialize, SerializeStruct, Serializer};

use super::{ClutterMode, MotionSettings, OcclusionMode, PoseEstimator, TrackerConfig};
use crate::dynamics::DynamicsSettings;
use crate::dynamics::reacquisition::ReacquisitionSettings;
use crate::observation::LikelihoodSettings;

/// Writes `value` as `key` when `print`, and skips the field otherwise.
fn field_if<S: SerializeStruct, T: Serialize + ?Sized>(
    out: &mut S,
    key: &'static str,
    value: &T,
    print: bool,
) -> Result<(), S::Error> {
    if print {
        out.serialize_field(key, value)
    } else {
        out.skip_field(key)
    }
}

impl Serialize for TrackerConfig {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let TrackerConfig {
            name,
            particles,
            seed,
            space,
            dynamics,
            proposal,
            motion,
            likelihood,
            clutter,
            occlusion,
            filter,
            resampling,
            estimator,
            init_spread,
            reacquisition,
            working_radius,
            appearance,
        } = self;
        let mut out = serializer.serialize_struct("TrackerConfig", 17)?;
        out.serialize_field("name", name)?;
        out.serialize_field("particles", particles)?;
        out.serialize_field("seed", seed)?;
        out.serialize_field("space", space)?;
        out.serialize_field(
            "dynamics",
            &DynamicsView {
                settings: dynamics,
                status_hmm: self.has_status_hmm(),
                hidden_chains: self.has_hidden_chains(),
            },
        )?;
        out.serialize_field("proposal", proposal)?;
        field_if(
            &mut out,
            "motion",
            motion,
            self.needs_motion() || *motion != MotionSettings::default(),
        )?;
        field_if(
            &mut out,
            "likelihood",
            &LikelihoodView(likelihood),
            *likelihood != LikelihoodSettings::default(),
        )?;
        field_if(
            &mut out,
            "clutter",
            clutter,
            self.reads_clutter() || *clutter != ClutterMode::default(),
        )?;
        field_if(
            &mut out,
            "occlusion",
            occlusion,
            *occlusion != OcclusionMode::None,
        )?;
        out.serialize_field("filter", filter)?;
        out.serialize_field("resampling", resampling)?;
        field_if(
            &mut out,
            "estimator",
            estimator,
            self.has_clutter_switching() || *estimator != PoseEstimator::default(),
        )?;
        out.serialize_field("init_spread", init_spread)?;
        if let Some(settings) = reacquisition {
            let view = ReacquisitionView {
                settings,
                appearance: appearance.is_some(),
            };
            out.serialize_field("reacquisition", &view)?;
        } else {
            out.skip_field("reacquisition")?;
        }
        field_if(
            &mut out,
            "working_radius",
            working_radius,
            working_radius.is_some(),
        )?;
        field_if(&mut out, "appearance", appearance, appearance.is_some())?;
        out.end()
    }
}

/// `likelihood` as printed: the terms that are on, and Wu's line fraction and occlusion form
/// with Wu's likelihood (or when not at their defaults).
struct LikelihoodView<'a>(&'a LikelihoodSettings);

impl Serialize for LikelihoodView<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let LikelihoodSettings {
            shape,
            implicit_motion,
            motion_consistency,
            clutter,
            clutter_line_fraction,
            occlusion_form,
        } = self.0;
        let default = LikelihoodSettings::default();
        let wu = clutter.is_some();
        let mut out = serializer.serialize_struct("LikelihoodSettings", 6)?;
        field_if(&mut out, "shape", shape, shape.is_some())?;
        field_if(
            &mut out,
            "implicit_motion",
            implicit_motion,
            implicit_motion.is_some(),
        )?;
        field_if(
            &mut out,
            "motion_consistency",
            motion_consistency,
            *motion_consistency,
        )?;
        field_if(&mut out, "clutter", clutter, wu)?;
        field_if(
            &mut out,
            "clutter_line_fraction",
            clutter_line_fraction,
            wu || *clutter_line_fraction != default.clutter_line_fraction,
        )?;
        field_if(
            &mut out,
            "occlusion_form",
            occlusion_form,
            wu || *occlusion_form != default.occlusion_form,
        )?;
        out.end()
    }
}

/// `dynamics` as printed: κ of the locked γ with the status HMM, ε of the hidden chains with a
/// hidden chain (or either when not 0).
struct DynamicsView<'a> {
    settings: &'a DynamicsSettings,
    status_hmm: bool,
    hidden_chains: bool,
}

impl Serialize for DynamicsView<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let DynamicsSettings {
            noise,
            sigma_translation,
            sigma_scale,
            sigma_shape,
            velocity_retention,
            shape_velocity_retention,
            min_scale,
            scale_range,
            aspect_range,
            locked_gamma_rate,
            shape_reversion,
            hidden_exploration,
        } = self.settings;
        let default = DynamicsSettings::default();
        let mut out = serializer.serialize_struct("DynamicsSettings", 12)?;
        out.serialize_field("noise", noise)?;
        out.serialize_field("sigma_translation", sigma_translation)?;
        out.serialize_field("sigma_scale", sigma_scale)?;
        out.serialize_field("sigma_shape", sigma_shape)?;
        out.serialize_field("velocity_retention", velocity_retention)?;
        out.serialize_field("shape_velocity_retention", shape_velocity_retention)?;
        out.serialize_field("min_scale", min_scale)?;
        out.serialize_field("scale_range", scale_range)?;
        out.serialize_field("aspect_range", aspect_range)?;
        field_if(
            &mut out,
            "locked_gamma_rate",
            locked_gamma_rate,
            self.status_hmm || *locked_gamma_rate != default.locked_gamma_rate,
        )?;
        out.serialize_field("shape_reversion", shape_reversion)?;
        field_if(
            &mut out,
            "hidden_exploration",
            hidden_exploration,
            self.hidden_chains || *hidden_exploration != default.hidden_exploration,
        )?;
        out.end()
    }
}

/// `reacquisition` as printed: `detection_share` only with an appearance model (or when not at
/// its default).
struct ReacquisitionView<'a> {
    settings: &'a ReacquisitionSettings,
    appearance: bool,
}

impl Serialize for ReacquisitionView<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let ReacquisitionSettings {
            lock_gamma,
            shape_tolerance,
            rollback,
            share_rate,
            max_share,
            detection_share,
            spread,
            spread_growth,
            position_gain,
            velocity_gain,
            shape_gain,
        } = self.settings;
        let default = ReacquisitionSettings::default();
        let mut out = serializer.serialize_struct("ReacquisitionSettings", 11)?;
        out.serialize_field("lock_gamma", lock_gamma)?;
        field_if(
            &mut out,
            "shape_tolerance",
            shape_tolerance,
            shape_tolerance.is_some(),
        )?;
        out.serialize_field("rollback", rollback)?;
        out.serialize_field("share_rate", share_rate)?;
        out.serialize_field("max_share", max_share)?;
        field_if(
            &mut out,
            "detection_share",
            detection_share,
            self.appearance || *detection_share != default.detection_share,
        )?;
        out.serialize_field("spread", spread)?;
        out.serialize_field("spread_growth", spread_growth)?;
        out.serialize_field("position_gain", position_gain)?;
        out.serialize_field("velocity_gain", velocity_gain)?;
        out.serialize_field("shape_gain", shape_gain)?;
        out.end()
    }
}
