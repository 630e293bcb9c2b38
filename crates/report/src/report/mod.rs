//! `report.html`: one self-contained page per run — the run's settings (command, files,
//! mapping, estimator, structure, options, version), the results tables of
//! [`aeroident_pipelines::results`] and the figures inlined as SVG — written through
//! [`OutputDir`] like every other output. No script, no external
//! file, font or style sheet: the page opens offline in any browser.
//!
//! [`replay`] builds the results, figures and report of a `replay`; [`run`] those of the
//! closed-loop `run` experiment.

pub mod batch;
pub mod compat;
pub mod freqresp;
pub mod montecarlo;
pub mod replay;
pub mod run;

use crate::outdir::{OutputDir, OutputError};
use crate::plot::{Panel, PlotError, render_panels_png, render_panels_svg};
use crate::table::{fmt_error_pct, fmt_estimate, fmt_sig, fmt_within};
use aeroident_pipelines::results::Results;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Where a replayed record came from, as its report's settings table names it.
#[derive(Debug, Clone, Copy)]
pub struct Source<'a> {
    /// The record (a path, `-` for stdin, or a `mavlink:` feed).
    pub data: &'a str,
    /// The channel mapping file.
    pub mapping: &'a std::path::Path,
}

/// Standard base64 (RFC 4648, with padding) of `bytes`, for PNG figures inlined as data URIs.
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut o = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                o.push(char::from(A[((n >> (18 - 6 * k)) & 63) as usize]));
            } else {
                o.push('=');
            }
        }
    }
    o
}

/// A PNG as an inline `<img>` (a data URI), usable as a [`Figure`]'s `svg` field: the page
/// stays self-contained.
pub fn png_figure(png: &[u8], alt: &str, caption: &str) -> Figure {
    Figure {
        caption: caption.to_string(),
        svg: format!(
            "<img alt=\"{}\" style=\"max-width:100%\" src=\"data:image/png;base64,{}\">",
            escape(alt),
            base64(png)
        ),
    }
}

/// One figure of the report: its SVG text (from [`crate::plot::render_panels_svg`]) and a
/// caption.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Caption under the figure.
    pub caption: String,
    /// The SVG document (or an inline `<img>` from [`png_figure`]).
    pub svg: String,
}

/// The report's row of the record's sign tests (`None` when there are none): each channel's
/// verdict and its evidence.
pub fn sign_tests_row(tests: &[aeroident_io::replay_output::SignTest]) -> Option<(String, String)> {
    let items: Vec<String> =
        tests.iter().map(|t| format!("{}: {}", t.short(), t.evidence)).collect();
    (!items.is_empty())
        .then(|| ("sign tests (the record's own responses)".into(), items.join("; ")))
}

/// The content of one `report.html`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Report {
    /// Page title and heading.
    pub title: String,
    /// The run's settings as (name, value) rows.
    pub settings: Vec<(String, String)>,
    /// Results tables.
    pub results: Vec<Results>,
    /// Figures, in order.
    pub figures: Vec<Figure>,
    /// Warnings of the run.
    pub warnings: Vec<String>,
    /// Links to the reports of the runs this one summarises: (relative path, text). Relative
    /// links to sibling files only: the page itself stays self-contained.
    pub links: Vec<(String, String)>,
}

/// Renders `panels` (see [`crate::plot`]) to `<stem>.png` and `<stem>.svg` in `od` and returns
/// the SVG as a report [`Figure`] with `caption`.
///
/// # Errors
/// Figure or output errors, naming the file.
pub fn write_figure<E: From<PlotError> + From<OutputError>>(
    od: &mut OutputDir,
    stem: &str,
    title: &str,
    caption: &str,
    panels: &[Panel],
    size_px: (u32, u32),
) -> Result<Figure, E> {
    let (w, ph) = size_px;
    od.write_path(&format!("{stem}.png"), |p| render_panels_png(p, title, panels, w, ph))?;
    let svg = render_panels_svg(&format!("{stem}.svg"), title, panels, w, ph)?;
    od.write_bytes(&format!("{stem}.svg"), svg.as_bytes())?;
    Ok(Figure { caption: caption.to_string(), svg })
}

/// The settings every report carries: the command line as given and the tool's version.
pub fn common_settings() -> Vec<(String, String)> {
    let args: Vec<String> = std::env::args().collect();
    vec![
        ("command".into(), args.join(" ")),
        ("aeroident version".into(), env!("CARGO_PKG_VERSION").into()),
    ]
}

/// The settings row `left out by the reader` (per file: what a multi-rate log reader left
/// out, totals per unit) and one warning per loss ([`aeroident_io::ReaderReport::notes`]);
/// nothing when no reader report was made (a CSV record).
pub fn reader_rows(reports: &[aeroident_io::ReaderReport]) -> (Vec<(String, String)>, Vec<String>) {
    if reports.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let text: Vec<String> = reports
        .iter()
        .map(|r| {
            let (samples, messages, bytes, rows) = r.totals();
            if r.dropped.is_empty() {
                format!("{}: nothing", r.file)
            } else {
                format!(
                    "{}: {samples} samples (timestamps out of order), {messages} cut message(s), {bytes} corrupt bytes skipped, {rows} aligned rows dropped (see warnings)",
                    r.file
                )
            }
        })
        .collect();
    let warnings = reports.iter().flat_map(|r| r.notes()).collect();
    (vec![("left out by the reader".into(), text.join("; "))], warnings)
}

/// `s` with `& < > " '` escaped for HTML text and attribute values.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// The SVG element of `svg` without an XML declaration (it may not appear inside HTML).
fn inline_svg(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |k| &svg[k..])
}

const STYLE: &str = "body{font-family:sans-serif;margin:24px auto;max-width:1200px;color:#222;padding:0 16px}\
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ccc}\
table{border-collapse:collapse;margin:8px 0}th,td{border:1px solid #ccc;padding:3px 9px}\
th{background:#f2f2f2}td.n{text-align:right;font-variant-numeric:tabular-nums}\
td.ok{color:#196b24}td.bad{color:#b00020;font-weight:bold}td.na{color:#777}\
table.settings td:first-child{font-weight:bold;white-space:nowrap}table.settings td{font-family:monospace}\
figure{margin:12px 0}figure svg{max-width:100%;height:auto;border:1px solid #eee}\
figcaption{color:#555;font-size:.9em}li.warn{color:#8a5a00}";

fn results_html(r: &Results, h: &mut String) {
    let _ = writeln!(h, "<h2>{}</h2>", escape(&r.title));
    if !r.rows.is_empty() {
        params_html(r, h);
    }
    fit_html(r, h);
}

fn params_html(r: &Results, h: &mut String) {
    let crb = r.has_crb_std_error();
    let _ = writeln!(
        h,
        "<table class=\"params\"><tr><th>parameter</th><th>estimate ± σ</th>{}<th>{}</th><th>error %</th><th>within ±2σ</th><th>status</th></tr>",
        if crb { "<th>Cramér–Rao σ</th>" } else { "" },
        escape(&r.reference_label)
    );
    for row in &r.rows {
        let class = match row.status.as_str() {
            "identified" => "ok",
            "not identified" => "na",
            _ => "bad",
        };
        let crb_cell = if crb {
            format!("<td class=\"n\">{}</td>", escape(&fmt_sig(row.crb_std_error, 2)))
        } else {
            String::new()
        };
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td class=\"n\">{}</td>{crb_cell}<td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td><td class=\"{class}\">{}</td></tr>",
            escape(&row.name),
            escape(&fmt_estimate(row.estimate, row.std_error)),
            escape(&fmt_sig(row.reference, 4)),
            fmt_error_pct(row.error_pct()),
            fmt_within(row),
            escape(&row.status)
        );
    }
    h.push_str("</table>\n");
    let flags = r.flag_lines(usize::MAX);
    if !flags.is_empty() {
        h.push_str("<p>Flags (why a parameter is not simply identified):</p>\n<ul>\n");
        for f in flags {
            let _ = writeln!(h, "<li class=\"warn\">{}</li>", escape(&f));
        }
        h.push_str("</ul>\n");
    }
    let notes = r.note_lines(usize::MAX);
    if !notes.is_empty() {
        h.push_str("<p>Notes (no doubt about the value; they do not block <em>identified</em>):</p>\n<ul>\n");
        for n in notes {
            let _ = writeln!(h, "<li>{}</li>", escape(&n));
        }
        h.push_str("</ul>\n");
    }
}

fn fit_html(r: &Results, h: &mut String) {
    if !r.fit.is_empty() {
        h.push_str("<p>Fit quality: each measured quantity (a coefficient, or an output of the output-error model) versus the model's prediction from the final estimates.</p>\n");
        h.push_str("<table class=\"fit\"><tr><th>measured</th><th>samples</th><th>residual RMS</th><th>R²</th><th>Theil's U</th></tr>\n");
        for q in &r.fit {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td></tr>",
                escape(&q.coefficient),
                q.samples,
                escape(&fmt_sig(Some(q.residual_rms), 3)),
                q.r_squared.map_or("—".into(), |v| format!("{v:.4}")),
                q.theil_u.map_or("—".into(), |v| format!("{v:.4}"))
            );
        }
        h.push_str("</table>\n");
    }
    for n in &r.notes {
        let _ = writeln!(h, "<p class=\"note\">{}</p>", escape(n));
    }
}

impl Report {
    /// The page (module doc).
    pub fn to_html(&self) -> String {
        let mut h = String::new();
        let _ = write!(
            h,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
             <title>{t}</title><style>{STYLE}</style></head>\n<body>\n<h1>{t}</h1>\n",
            t = escape(&self.title)
        );
        if !self.links.is_empty() {
            h.push_str("<h2>Runs</h2>\n<ul>\n");
            for (href, text) in &self.links {
                let _ = writeln!(h, "<li><a href=\"{}\">{}</a></li>", escape(href), escape(text));
            }
            h.push_str("</ul>\n");
        }
        for r in &self.results {
            results_html(r, &mut h);
        }
        if !self.warnings.is_empty() {
            h.push_str("<h2>Warnings</h2>\n<ul>\n");
            for w in &self.warnings {
                let _ = writeln!(h, "<li class=\"warn\">{}</li>", escape(w));
            }
            h.push_str("</ul>\n");
        }
        h.push_str("<h2>Settings</h2>\n<table class=\"settings\">\n");
        for (k, v) in &self.settings {
            let _ = writeln!(h, "<tr><td>{}</td><td>{}</td></tr>", escape(k), escape(v));
        }
        h.push_str("</table>\n");
        if !self.figures.is_empty() {
            h.push_str("<h2>Figures</h2>\n");
            for f in &self.figures {
                let _ = writeln!(
                    h,
                    "<figure>{}<figcaption>{}</figcaption></figure>",
                    inline_svg(&f.svg),
                    escape(&f.caption)
                );
            }
        }
        h.push_str("</body></html>\n");
        h
    }

    /// Writes `report.html` into `od` (atomically, listed in its manifest).
    ///
    /// # Errors
    /// [`OutputError`] naming the file.
    pub fn write(&self, od: &mut OutputDir) -> Result<PathBuf, OutputError> {
        od.write_bytes("report.html", self.to_html().as_bytes())
    }
}

/// A report's warnings: the summary's texts, then what the log readers said.
pub fn warning_texts(
    warnings: &aeroident_io::warning::Warnings,
    reader_warnings: Vec<String>,
) -> Vec<String> {
    warnings.texts().map(str::to_string).chain(reader_warnings).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_pipelines::results::{FitQuality, ParameterResult};

    #[test]
    fn page_is_self_contained_and_escaped() {
        let r = Report {
            title: "run <x> & y".into(),
            settings: vec![("mapping".into(), "a\"b.toml".into())],
            results: vec![Results {
                title: "params".into(),
                reference_label: "truth".into(),
                rows: vec![ParameterResult::new(
                    "Cm_q",
                    Some(-27.0),
                    Some(0.7),
                    Some(-27.06),
                    None,
                )],
                fit: vec![FitQuality {
                    coefficient: "Cm".into(),
                    samples: 3,
                    residual_rms: 0.1,
                    r_squared: Some(0.9),
                    theil_u: Some(0.1),
                }],
                notes: vec![],
            }],
            figures: vec![Figure {
                caption: "fig".into(),
                svg: "<?xml version=\"1.0\"?><svg xmlns=\"http://www.w3.org/2000/svg\"></svg>"
                    .into(),
            }],
            warnings: vec!["w <1>".into()],
            links: Vec::new(),
        };
        let h = r.to_html();
        assert!(h.starts_with("<!DOCTYPE html>") && h.trim_end().ends_with("</html>"));
        assert!(h.contains("<title>run &lt;x&gt; &amp; y</title>"));
        assert!(h.contains("a&quot;b.toml") && h.contains("w &lt;1&gt;"));
        assert!(h.contains("-27.00 ± 0.70") && h.contains("<td class=\"ok\">identified</td>"));
        assert!(h.contains("<figure><svg xmlns") && !h.contains("<?xml"));
        for external in ["<script", "src=", "href=", "@import", "url("] {
            assert!(!h.contains(external), "{external}");
        }
    }

    /// RFC 4648 test vectors.
    #[test]
    fn base64_rfc4648_vectors() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }
}
