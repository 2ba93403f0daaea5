//! Progress bars on standard error, with rates in one decimal.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle};

/// A progress bar on standard error, hidden when `quiet`: `len` frames, with the rate and the
/// time left.
pub fn progress(len: u64, quiet: bool, what: &str) -> ProgressBar {
    progress_of(len, quiet, what, "frames")
}

/// A progress bar on standard error over `len` things named `unit` (`frames`, `runs`), hidden
/// when `quiet`.
pub fn progress_of(len: u64, quiet: bool, what: &str, unit: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    progress_to(len, what, unit, ProgressDrawTarget::stderr())
}

/// [`progress_of`] drawn on `target`.
pub fn progress_to(len: u64, what: &str, unit: &str, target: ProgressDrawTarget) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(len), target);
    let template = format!("{{msg}} [{{bar:30}}] {{pos}}/{{len}} {unit}, {{rate}}, eta {{eta}}");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        let unit = unit.to_owned();
        let rate = move |state: &ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = w.write_str(&rate_in(state.per_sec(), &unit));
        };
        bar.set_style(style.with_key("rate", rate).progress_chars("=> "));
    }
    bar.set_message(what.to_owned());
    bar
}

/// A rate in frames per second with one decimal (`–` before there is one).
pub fn rate_text(per_sec: f64) -> String {
    rate_in(per_sec, "frames")
}

/// A rate in `unit` per second with one decimal (`–` before there is one).
pub fn rate_in(per_sec: f64, unit: &str) -> String {
    if per_sec.is_finite() && per_sec >= 0.0 {
        format!("{per_sec:.1} {unit}/s")
    } else {
        format!("– {unit}/s")
    }
}

/// A progress spinner for a stream of unknown length, hidden when `quiet`.
pub fn stream_progress(quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new_spinner();
    if let Ok(style) = ProgressStyle::with_template("{msg} {pos} frames, {rate}") {
        bar.set_style(style.with_key("rate", rate_key));
    }
    bar
}

/// The `{rate}` of a progress bar over frames: frames per second with one decimal.
fn rate_key(state: &ProgressState, w: &mut dyn std::fmt::Write) {
    let _ = w.write_str(&rate_text(state.per_sec()));
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    /// A terminal that keeps what is drawn on it.
    #[derive(Debug, Clone, Default)]
    struct Screen(Arc<Mutex<String>>);

    impl indicatif::TermLike for Screen {
        fn width(&self) -> u16 {
            200
        }
        fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn write_line(&self, s: &str) -> std::io::Result<()> {
            self.write_str(&format!("{s}\n"))
        }
        fn write_str(&self, s: &str) -> std::io::Result<()> {
            self.0.lock().unwrap().push_str(s);
            Ok(())
        }
        fn clear_line(&self) -> std::io::Result<()> {
            Ok(())
        }
        fn flush(&self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn the_progress_bar_shows_total_eta_and_a_rate_with_one_decimal() {
        let screen = Screen::default();
        let bar = progress_to(
            40,
            "m1 on clip",
            "frames",
            ProgressDrawTarget::term_like(Box::new(screen.clone())),
        );
        for _ in 0..12 {
            std::thread::sleep(std::time::Duration::from_millis(2));
            bar.inc(1);
        }
        bar.abandon();
        let text = screen.0.lock().unwrap().clone();
        let last = text.lines().rev().find(|l| !l.trim().is_empty()).unwrap();
        assert!(
            last.contains("m1 on clip") && last.contains("12/40 frames"),
            "{last}"
        );
        assert!(last.contains("eta "), "{last}");
        // "NNN.N frames/s": one decimal, never indicatif's four.
        let rate = last.split(", ").find(|p| p.ends_with("frames/s")).unwrap();
        let number = rate.trim_end_matches(" frames/s");
        assert_eq!(number.split('.').nth(1).map(str::len), Some(1), "{last}");
        assert_eq!(rate_text(12.345_67), "12.3 frames/s");
        assert_eq!(rate_text(f64::NAN), "– frames/s");
    }
}
