//! `report.html` of a replay opened in headless Chromium: it renders (a screenshot of the page
//! is written) and logs no console message; the DOM holds the results table with the known
//! derivatives of a synthetic record, the fit quality and the inlined figures. The top-level
//! `report.html` of `run --all` is checked the same way: it renders, links every scenario's
//! own report (which exists) and holds each scenario's table against the truth.
//!
//! Needs the `chromium` binary (Debian package `chromium`; `.ci/run` installs it). Without it
//! the test is skipped with a message — and fails when `CI=true`.

use crate::common;

use common::browser::{chromium, console_lines, headless, page_url};
use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroident"))
}

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aeroident-report-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const MAP: &str = r#"nominal_dt_s = 0.02
[time]
column = "t"
unit = "s"
[channels]
vt = { column = "V", unit = "m/s" }
alpha = { column = "alpha", unit = "rad" }
q = { column = "q", unit = "rad/s" }
qdot = { column = "qdot", unit = "rad/s2" }
ax = { column = "ax", unit = "m/s2" }
az = { column = "az", unit = "m/s2" }
de = { column = "de", unit = "rad" }
thrust = { value = 0.0, unit = "N" }
rho = { value = 1.0, unit = "kg/m3" }
mass = { value = 1000.0, unit = "kg" }
S = { value = 10.0, unit = "m2" }
cbar = { value = 2.0, unit = "m" }
Iyy = { value = 4000.0, unit = "kg*m2" }
"#;

/// The longitudinal preset's derivatives the record is generated from (CL, CD, Cm × 0, α, q̂,
/// δe).
const TRUTH: [(&str, f64); 12] = [
    ("CL_0", 0.2),
    ("CL_alpha", 4.5),
    ("CL_q", 6.0),
    ("CL_de", 0.4),
    ("CD_0", 0.03),
    ("CD_alpha", 0.25),
    ("CD_q", 0.5),
    ("CD_de", 0.02),
    ("Cm_0", 0.02),
    ("Cm_alpha", -0.8),
    ("Cm_q", -12.0),
    ("Cm_de", -1.2),
];

/// A noise-free record of the model above: independent multisines in α, q, δe; the measured
/// accelerations and q̇ follow from the coefficients exactly.
fn record() -> String {
    let (m, s, cbar, iyy, rho, v) = (1000.0, 10.0, 2.0, 4000.0, 1.0, 50.0);
    let qbar = 0.5 * rho * v * v;
    let c = |name: &str| TRUTH.iter().find(|(n, _)| *n == name).unwrap().1;
    let mut csv = String::from("t,V,alpha,q,qdot,ax,az,de\n");
    for k in 0..1500 {
        let t = k as f64 * 0.02;
        let alpha = 0.06 + 0.03 * (0.9 * t).sin() + 0.01 * (3.1 * t).cos();
        let q = 0.08 * (1.7 * t + 0.3).sin() + 0.02 * (4.3 * t).sin();
        let de = -0.02 + 0.03 * (2.3 * t + 1.0).sin() + 0.01 * (5.9 * t).cos();
        let qhat = q * cbar / (2.0 * v);
        let coef = |p: &str| {
            c(&format!("{p}_0"))
                + c(&format!("{p}_alpha")) * alpha
                + c(&format!("{p}_q")) * qhat
                + c(&format!("{p}_de")) * de
        };
        let (cl, cd, cm) = (coef("CL"), coef("CD"), coef("Cm"));
        let (sa, ca) = alpha.sin_cos();
        let cx = -cd * ca + cl * sa;
        let cz = -cl * ca - cd * sa;
        let (ax, az) = (cx * qbar * s / m, cz * qbar * s / m);
        let qdot = cm * qbar * s * cbar / iyy;
        csv.push_str(&format!("{t},{v},{alpha},{q},{qdot},{ax},{az},{de}\n"));
    }
    csv
}

#[test]
fn report_html_renders_in_headless_chromium_without_console_errors() {
    let Some(chrome) = chromium() else {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but no chromium on PATH: .ci/run must install the Debian package `chromium`"
        );
        eprintln!(
            "SKIPPED report_html: no chromium on PATH (install the Debian package `chromium`)"
        );
        return;
    };
    let dir = scratch("replay");
    std::fs::write(dir.join("map.toml"), MAP).unwrap();
    std::fs::write(dir.join("rec.csv"), record()).unwrap();
    let out = dir.join("out");
    let o = bin()
        .arg("replay")
        .arg(dir.join("rec.csv"))
        .arg("--map")
        .arg(dir.join("map.toml"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The console table lists every parameter with its estimate.
    for (name, _) in TRUTH {
        assert!(stdout.contains(name), "{name} missing from the console table:\n{stdout}");
    }
    for f in ["report.html", "estimates.png", "estimates.svg", "fit.png", "fit.svg"] {
        assert!(out.join(f).is_file(), "{f} not written");
    }
    let page = out.join("report.html");

    // 1. Screenshot, with Chromium's log on stderr: no console message.
    let shot = dir.join("screenshot.png");
    let (ok, _, err) = headless(
        &chrome,
        &page_url(&page),
        &dir.join("profile1"),
        &[&format!("--screenshot={}", shot.display()), "--window-size=1280,1800"],
    );
    assert!(ok, "chromium failed: {err}");
    assert!(console_lines(&err).is_empty(), "console messages: {:?}", console_lines(&err));
    let png = std::fs::read(&shot).expect("no screenshot written");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let (w, h) = (
        u32::from_be_bytes(png[16..20].try_into().unwrap()),
        u32::from_be_bytes(png[20..24].try_into().unwrap()),
    );
    assert_eq!((w, h), (1280, 1800));
    // A blank page compresses to a few kB; tables and figures do not.
    assert!(png.len() > 50_000, "screenshot only {} bytes: nothing rendered?", png.len());
    eprintln!("report screenshot: {}", shot.display());

    // 2. The rendered DOM: the table's estimates equal the generating derivatives (noise-free
    // record: RLS is exact to rounding), the fit is perfect, the figures are inline SVG.
    let (ok, dom, err) =
        headless(&chrome, &page_url(&page), &dir.join("profile2"), &["--dump-dom"]);
    assert!(ok, "chromium --dump-dom failed: {err}");
    assert!(console_lines(&err).is_empty(), "{:?}", console_lines(&err));
    for (name, value) in TRUTH {
        let row_start =
            dom.find(&format!("<td>{name}</td>")).unwrap_or_else(|| panic!("{name} row"));
        let row = &dom[row_start..row_start + dom[row_start..].find("</tr>").unwrap()];
        let cell = row.split("<td class=\"n\">").nth(1).unwrap();
        let est: f64 = cell.split([' ', '<']).next().unwrap().parse().unwrap();
        assert!((est - value).abs() <= 1e-3 * value.abs().max(1.0), "{name}: {est} vs {value}");
    }
    for coef in ["CL", "CD", "Cm"] {
        let at = dom.find(&format!("<td>{coef}</td>")).unwrap_or_else(|| panic!("fit row {coef}"));
        let row = &dom[at..at + dom[at..].find("</tr>").unwrap()];
        assert!(row.contains(">1.0000<"), "R² of {coef} not 1: {row}");
    }
    assert_eq!(dom.matches("<svg").count(), 2, "estimates and fit figures inline");
    assert!(dom.contains("<td>mapping</td>") && dom.contains("map.toml"));
    assert!(dom.contains("<td>estimator</td>") && dom.contains("<td>structure</td>"));

    // 3. The console check can fail: a page with a script error is caught.
    let bad = dir.join("bad.html");
    std::fs::write(
        &bad,
        "<!DOCTYPE html><html><body><script>undefinedFunction();</script></body></html>",
    )
    .unwrap();
    let (_, _, err) = headless(&chrome, &page_url(&bad), &dir.join("profile3"), &["--dump-dom"]);
    assert!(!console_lines(&err).is_empty(), "a script error must show in the log: {err}");
}

/// `run --all` on two shipped scenarios: the index page renders without console messages,
/// links each scenario's own report (which exists and renders too) and holds each scenario's
/// results table with the truth of its scenario file (Cm_alpha increment of `t4_7_case4`).
#[test]
fn run_all_index_report_renders_and_links_every_scenario() {
    let Some(chrome) = chromium() else {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but no chromium on PATH: .ci/run must install the Debian package `chromium`"
        );
        eprintln!("SKIPPED run --all report: no chromium on PATH");
        return;
    };
    let dir = scratch("runall");
    let scenarios = dir.join("scenarios");
    std::fs::create_dir_all(&scenarios).unwrap();
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/f16");
    for name in ["t4_7_case4", "t4_8_case1"] {
        std::fs::copy(shipped.join(format!("{name}.toml")), scenarios.join(format!("{name}.toml")))
            .unwrap();
    }
    let out = dir.join("out");
    let o = bin()
        .args(["run", "--all"])
        .arg(&scenarios)
        .arg("--out")
        .arg(&out)
        .arg("--no-figures")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = out.join("report.html");
    assert!(page.is_file(), "no top-level report.html");
    let shot = dir.join("screenshot.png");
    let (ok, _, err) = headless(
        &chrome,
        &page_url(&page),
        &dir.join("profile1"),
        &[&format!("--screenshot={}", shot.display()), "--window-size=1280,1400"],
    );
    assert!(ok, "chromium failed: {err}");
    assert!(console_lines(&err).is_empty(), "console messages: {:?}", console_lines(&err));
    assert!(std::fs::metadata(&shot).unwrap().len() > 20_000, "blank screenshot?");
    let (ok, dom, err) =
        headless(&chrome, &page_url(&page), &dir.join("profile2"), &["--dump-dom"]);
    assert!(ok && console_lines(&err).is_empty(), "{err}");
    for name in ["t4_7_case4", "t4_8_case1"] {
        let href = format!("{name}/report.html");
        assert!(dom.contains(&format!("<a href=\"{href}\">")), "no link to {href}");
        assert!(out.join(&href).is_file(), "{href} linked but not written");
        assert!(dom.contains(&format!("<h2>{name} — ")), "no table of {name}");
    }
    // The truth column of t4_7_case4's Cm_alpha row is the scenario file's increment.
    let text = std::fs::read_to_string(scenarios.join("t4_7_case4.toml")).unwrap();
    let table: toml::Table = toml::from_str(&text).unwrap();
    let truth = table["increments"]["Cm_alpha"]["truth"].as_float().unwrap();
    let at = dom.find("<h2>t4_7_case4 — ").unwrap();
    let row_at = at + dom[at..].find("<td>Cm_alpha").expect("Cm_alpha row");
    let row = &dom[row_at..row_at + dom[row_at..].find("</tr>").unwrap()];
    let cell = row.split("<td class=\"n\">").nth(2).unwrap();
    let shown: f64 = cell.split('<').next().unwrap().parse().unwrap();
    assert!((shown - truth).abs() <= 1e-3 * truth.abs(), "truth {shown} vs {truth}");
}
