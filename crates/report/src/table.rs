//! Console tables of [`Results`] (`comfy-table`): the parameter table (estimate ± σ, reference
//! or truth, error %, status) and the fit-quality table (residual RMS, R², Theil's U). Pure
//! rendering: the numbers come from [`aeroident_pipelines::results`]. [`fmt_sig`] is the one number format
//! shared with the HTML report.

use aeroident_pipelines::results::Results;
use comfy_table::presets::UTF8_FULL_CONDENSED;
use comfy_table::{CellAlignment, ColumnConstraint, Table, Width};

/// `x` with `sig` significant digits, plain for 1e-3 ≤ |x| < 1e5, else in e-notation; `-0`
/// is written `0`; `—` for `None` or a non-finite value.
pub fn fmt_sig(x: Option<f64>, sig: usize) -> String {
    let Some(x) = x.filter(|x| x.is_finite()) else { return "—".into() };
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        let mag = a.log10().floor() as i32;
        let decimals = (sig as i32 - 1 - mag).max(0) as usize;
        let s = format!("{x:.decimals$}");
        // A value that rounds to zero at this precision must not print as "-0.000".
        if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') { "0".into() } else { s }
    } else {
        format!("{x:.prec$e}", prec = sig.saturating_sub(1))
    }
}

/// An error in % with its sign and one decimal (`+3.2`, `-0.4`); an error that rounds to zero
/// is `0.0` (never `-0.0`); `—` for `None`.
pub fn fmt_error_pct(e: Option<f64>) -> String {
    match e.filter(|e| e.is_finite()) {
        None => "—".into(),
        Some(e) if (e * 10.0).round() == 0.0 => "0.0".into(),
        Some(e) => format!("{e:+.1}"),
    }
}

/// `estimate ± σ` (σ to 2 significant digits, the estimate to the same decimal place where
/// plain), `—` if not identified.
pub fn fmt_estimate(est: Option<f64>, sigma: Option<f64>) -> String {
    match (est, sigma.filter(|s| s.is_finite() && *s > 0.0)) {
        (None, _) => "—".into(),
        (Some(e), None) => fmt_sig(Some(e), 4),
        (Some(e), Some(s)) => format!("{} ± {}", fmt_sig(Some(e), 4), fmt_sig(Some(s), 2)),
    }
}

/// A table with `header`; columns `1..numeric_to` right-aligned (numbers), the rest left.
fn table_with(header: &[&str], numeric_to: usize) -> Table {
    let mut t = Table::new();
    t.load_preset(UTF8_FULL_CONDENSED).set_header(header.to_vec());
    // A fixed layout (no terminal probing): the same text on a terminal, a pipe and in CI.
    t.set_content_arrangement(comfy_table::ContentArrangement::Disabled);
    for i in 1..numeric_to.min(header.len()) {
        if let Some(c) = t.column_mut(i) {
            c.set_cell_alignment(CellAlignment::Right);
        }
    }
    if let Some(c) = t.column_mut(0) {
        c.set_constraint(ColumnConstraint::LowerBoundary(Width::Fixed(10)));
    }
    t
}

/// The reference check's cell: `yes` when ±2σ covers the reference, `no` when it does not,
/// `—` without a reference or a σ (the verdict never reads it: docs/output-schema.md).
pub fn fmt_within(row: &aeroident_io::ParameterResult) -> String {
    match row.reference_check.as_ref().and_then(|c| c.within_2sigma) {
        Some(true) => "yes".into(),
        Some(false) => "no".into(),
        None => "—".into(),
    }
}

/// Most flags the console lists under a table; `summary.json` and `report.html` have all.
pub const CONSOLE_FLAGS: usize = 20;

/// The parameter table and (if any) the fit-quality table of `r`, with the title above and
/// the flags and notes below, as text for the console.
pub fn render(r: &Results) -> String {
    let crb = r.has_crb_std_error();
    let mut header = vec!["parameter", "estimate ± σ"];
    header.extend(crb.then_some("Cramér–Rao σ"));
    header.extend([r.reference_label.as_str(), "error %", "within ±2σ", "status"]);
    let mut t = table_with(&header, header.len() - 1);
    for row in &r.rows {
        let mut cells = vec![row.name.clone(), fmt_estimate(row.estimate, row.std_error)];
        cells.extend(crb.then(|| fmt_sig(row.crb_std_error, 2)));
        cells.extend([
            fmt_sig(row.reference, 4),
            fmt_error_pct(row.error_pct()),
            fmt_within(row),
            row.status.clone(),
        ]);
        t.add_row(cells);
    }
    let mut s = format!("{}\n{t}\n", r.title);
    if !r.fit.is_empty() {
        let mut f = table_with(&["measured", "samples", "residual RMS", "R²", "Theil's U"], 5);
        for q in &r.fit {
            f.add_row(vec![
                q.coefficient.clone(),
                q.samples.to_string(),
                fmt_sig(Some(q.residual_rms), 3),
                q.r_squared.map_or("—".into(), |v| format!("{v:.4}")),
                q.theil_u.map_or("—".into(), |v| format!("{v:.4}")),
            ]);
        }
        s.push_str(&format!("fit quality (measured vs model from the final estimates)\n{f}\n"));
    }
    let flags = r.flag_lines(CONSOLE_FLAGS);
    if !flags.is_empty() {
        s.push_str("flags:\n");
        flags.iter().for_each(|f| s.push_str(&format!("  {f}\n")));
    }
    let notes = r.note_lines(CONSOLE_FLAGS);
    if !notes.is_empty() {
        s.push_str("notes (no doubt about the value):\n");
        notes.iter().for_each(|f| s.push_str(&format!("  {f}\n")));
    }
    for n in &r.notes {
        s.push_str(n);
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_percent_has_a_sign_but_never_minus_zero() {
        assert_eq!(fmt_error_pct(Some(-0.04)), "0.0");
        assert_eq!(fmt_error_pct(Some(-0.0)), "0.0");
        assert_eq!(fmt_error_pct(Some(-0.06)), "-0.1");
        assert_eq!(fmt_error_pct(Some(33.333)), "+33.3");
        assert_eq!(fmt_error_pct(None), "—");
    }
    use aeroident_pipelines::results::{FitQuality, ParameterResult};

    #[test]
    fn numbers_have_no_negative_zero_and_sensible_precision() {
        assert_eq!(fmt_sig(Some(-0.0), 4), "0");
        assert_eq!(fmt_sig(Some(-1.0023), 4), "-1.002");
        assert_eq!(fmt_sig(Some(27.06299), 4), "27.06");
        assert_eq!(fmt_sig(Some(0.0012345), 3), "0.00123");
        assert_eq!(fmt_sig(Some(1.5e-27), 3), "1.50e-27");
        assert_eq!(fmt_sig(Some(123456.0), 3), "1.23e5");
        assert_eq!(fmt_sig(None, 3), "—");
        assert_eq!(fmt_sig(Some(f64::NAN), 3), "—");
        assert_eq!(fmt_estimate(Some(-1.0023), Some(0.0087)), "-1.002 ± 0.0087");
        assert_eq!(fmt_estimate(None, Some(0.1)), "—");
    }

    /// A batch fit's row: the reference check uses its σ (here a coloured σ of 0.1, the
    /// reference 1σ away: within ±2σ), not the Cramér–Rao σ shown beside it (0.01: 10σ away),
    /// and the column appears only when a row has one.
    #[test]
    fn the_status_follows_the_reported_sigma_and_the_bound_stands_beside_it() {
        let row = ParameterResult::new("Cm_alpha", Some(-1.1), Some(0.1), Some(-1.0), None)
            .with_crb_std_error(Some(0.01));
        assert_eq!(row.status, "identified");
        let r = Results {
            title: "rec — oe".into(),
            reference_label: "reference".into(),
            rows: vec![row],
            fit: Vec::new(),
            notes: Vec::new(),
        };
        let s = render(&r);
        assert!(s.contains("Cramér–Rao σ"), "{s}");
        let a = s.lines().find(|l| l.contains("Cm_alpha")).unwrap();
        for want in ["-1.100 ± 0.10", "0.010", " yes ", "identified"] {
            assert!(a.contains(want), "{want} in {a}");
        }
        let plain = Results {
            rows: vec![ParameterResult::new("Cm_alpha", Some(-1.1), Some(0.1), None, None)],
            ..r
        };
        assert!(!render(&plain).contains("Cramér–Rao σ"));
    }

    /// Every row and fit entry appears with its numbers; a missing estimate is `—`, never 0.
    #[test]
    fn table_lists_rows_and_fit() {
        let r = Results {
            title: "rec — rls — longitudinal".into(),
            reference_label: "reference".into(),
            rows: vec![
                ParameterResult::new("Cm_alpha", Some(-1.1), Some(0.01), Some(-1.0), None),
                ParameterResult::new("Cm_q", None, None, None, None),
            ],
            fit: vec![FitQuality {
                coefficient: "Cm".into(),
                samples: 600,
                residual_rms: 0.0123,
                r_squared: Some(0.987),
                theil_u: Some(0.05),
            }],
            notes: vec!["reference: a test".into()],
        };
        let s = render(&r);
        let line = |name: &str| s.lines().find(|l| l.contains(name)).unwrap().to_string();
        let a = line("Cm_alpha");
        // The reference 10σ away is compared beside the verdict: `no`, and `identified`.
        for want in ["-1.100 ± 0.010", "-1.000", "-10.0", " no ", "identified"] {
            assert!(a.contains(want), "{want} in {a}");
        }
        let q = line("Cm_q ");
        assert!(q.contains("not identified") && !q.contains(" 0 "), "{q}");
        let f = line("│ Cm ");
        for want in ["600", "0.0123", "0.9870", "0.0500"] {
            assert!(f.contains(want), "{want} in {f}");
        }
        assert!(s.starts_with("rec — rls") && s.trim_end().ends_with("reference: a test"));
    }
}
