//! Evaluation on synthetic scenes with exact ground truth: Odobez's Table 1 protocol and the
//! accuracy of Wu's hidden switching processes. Library functions, so that tests and the command
//! line run the same code.

use rayon::prelude::*;
use scene_synth::{FrameTruth, Scenario, ScenarioParams, Scene};
use trackers::{Preset, SmootherSettings, SwitchingStatistics, TrackerConfig};
use vision_core::{BoundingBox, Ellipse, ToGreyBuffer, first_failure};

use crate::record::FrameRecord;
use crate::sequence::{Frame, Original};
use crate::session::{DrawOptions, Session, SessionOutput};
use crate::{AppError, Result};

/// A rendered synthetic sequence: frames as the command line reads them, and their truth.
#[derive(Debug, Clone)]
pub struct SyntheticSequence {
    /// The scenario's name.
    pub name: String,
    /// The frames.
    pub frames: Vec<Frame>,
    /// Ground truth of each frame.
    pub truth: Vec<FrameTruth>,
}

impl SyntheticSequence {
    /// Renders `scenario` with `frames` frames (`None`: the preset's length), scene seed `seed`
    /// and parameter overrides `dotted.path=JSON` (see `ScenarioParams::with_override`).
    ///
    /// # Errors
    /// [`AppError::InvalidSetting`] for parameters the generator rejects.
    pub fn render(
        scenario: Scenario,
        frames: Option<usize>,
        seed: u64,
        overrides: &[String],
    ) -> Result<Self> {
        let mut params = ScenarioParams::preset(scenario);
        if let Some(n) = frames {
            params.frames = n;
        }
        for spec in overrides {
            params = params
                .with_override(spec)
                .map_err(|e| AppError::setting("--set", e.to_string()))?;
        }
        let scene =
            Scene::new(&params, seed).map_err(|e| AppError::setting("--frames", e.to_string()))?;
        let mut out = Self {
            name: scenario.name().to_owned(),
            frames: Vec::with_capacity(scene.len()),
            truth: Vec::with_capacity(scene.len()),
        };
        for k in 0..scene.len() {
            let (img, truth) = scene
                .render_frame(k)
                .map_err(|e| AppError::computation("rendering the scene", e))?;
            out.frames.push(Frame {
                index: k,
                name: format!("{}#{}", out.name, k + 1),
                grey: img.to_grey_buffer(),
                original: Original::Luma(img),
            });
            out.truth.push(truth);
        }
        Ok(out)
    }

    /// The true box of frame `k`.
    pub fn truth_box(&self, k: usize) -> Option<BoundingBox> {
        self.truth.get(k).map(|t| t.bbox)
    }

    /// The true ellipse of the first frame, where trackers start.
    pub fn initial_ellipse(&self) -> Result<Ellipse> {
        let t = self
            .truth
            .first()
            .ok_or_else(|| AppError::setting("--frames", "the scene has no frame"))?;
        Ok(t.ellipse)
    }

    /// Tracks the whole sequence with `config`, starting from the true first ellipse.
    ///
    /// # Errors
    /// An invalid configuration or a tracker failure.
    pub fn track(&self, config: TrackerConfig, draw: Option<DrawOptions>) -> Result<SessionOutput> {
        Ok(self.session(config, draw)?.finish())
    }

    /// A session of `config` that has tracked every frame, not yet finished.
    fn session(&self, config: TrackerConfig, draw: Option<DrawOptions>) -> Result<Session> {
        let init = self.initial_ellipse()?;
        let tracker =
            trackers::build(config).map_err(|e| AppError::setting("tracker", e.to_string()))?;
        let mut session = Session::new(tracker, draw);
        for (k, f) in self.frames.iter().enumerate() {
            session.push(f, &init, self.truth_box(k))?;
        }
        Ok(session)
    }

    /// Tracks the whole sequence with `config` recording its particles, and smooths the run:
    /// the filtered records, the smoothed ones and the run's switching statistics.
    ///
    /// # Errors
    /// An invalid configuration, a tracker failure or a smoother failure.
    pub fn track_and_smooth(
        &self,
        mut config: TrackerConfig,
        smoother: &SmootherSettings,
    ) -> Result<(SessionOutput, Vec<FrameRecord>, SwitchingStatistics)> {
        config.filter.history = Some(Default::default());
        let mut session = self.session(config, None)?;
        let (smoothed, statistics) = session.smoothed(smoother)?;
        Ok((session.finish(), smoothed, statistics))
    }

    /// IoU of each record's box with the true box.
    pub fn ious(&self, records: &[FrameRecord]) -> Vec<f64> {
        records
            .iter()
            .enumerate()
            .map(|(k, r)| self.truth_box(k).map_or(0.0, |t| r.bbox.iou(&t)))
            .collect()
    }
}

/// One column of Odobez's Table 1: dynamics noise (σ_T in pixels, σ_s relative) and particles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Table1Column {
    /// Column name (D1 … D4, S1, S2).
    pub name: &'static str,
    /// σ_T, pixels per frame.
    pub sigma_translation: f64,
    /// σ_s, relative.
    pub sigma_scale: f64,
    /// Number of particles.
    pub particles: usize,
}

/// Odobez Table 1's columns (docs/MODELS.md): D1 (2, 0.01), D2 (3, 0.01), D3 (5, 0.01), D4 (8,
/// 0.02) with 500 particles; S1, S2 = (5, 0.01) with 250 and 100.
pub const TABLE1_COLUMNS: [Table1Column; 6] = [
    Table1Column {
        name: "D1",
        sigma_translation: 2.0,
        sigma_scale: 0.01,
        particles: 500,
    },
    Table1Column {
        name: "D2",
        sigma_translation: 3.0,
        sigma_scale: 0.01,
        particles: 500,
    },
    Table1Column {
        name: "D3",
        sigma_translation: 5.0,
        sigma_scale: 0.01,
        particles: 500,
    },
    Table1Column {
        name: "D4",
        sigma_translation: 8.0,
        sigma_scale: 0.02,
        particles: 500,
    },
    Table1Column {
        name: "S1",
        sigma_translation: 5.0,
        sigma_scale: 0.01,
        particles: 250,
    },
    Table1Column {
        name: "S2",
        sigma_translation: 5.0,
        sigma_scale: 0.01,
        particles: 100,
    },
];

/// The trackers of Table 1.
pub const TABLE1_TRACKERS: [Preset; 4] = [Preset::M1, Preset::M2, Preset::M3, Preset::Full];

/// The configuration of one Table 1 cell for one trial.
pub fn table1_config(preset: Preset, column: &Table1Column, seed: u64) -> TrackerConfig {
    let mut c = preset.config(column.particles, seed);
    c.dynamics.sigma_translation = column.sigma_translation;
    c.dynamics.sigma_scale = column.sigma_scale;
    c
}

/// Success rates of one tracker over the columns.
#[derive(Debug, Clone, PartialEq)]
pub struct Table1Row {
    /// The tracker.
    pub tracker: Preset,
    /// Share of trials that never failed, per column, in [0, 1].
    pub success: Vec<f64>,
    /// Mean frames per second per column.
    pub fps: Vec<f64>,
}

/// Whether one trial failed (docs/MODELS.md: IoU below 0.2 for 5 consecutive frames), and its
/// speed.
///
/// # Errors
/// A tracker failure.
pub fn table1_trial(seq: &SyntheticSequence, config: TrackerConfig) -> Result<(bool, f64)> {
    let out = seq.track(config, None)?;
    let failed = first_failure(&seq.ious(&out.records)).is_some();
    Ok((failed, out.records.len() as f64 / out.seconds.max(1e-9)))
}

/// Runs Odobez's protocol: every tracker, every column, `trials` seeds (1..=trials), in parallel
/// over trials; each trial is deterministic in its seed. `progress` is called after each cell.
///
/// # Errors
/// The first tracker failure.
pub fn table1(
    seq: &SyntheticSequence,
    trackers: &[Preset],
    columns: &[Table1Column],
    trials: usize,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<Table1Row>> {
    trackers
        .iter()
        .map(|&tracker| {
            let mut row = Table1Row {
                tracker,
                success: Vec::new(),
                fps: Vec::new(),
            };
            for column in columns {
                let results: Vec<(bool, f64)> = (1..=trials as u64)
                    .into_par_iter()
                    .map(|seed| table1_trial(seq, table1_config(tracker, column, seed)))
                    .collect::<Result<_>>()?;
                let ok = results.iter().filter(|(failed, _)| !failed).count();
                row.success.push(ok as f64 / trials.max(1) as f64);
                row.fps
                    .push(results.iter().map(|r| r.1).sum::<f64>() / results.len().max(1) as f64);
                progress();
            }
            Ok(row)
        })
        .collect()
}

/// Table 1 as Markdown, success rates in percent.
pub fn table1_markdown(rows: &[Table1Row], columns: &[Table1Column], trials: usize) -> String {
    let mut s = String::from("| Tracker |");
    for c in columns {
        s.push_str(&format!(" {} |", c.name));
    }
    s.push_str("\n|---|");
    s.push_str(&"---|".repeat(columns.len()));
    s.push('\n');
    for r in rows {
        s.push_str(&format!("| {} |", r.tracker.name()));
        for v in &r.success {
            s.push_str(&format!(" {:.0} |", 100.0 * v));
        }
        s.push('\n');
    }
    s.push_str(&format!(
        "\nSuccess rate in % over {trials} trials (seeds 1..={trials}); a trial fails once IoU < 0.2 \
         for 5 consecutive frames. Columns: {}.\n",
        columns
            .iter()
            .map(|c| format!(
                "{} = (σ_T {}, σ_s {}) × {} particles",
                c.name, c.sigma_translation, c.sigma_scale, c.particles
            ))
            .collect::<Vec<_>>()
            .join("; ")
    ));
    s
}

/// Table 1 as CSV: tracker, column, sigma_t, sigma_s, particles, trials, success_rate, fps.
pub fn table1_csv(rows: &[Table1Row], columns: &[Table1Column], trials: usize) -> String {
    let mut s = String::from("tracker,column,sigma_t,sigma_s,particles,trials,success_rate,fps\n");
    for r in rows {
        for ((c, v), fps) in columns.iter().zip(&r.success).zip(&r.fps) {
            s.push_str(&format!(
                "{},{},{},{},{},{},{:.4},{:.2}\n",
                r.tracker.name(),
                c.name,
                c.sigma_translation,
                c.sigma_scale,
                c.particles,
                trials,
                v,
                fps
            ));
        }
    }
    s
}

/// Accuracy of the hidden processes against the generator's ground truth on one scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SwitchingScores {
    /// Scene name.
    pub scene: String,
    /// Tracker name.
    pub tracker: String,
    /// Share of frames with β̂ equal to the true clutter class (`None` without β).
    pub beta_accuracy: Option<f64>,
    /// Mean |γ̂ − (1 − visible fraction)| (`None` without γ).
    pub gamma_mae: Option<f64>,
    /// Share of frames with α̂ equal to the true status (`None` without α).
    pub alpha_accuracy: Option<f64>,
    /// Mean IoU with the true box.
    pub mean_iou: f64,
}

/// Scores the hidden-process estimates of a run against the scene's truth. Frame 0 (the
/// initialisation, where nothing is estimated yet) is left out.
pub fn switching_scores(
    seq: &SyntheticSequence,
    tracker: &str,
    records: &[FrameRecord],
) -> SwitchingScores {
    let pairs: Vec<(&FrameRecord, &FrameTruth)> = records.iter().zip(&seq.truth).skip(1).collect();
    let mean = |v: Vec<f64>| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    let beta = mean(
        pairs
            .iter()
            .filter_map(|(r, t)| {
                r.beta_hat
                    .map(|b| f64::from(u8::from(b + 1 == usize::from(t.clutter_class))))
            })
            .collect(),
    );
    let gamma = mean(
        pairs
            .iter()
            .filter_map(|(r, t)| r.gamma_hat.map(|g| (g - (1.0 - t.visible_fraction)).abs()))
            .collect(),
    );
    let alpha = mean(
        pairs
            .iter()
            .filter_map(|(r, t)| r.alpha_hat.map(|a| f64::from(u8::from(a == t.status))))
            .collect(),
    );
    let ious = seq.ious(records);
    SwitchingScores {
        scene: seq.name.clone(),
        tracker: tracker.to_owned(),
        beta_accuracy: beta,
        gamma_mae: gamma,
        alpha_accuracy: alpha,
        mean_iou: ious.iter().sum::<f64>() / ious.len().max(1) as f64,
    }
}

/// The switching scores as a Markdown table: one row per scene and tracker, in order of first
/// appearance; where several runs (seeds) share a row, each cell is their mean and, in
/// brackets, their range.
pub fn switching_markdown(rows: &[SwitchingScores]) -> String {
    let mut groups: Vec<(&str, &str, Vec<&SwitchingScores>)> = Vec::new();
    for r in rows {
        match groups
            .iter_mut()
            .find(|(scene, tracker, _)| *scene == r.scene && *tracker == r.tracker)
        {
            Some((_, _, g)) => g.push(r),
            None => groups.push((&r.scene, &r.tracker, vec![r])),
        }
    }
    let cell = |values: Vec<f64>, pct: bool| -> String {
        if values.is_empty() {
            return "—".to_owned();
        }
        let k = if pct { 100.0 } else { 1.0 };
        let fmt = |v: f64| {
            if pct {
                format!("{:.1} %", k * v)
            } else {
                format!("{v:.3}")
            }
        };
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        if values.len() == 1 {
            return fmt(mean);
        }
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        format!("{} ({}–{})", fmt(mean), fmt(lo), fmt(hi))
    };
    let mut s = String::from(
        "| Scene | Tracker | runs | β̂ accuracy | γ̂ MAE | α̂ accuracy | mean IoU |\n|---|---|---|---|---|---|---|\n",
    );
    for (scene, tracker, g) in groups {
        let pick = |f: fn(&SwitchingScores) -> Option<f64>| g.iter().filter_map(|r| f(r)).collect();
        s.push_str(&format!(
            "| {scene} | {tracker} | {} | {} | {} | {} | {} |\n",
            g.len(),
            cell(pick(|r| r.beta_accuracy), true),
            cell(pick(|r| r.gamma_mae), false),
            cell(pick(|r| r.alpha_accuracy), true),
            cell(pick(|r| Some(r.mean_iou)), false),
        ));
    }
    s
}

/// The switching scores as CSV.
pub fn switching_csv(rows: &[SwitchingScores]) -> String {
    let cell = |v: Option<f64>| v.map(|v| format!("{v:.4}")).unwrap_or_default();
    let mut s = String::from("scene,tracker,beta_accuracy,gamma_mae,alpha_accuracy,mean_iou\n");
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{},{:.4}\n",
            r.scene,
            r.tracker,
            cell(r.beta_accuracy),
            cell(r.gamma_mae),
            cell(r.alpha_accuracy),
            r.mean_iou
        ));
    }
    s
}
