//! The HTML index of `track eval otb` (`OUT/index.html`): per protocol, each tracker's mean, the
//! success and precision plots over the set inlined, success AUC per sequence, and each
//! sequence's plots. It uses the run report's style and escaping ([`crate::report`]) and, like
//! that report, needs no other file and no network.

use std::fmt::Write as _;

use super::plots::Chart;
use super::{Protocol, SequenceScore, sequence_names};
use crate::report::{STYLE, escape};

/// What one protocol contributes to the page.
#[derive(Debug, Clone)]
pub struct ProtocolSection<'a> {
    /// The protocol.
    pub protocol: Protocol,
    /// Every sequence's row (one per sequence and tracker).
    pub rows: &'a [SequenceScore],
    /// Each tracker's mean over sequences.
    pub means: &'a [SequenceScore],
    /// The charts: the two over the set first, then two per sequence
    /// ([`super::plots::protocol_charts`]).
    pub charts: &'a [Chart],
    /// SRE's ceiling, the success AUC of the truth in each run's start convention
    /// ([`super::in_start_convention`]); `None` under the other protocols.
    pub ceiling: Option<f64>,
}

fn opt(v: Option<f64>, decimals: usize) -> String {
    v.map_or_else(|| "—".to_owned(), |v| format!("{v:.decimals$}"))
}

/// Renders the page; `command` is the command line that produced it.
pub fn render(command: &str, sections: &[ProtocolSection<'_>]) -> String {
    let mut h = String::new();
    let title = "OTB evaluation";
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{title}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{title}</h1>\n<p><code>{}</code></p>\n\
         <p>Success AUC: the area under the success plot (share of scored frames whose box overlaps \
         the truth by more than each threshold 0, 0.05, …, 1). Precision@20: share of scored frames \
         whose centre error is at most 20 px. Scored: the labelled frames after each run's start \
         frame. A sequence's figure is the mean over its runs, the set's the mean over \
         sequences.</p>\n",
        escape(command)
    );
    for s in sections {
        let p = s.protocol;
        let _ = writeln!(
            h,
            "<h2>{}</h2>\n<p>Tables: <a href=\"{1}/otb.md\">{1}/otb.md</a>, <a href=\"{1}/otb.csv\">{1}/otb.csv</a>.</p>",
            p.title(),
            p.name()
        );
        h.push_str(
            "<table>\n<tr><th>tracker</th><th>runs</th><th>success AUC</th><th>precision@20</th><th>frames/s</th><th>P(lost) ROC AUC</th></tr>\n",
        );
        for m in s.means {
            let _ = writeln!(
                h,
                "<tr><th>{}</th><td class=\"v\">{}</td><td class=\"v\">{:.3}</td><td class=\"v\">{:.3}</td><td class=\"v\">{}</td><td class=\"v\">{}</td></tr>",
                escape(&m.tracker),
                m.runs,
                m.metrics.success_auc,
                m.metrics.precision_20,
                opt(m.metrics.fps, 1),
                opt(m.metrics.lost_auc, 3)
            );
        }
        h.push_str("</table>\n");
        if let Some(c) = s.ceiling {
            let _ = writeln!(h, "<p>{}</p>", escape(&super::ceiling_sentence(c)));
        }
        h.push_str("<div class=\"strip\">\n");
        for c in s.charts.iter().take(2) {
            let _ = writeln!(h, "<div class=\"plot\">{}</div>", c.svg);
        }
        h.push_str("</div>\n");
        let seqs = sequence_names(s.rows);
        h.push_str("<h3>Success AUC per sequence</h3>\n<table>\n<tr><th>tracker</th>");
        for seq in &seqs {
            let _ = write!(h, "<th>{}</th>", escape(seq));
        }
        h.push_str("</tr>\n");
        for m in s.means {
            let _ = write!(h, "<tr><th>{}</th>", escape(&m.tracker));
            for seq in &seqs {
                let cell = s
                    .rows
                    .iter()
                    .find(|r| &r.sequence == seq && r.tracker == m.tracker)
                    .map_or_else(
                        || "—".to_owned(),
                        |r| format!("{:.2}", r.metrics.success_auc),
                    );
                let _ = write!(h, "<td class=\"v\">{cell}</td>");
            }
            h.push_str("</tr>\n");
        }
        h.push_str("</table>\n");
        let _ = writeln!(
            h,
            "<details><summary>Plots of each sequence ({})</summary>\n<div class=\"strip\">",
            p.title()
        );
        for c in s.charts.iter().skip(2) {
            let _ = writeln!(h, "<div class=\"plot\">{}</div>", c.svg);
        }
        h.push_str("</div>\n</details>\n");
    }
    h.push_str("</body>\n</html>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::score_run;
    use crate::otb::plots::protocol_charts;
    use crate::otb::set_means;
    use vision_core::BoundingBox;

    #[test]
    fn the_page_escapes_names_and_holds_every_chart() {
        let gt = BoundingBox::new(10.0, 10.0, 20.0, 20.0);
        let m = score_run(&[Some(gt); 4], &[Some(gt); 4], 0, Some(0.5))
            .unwrap()
            .unwrap();
        let rows: Vec<SequenceScore> = ["a<b", "c"]
            .iter()
            .map(|seq| SequenceScore {
                sequence: (*seq).into(),
                tracker: "x&y".into(),
                runs: 1,
                metrics: m.clone(),
            })
            .collect();
        let means = set_means(&rows);
        let charts = protocol_charts(Protocol::Tre, &rows, &means).unwrap();
        assert_eq!(charts.len(), 2 + 2 * 2);
        let section = ProtocolSection {
            protocol: Protocol::Tre,
            rows: &rows,
            means: &means,
            charts: &charts,
            ceiling: None,
        };
        let html = render("track eval otb a<b c", std::slice::from_ref(&section));
        assert!(html.contains("<h2>TRE</h2>"));
        assert!(html.contains("a&lt;b") && html.contains("x&amp;y"));
        assert!(!html.contains("<th>a<b</th>"));
        assert_eq!(html.matches("<svg").count(), charts.len());
        assert!(html.contains("href=\"tre/otb.md\""));
        // SRE's ceiling is said when it is given, and only then.
        assert!(!html.contains("start convention"));
        let sre = ProtocolSection {
            protocol: Protocol::Sre,
            ceiling: Some(0.734),
            ..section
        };
        let html = render("track eval otb", &[sre]);
        assert!(html.contains("scores a success AUC of 0.734"));
    }
}
