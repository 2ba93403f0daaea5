//! Loading and saving settings as JSON or TOML, always validated.

use std::io::Write;
use std::path::Path;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::error::{Error, Result};

/// A settings struct that can be read from and written to JSON or TOML.
///
/// Every reader validates what it read, and [`ConfigFile::save`] validates before writing, so an
/// invalid configuration is a typed [`Error`] at the boundary, never a surprise later.
pub trait ConfigFile: Serialize + DeserializeOwned {
    /// Checks the settings; the inherent `validate` of each implementor.
    ///
    /// # Errors
    /// The first problem found.
    fn check(&self) -> Result<()>;

    /// Parses and validates JSON.
    ///
    /// # Errors
    /// [`Error::Json`] or a validation error.
    fn from_json_str(text: &str) -> Result<Self> {
        let config: Self = serde_json::from_str(text)?;
        config.check()?;
        Ok(config)
    }

    /// Pretty-printed JSON.
    ///
    /// # Errors
    /// [`Error::Json`] (not expected for these plain structs).
    fn to_json_string(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(self)?)
    }

    /// Parses and validates TOML.
    ///
    /// # Errors
    /// [`Error::TomlDe`] or a validation error.
    fn from_toml_str(text: &str) -> Result<Self> {
        let config: Self = toml::from_str(text)?;
        config.check()?;
        Ok(config)
    }

    /// TOML text.
    ///
    /// # Errors
    /// [`Error::TomlSer`] (not expected for these plain structs).
    fn to_toml_string(&self) -> Result<String> {
        Ok(toml::to_string(self)?)
    }

    /// Reads a `.json` or `.toml` file (chosen by extension) and validates it.
    ///
    /// # Errors
    /// [`Error::UnknownFormat`], [`Error::Io`], a parse or a validation error.
    fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let format = Format::of(path)?;
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_owned(),
            source,
        })?;
        match format {
            Format::Json => Self::from_json_str(&text),
            Format::Toml => Self::from_toml_str(&text),
        }
    }

    /// Validates, then writes a `.json` or `.toml` file (chosen by extension).
    ///
    /// The write is atomic: the text goes to a temporary file in the same folder, which is
    /// renamed over `path` only once it is complete and synced. On any error `path` is left as
    /// it was and the temporary file is deleted.
    ///
    /// # Errors
    /// A validation error, [`Error::UnknownFormat`], [`Error::Io`].
    fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.check()?;
        let text = match Format::of(path)? {
            Format::Json => self.to_json_string()?,
            Format::Toml => self.to_toml_string()?,
        };
        write_atomic(path, text.as_bytes())
    }
}

/// Writes `bytes` to a temporary sibling of `path`, syncs it and renames it over `path`.
///
/// The temporary file lives in the destination's own folder because a rename is atomic only
/// within one file system. `tempfile` deletes it when it is dropped before `persist`, so an
/// error at any step leaves no partial file behind.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |source| Error::Io {
        path: path.to_owned(),
        source,
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".dbn-switch-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(io)?;
    tmp.write_all(bytes).map_err(io)?;
    // Temporary files are created readable by their owner only; a configuration is an ordinary
    // file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(io)?;
    }
    tmp.as_file().sync_all().map_err(io)?;
    tmp.persist(path).map_err(|e| io(e.error))?;
    Ok(())
}

enum Format {
    Json,
    Toml,
}

impl Format {
    fn of(path: &Path) -> Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("json") => Ok(Self::Json),
            Some("toml") => Ok(Self::Toml),
            _ => Err(Error::UnknownFormat {
                path: path.to_owned(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SwitchingConfig;

    /// The names in `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn save_replaces_the_file_whole_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("switching.toml");
        std::fs::write(&path, "a much longer earlier file ".repeat(200)).unwrap();
        let config = SwitchingConfig::default();
        config.save(&path).unwrap();
        // Exactly the new text: nothing of the longer earlier file survives past its end.
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            config.to_toml_string().unwrap()
        );
        assert_eq!(names(dir.path()), ["switching.toml"]);
    }

    #[test]
    fn a_failed_save_leaves_the_folder_as_it_was() {
        let dir = tempfile::tempdir().unwrap();
        // A folder in the destination's place: the rename fails after the text was written.
        let path = dir.path().join("switching.json");
        std::fs::create_dir(&path).unwrap();
        assert!(matches!(
            SwitchingConfig::default().save(&path),
            Err(Error::Io { .. })
        ));
        assert_eq!(names(dir.path()), ["switching.json"]);
        assert!(path.is_dir());

        // An invalid configuration is refused before anything is written.
        let earlier = dir.path().join("earlier.json");
        std::fs::write(&earlier, "{}").unwrap();
        let mut invalid = SwitchingConfig::default();
        invalid.occlusion.sigma_gamma = f64::NAN;
        assert!(invalid.save(&earlier).is_err());
        assert_eq!(std::fs::read_to_string(&earlier).unwrap(), "{}");
        assert_eq!(names(dir.path()), ["earlier.json", "switching.json"]);
    }
}
