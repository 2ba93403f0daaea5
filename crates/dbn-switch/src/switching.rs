//! All three processes' settings in one file, for trackers and the command line.

use serde::{Deserialize, Serialize};

use crate::clutter::ClutterConfig;
use crate::config::ConfigFile;
use crate::error::Result;
use crate::occlusion::OcclusionConfig;
use crate::status::StatusConfig;

/// Settings of every hidden switching process of Wu et al.; each section defaults to Wu's
/// published values and may be omitted from a file.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SwitchingConfig {
    /// The clutter process `{β, λ}` (Wu §4, §6.1).
    #[serde(default)]
    pub clutter: ClutterConfig,
    /// The occlusion random walk `γ` (Wu §5, §6.2).
    #[serde(default)]
    pub occlusion: OcclusionConfig,
    /// The status HMM `{α, γ}` (Wu §5, §6.3).
    #[serde(default)]
    pub status: StatusConfig,
}

impl SwitchingConfig {
    /// Checks every section.
    ///
    /// # Errors
    /// The first error of [`ClutterConfig::validate`], [`OcclusionConfig::validate`] or
    /// [`StatusConfig::validate`].
    pub fn validate(&self) -> Result<()> {
        self.clutter.validate()?;
        self.occlusion.validate()?;
        self.status.validate()
    }
}

impl ConfigFile for SwitchingConfig {
    fn check(&self) -> Result<()> {
        self.validate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

    #[test]
    fn json_and_toml_round_trip_through_files() {
        let dir = tempfile::tempdir().unwrap();
        let mut config = SwitchingConfig::default();
        config.clutter.lambda_model = crate::LambdaModel::Fixed;
        config.occlusion.sigma_gamma = 0.05;
        for name in ["switching.json", "switching.toml"] {
            let path = dir.path().join(name);
            config.save(&path).unwrap();
            assert_eq!(SwitchingConfig::load(&path).unwrap(), config, "{name}");
        }
        // Each section on its own, too.
        let path = dir.path().join("status.toml");
        StatusConfig::default().save(&path).unwrap();
        assert_eq!(StatusConfig::load(&path).unwrap(), StatusConfig::default());
    }

    #[test]
    fn missing_sections_default_and_invalid_files_are_typed_errors() {
        let config = SwitchingConfig::from_toml_str("[occlusion]\nsigma_gamma = 0.2\n").unwrap();
        assert_eq!(config.clutter, ClutterConfig::default());
        assert_eq!(config.occlusion.sigma_gamma, 0.2);

        // Wu's printed range for "partially occluded" is caught at load time.
        let typo = "[status.partially_occluded]\nlow = 1.0\nhigh = 0.9\n";
        let text = SwitchingConfig::default().to_toml_string().unwrap();
        let text = text.replace("[status.partially_occluded]\nlow = 0.1\nhigh = 0.9\n", typo);
        assert!(text.contains(typo), "{text}");
        assert!(matches!(
            SwitchingConfig::from_toml_str(&text),
            Err(Error::InvalidRange { .. })
        ));

        let json = r#"{"clutter": {"transition": [[0.5, 0.6], [0.5, 0.5]],
            "lambda_mean": [0.01, 0.1], "lambda_std": [0.01, 0.01]}}"#;
        assert!(matches!(
            SwitchingConfig::from_json_str(json),
            Err(Error::InvalidTransitionMatrix { row: 0, .. })
        ));
        assert!(matches!(
            SwitchingConfig::from_json_str("{"),
            Err(Error::Json { .. })
        ));
        assert!(matches!(
            SwitchingConfig::from_toml_str("clutter = 3"),
            Err(Error::TomlDe { .. })
        ));
        assert!(matches!(
            SwitchingConfig::from_json_str(r#"{"occlusion": {"sigma_gamma": 0.1, "typo": 1}}"#),
            Err(Error::Json { .. })
        ));

        let dir = tempfile::tempdir().unwrap();
        let yaml = dir.path().join("switching.yaml");
        assert!(matches!(
            SwitchingConfig::default().save(&yaml),
            Err(Error::UnknownFormat { .. })
        ));
        assert!(matches!(
            SwitchingConfig::load(dir.path().join("absent.toml")),
            Err(Error::Io { .. })
        ));
        let mut invalid = SwitchingConfig::default();
        invalid.occlusion.sigma_gamma = -1.0;
        assert!(matches!(
            invalid.save(dir.path().join("x.json")),
            Err(Error::InvalidStd { .. })
        ));
    }
}
