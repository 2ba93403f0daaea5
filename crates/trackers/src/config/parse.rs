//! Reading a configuration file: [`ConfigFormat`] and [`TrackerConfig::parse`], with what
//! earlier releases' files need (their null `region`, and the message naming what replaced a
//! `region` that is set).

use super::TrackerConfig;

/// The text format of a tracker configuration, as `track config` prints it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConfigFormat {
    /// JSON (`track config PRESET`).
    Json,
    /// TOML (`track config PRESET --toml`).
    Toml,
}

impl ConfigFormat {
    /// The format of a configuration file: TOML for a `.toml` extension (any case), JSON
    /// otherwise.
    pub fn of_path(path: &std::path::Path) -> Self {
        let is_toml = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        if is_toml { Self::Toml } else { Self::Json }
    }
}

impl TrackerConfig {
    /// Parses a configuration written as `track config` prints it (sections it leaves out take
    /// their defaults), or as earlier releases printed it. Does not validate it
    /// ([`TrackerConfig::validate`], which refuses unread settings that are not at their
    /// defaults).
    ///
    /// # Errors
    /// A one-line message: `invalid JSON: …`, or `invalid TOML at line L, column C: …`.
    pub fn parse(text: &str, format: ConfigFormat) -> std::result::Result<Self, String> {
        match format {
            ConfigFormat::Toml => toml::from_str(text).map_err(|e| {
                // toml's own message draws the line with a caret over several lines; one line here.
                let at = e
                    .span()
                    .map(|span| {
                        let before = &text[..span.start.min(text.len())];
                        let line = before.matches('\n').count() + 1;
                        let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
                        format!(" at line {line}, column {column}")
                    })
                    .unwrap_or_default();
                format!("invalid TOML{at}: {}", e.message().trim())
            }),
            ConfigFormat::Json => serde_json::from_str(text)
                .or_else(|e| {
                    without_null_region(text)
                        .ok_or(e)
                        .and_then(serde_json::from_value)
                })
                .map_err(|e| format!("invalid JSON: {e}")),
        }
        .map_err(|message| match replaced_field(&message) {
            Some(replacement) => format!("{message}; {replacement}"),
            None => message,
        })
    }
}

/// The JSON configuration `text` without its `"region": null`, which every file the release
/// before the one engine printed for a contour tracker holds (TOML has no null, so its files
/// leave the field out); `None` when `text` has no null `region`. A `region` that is not null
/// stays refused, naming what replaced it ([`replaced_field`]).
fn without_null_region(text: &str) -> Option<serde_json::Value> {
    let mut value: serde_json::Value = serde_json::from_str(text).ok()?;
    let fields = value.as_object_mut()?;
    fields
        .get("region")
        .is_some_and(serde_json::Value::is_null)
        .then(|| fields.remove("region"))?;
    Some(value)
}

/// What replaced a field of an earlier configuration file that an error names as unknown.
fn replaced_field(message: &str) -> Option<&'static str> {
    message.contains("unknown field `region`").then_some(
        "`region` held the settings of the region tracker behind the old `head`, which is now \
         a composition of the one particle engine: its colour, template and contour terms are \
         `appearance`, its tempering `filter.min_ess_fraction`, its working scale \
         `working_radius` (write a new file with `track config head`)",
    )
}
