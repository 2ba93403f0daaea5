//! Loading and saving settings as JSON or TOML, always validated.

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
    /// # Errors
    /// A validation error, [`Error::UnknownFormat`], [`Error::Io`].
    fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.check()?;
        let text = match Format::of(path)? {
            Format::Json => self.to_json_string()?,
            Format::Toml => self.to_toml_string()?,
        };
        std::fs::write(path, text).map_err(|source| Error::Io {
            path: path.to_owned(),
            source,
        })
    }
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
