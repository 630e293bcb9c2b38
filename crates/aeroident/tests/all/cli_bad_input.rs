//! Exit codes of every subcommand on bad input, end to end through the binary (a script
//! calling it judges by the exit code alone, so each must be the documented one), and the one
//! scenario format's `kind` errors.
//!
//! The contract (`src/main.rs`): 0 on success (and on a closed output pipe), 1 on an error of
//! the input or the run with one `error: …` line naming the file/row/key and the cause, 2 on a
//! command-line usage error (clap). Never a panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroident"))
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(p)
}

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aeroident-bad-input-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs the binary and checks the exit code, that it did not panic, and (for code 1) that the
/// one error line contains every `needle`; returns stderr.
fn expect(args: &[&str], code: i32, needles: &[&str]) -> String {
    let o: Output = bin().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    if code == 1 {
        let line = err.lines().find(|l| l.starts_with("error: ")).unwrap_or_else(|| {
            panic!("{args:?}: no `error:` line in {err}");
        });
        for n in needles {
            assert!(line.contains(n), "{args:?}: `{n}` not in: {line}");
        }
    }
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Each command given another command's scenario names the kind expected and the kind found
/// (not "unknown field `aircraft`"), and the command that runs it; exit 1, nothing written.
#[test]
fn errors_wrong_scenario_kind_names_expected_and_found() {
    let d = scratch("kind");
    let sim = repo("scenarios/sim/elevator_doublet.toml");
    let poc = repo("scenarios/poc/t4_1_case1.toml");
    let run = repo("scenarios/f16/t4_7_case1.toml");
    let out = d.join("out");
    let cases: [(Vec<&str>, &Path, &str, &str, &str); 4] = [
        (vec!["run"], &sim, "run", "sim", "aeroident f16 sim"),
        (vec!["poc", "--out", s(&out)], &run, "poc", "run", "aeroident run"),
        (vec!["f16", "sim", "--out", s(&out)], &poc, "sim", "poc", "aeroident poc"),
        (vec!["montecarlo", "--runs", "2", "--json"], &poc, "run", "poc", "aeroident poc"),
    ];
    for (cmd, file, expected, found, how) in cases {
        let mut args = cmd.clone();
        args.push(s(file));
        let err = expect(
            &args,
            1,
            &[
                s(file),
                &format!("expected kind \"{expected}\", found kind \"{found}\""),
                how,
                "line ",
            ],
        );
        assert!(!err.contains("unknown field"), "{err}");
    }
    assert!(!out.join("timeseries.csv").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// A scenario without `kind` is refused with the kind to write; an unknown kind is quoted.
#[test]
fn errors_missing_or_unknown_kind() {
    let d = scratch("nokind");
    let text = std::fs::read_to_string(repo("scenarios/sim/elevator_doublet.toml")).unwrap();
    let nokind = d.join("nokind.toml");
    std::fs::write(&nokind, text.replace("kind = \"sim\"\n", "")).unwrap();
    expect(
        &["f16", "sim", s(&nokind), "--out", s(&d.join("o"))],
        1,
        &[s(&nokind), "missing top-level `kind`", "kind = \"sim\""],
    );
    // Given to `run`, the missing kind comes with a guess of the format.
    expect(&["run", s(&nokind)], 1, &["missing top-level `kind`", "looks like a `sim` scenario"]);
    let odd = d.join("odd.toml");
    std::fs::write(&odd, text.replace("kind = \"sim\"", "kind = \"simulation\"")).unwrap();
    expect(
        &["f16", "sim", s(&odd), "--out", s(&d.join("o"))],
        1,
        &[s(&odd), "`kind = \"simulation\"` is not a scenario kind"],
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// `--all` over a directory holding a scenario of another kind names that file and both kinds
/// before running anything.
#[test]
fn errors_all_with_a_foreign_scenario_names_the_file() {
    let d = scratch("all");
    let sc = d.join("sc");
    std::fs::create_dir_all(&sc).unwrap();
    std::fs::copy(repo("scenarios/poc/t4_1_case1.toml"), sc.join("a.toml")).unwrap();
    std::fs::copy(repo("scenarios/sim/elevator_doublet.toml"), sc.join("b.toml")).unwrap();
    let out = d.join("out");
    expect(
        &["poc", "--all", s(&sc), "--out", s(&out)],
        1,
        &["b.toml", "expected kind \"poc\", found kind \"sim\""],
    );
    expect(
        &["run", "--no-figures", "--all", s(&sc), "--out", s(&out)],
        1,
        &["a.toml", "expected kind \"run\", found kind \"poc\""],
    );
    assert!(!out.join("t4_1_case1").exists(), "ran despite the foreign scenario");
    let _ = std::fs::remove_dir_all(&d);
}

/// Missing files, per subcommand: exit 1 naming the file.
#[test]
fn errors_missing_files_exit_1_naming_the_file() {
    let d = scratch("missing");
    let nope = d.join("nope.toml");
    let out = d.join("out");
    expect(&["run", s(&nope)], 1, &["nope.toml"]);
    expect(&["run", "--all", s(&d.join("nodir"))], 1, &["nodir"]);
    expect(&["poc", s(&nope), "--out", s(&out)], 1, &["nope.toml"]);
    expect(&["f16", "sim", s(&nope), "--out", s(&out)], 1, &["nope.toml"]);
    expect(&["montecarlo", s(&nope), "--runs", "2"], 1, &["nope.toml"]);
    let map = repo("mappings/hfb320.toml");
    expect(
        &["replay", s(&d.join("nope.csv")), "--map", s(&map), "--out", s(&out)],
        1,
        &["nope.csv"],
    );
    expect(&["replay", "-", "--map", s(&nope)], 1, &["nope.toml"]);
    let _ = std::fs::remove_dir_all(&d);
}

/// A mapping channel with `scale = 0` would make every parameter
/// fed by it unidentifiable and printed as if estimated; the replay refuses the mapping,
/// naming file, line and key, before reading data (exit 1, no outputs).
#[test]
fn errors_zero_scale_channel_is_a_mapping_error() {
    let d = scratch("scale0");
    let io = repo("crates/io/tests/data");
    let text = std::fs::read_to_string(io.join("min.toml")).unwrap();
    let line = text.lines().position(|l| l.starts_with("q = ")).unwrap() + 1;
    let map = d.join("scale0.toml");
    std::fs::write(
        &map,
        text.replace(
            "q = { column = \"q\", unit = \"deg/s\" }",
            "q = { column = \"q\", unit = \"deg/s\", scale = 0.0 }",
        ),
    )
    .unwrap();
    let out = d.join("out");
    expect(
        &["replay", s(&io.join("good.csv")), "--map", s(&map), "--out", s(&out)],
        1,
        &[s(&map), &format!("line {line}"), "channel `q`", "scale must be non-zero"],
    );
    assert!(!out.join("summary.json").exists());
    // The same mapping with the scale restored replays (the corpus is otherwise valid).
    let ok = bin()
        .args(["replay", s(&io.join("good.csv")), "--map", s(&io.join("min.toml")), "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    let _ = std::fs::remove_dir_all(&d);
}

/// Bad values of options: exit 1 naming the option (checked by the command) or 2 (clap).
#[test]
fn errors_bad_options_per_subcommand() {
    let d = scratch("opts");
    let out = d.join("out");
    let io = repo("crates/io/tests/data");
    let (good, min) = (io.join("good.csv"), io.join("min.toml"));
    expect(
        &["replay", s(&good), "--map", s(&min), "--out", s(&out), "--diff-window", "4"],
        1,
        &["diff-window"],
    );
    expect(&["replay", s(&good), "--map", s(&min)], 1, &["--out"]);
    // A forgetting factor means nothing to the EKF or the batch fits: refused, not ignored.
    for est in ["ekf", "oe", "fem"] {
        let args = ["replay", s(&good), "--map", s(&min), "--out", s(&out), "--estimator", est];
        let mut args = args.to_vec();
        args.extend(["--forgetting", "0.99"]);
        expect(&args, 1, &["--forgetting", &format!("--estimator {est}, which takes"), "ignored"]);
    }
    expect(&["replay", s(&good), "--map", s(&min), "--estimator", "kalman"], 2, &[]);
    expect(&["montecarlo", "--runs", "0"], 1, &["runs"]);
    expect(&["f16", "trim", "--alt-ft", "20000", "--vt-fps", "675", "--xcg", "0.9"], 1, &["xcg"]);
    expect(&["f16", "xdot", "--state", "1,2,3", "--controls", "0,0,0,0"], 1, &["--state"]);
    expect(&["f16", "linearize", "--alt-ft", "abc"], 2, &[]);
    expect(&["bench", "--bogus"], 2, &[]);
    expect(&["poc", "--all", s(&d.join("empty")), "--out", s(&out)], 1, &["empty"]);
    expect(&["nosuchcommand"], 2, &[]);
    let _ = std::fs::remove_dir_all(&d);
}

/// A negative number is an option's value, not a flag: `--xcg -0.5` reaches the range check
/// as `--xcg=-0.5` does (clap said "unexpected argument '-0'"), and a negative in range is
/// accepted.
#[test]
fn exit_negative_numbers_are_option_values() {
    let trim = ["f16", "trim", "--alt-ft", "10000", "--vt-fps", "500"];
    for xcg in [&["--xcg", "-0.5"][..], &["--xcg=-0.5"][..]] {
        let args: Vec<&str> = trim.iter().chain(xcg).copied().collect();
        let err = expect(&args, 1, &["xcg", "-0.5", "cg range"]);
        assert!(!err.contains("unexpected argument"), "{err}");
    }
    let args: Vec<&str> =
        trim.iter().chain(&["--gamma-deg", "-2", "--xcg", "0.3"]).copied().collect();
    expect(&args, 0, &[]);
}

/// Every subcommand, at every depth, takes negative numbers as values (one definition for the
/// whole command line, so a new subcommand cannot forget it).
#[test]
fn exit_every_subcommand_allows_negative_numbers() {
    fn check(cmd: &clap::Command, path: &str) {
        assert!(cmd.is_allow_negative_numbers_set(), "`{path}` reads -1 as a flag");
        for sub in cmd.get_subcommands() {
            check(sub, &format!("{path} {}", sub.get_name()));
        }
    }
    let def = aeroident::cli::Cli::definition();
    assert!(def.get_subcommands().count() >= 9);
    check(&def, "aeroident");
    let cli = aeroident::cli::Cli::try_parse_args([
        "aeroident",
        "f16",
        "trim",
        "--alt-ft",
        "-100",
        "--vt-fps",
        "500",
    ]);
    assert!(cli.is_ok(), "{cli:?}");
}

/// `export jsbsim` with a property name JSBSim would not accept (XML markup in it) exits 1
/// naming it, and writes nothing (it wrote malformed XML with exit 0).
#[test]
fn exit_export_refuses_property_names_that_are_not_jsbsims() {
    let d = scratch("export-prop");
    let summary = d.join("summary.json");
    std::fs::write(
        &summary,
        r#"{"estimator":"rls","model":"m","parameters":[{"name":"Cm_de","estimate":-1.2,"std_error":0.1}]}"#,
    )
    .unwrap();
    let out = d.join("aero.xml");
    let (s, o) = (summary.to_str().unwrap(), out.to_str().unwrap());
    let args = ["export", "jsbsim", "--summary", s, "--out", o, "--elevator-property", "fcs/a&b<c"];
    expect(&args, 1, &["elevator property", "fcs/a&b<c", "not a JSBSim property name"]);
    assert!(!out.exists());
    expect(&["export", "jsbsim", "--summary", s, "--out", o], 0, &[]);
    assert!(
        std::fs::read_to_string(&out)
            .unwrap()
            .contains("<property>fcs/elevator-pos-rad</property>")
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// `design` refuses what it cannot sample, allocate or trim, naming the option, before any
/// work (these aborted allocating or said "trim did not converge: no start evaluated").
#[test]
fn exit_design_refuses_out_of_range_options() {
    expect(&["design", "--band-hz", "0.1", "100"], 1, &["--band-hz", "Nyquist frequency 25 Hz"]);
    expect(&["design", "--rate-hz", "1e9"], 1, &["--rate-hz", "samples"]);
    expect(&["design", "--duration-s", "1e9"], 1, &["--duration-s", "samples"]);
    expect(&["design", "--alt-ft", "1e6"], 1, &["--alt-ft", "1000000", "altitudes"]);
}

/// `design --throw-deg` refuses a design that moves a surface beyond its throw, naming the
/// surface and the option; a malformed throw and `--arm-rc` without throws are refused too.
#[test]
fn exit_design_refuses_a_design_beyond_a_surface_throw() {
    let args = ["design", "--surfaces", "da", "--duration-s", "4", "--throw-deg", "da=1.5"];
    expect(&args, 1, &["--throw-deg da=1.5", "`da`", "beyond its throw"]);
    expect(&["design", "--throw-deg", "dx=3"], 2, &[]);
    expect(&["design", "--throw-deg", "de"], 2, &[]);
    expect(
        &["design", "--surfaces", "de", "--duration-s", "4", "--arm-rc", "7"],
        1,
        &["--arm-rc", "--throw-deg"],
    );
}

/// A window starting before the record's time zero (`--window -10:5`) is a window, for every
/// command that takes one; it once failed with "unexpected argument '-1'" (a negative number
/// is a value, but `-10:5` is not a number).
#[test]
fn exit_a_window_with_a_negative_start_is_a_value() {
    use aeroident::cli::{Cli, Command};
    let window = |cmd: &[&str]| {
        let args: Vec<&str> = ["aeroident"]
            .iter()
            .chain(cmd)
            .chain(&["--window", "-10:5", "--window", "-2.5:-1"])
            .copied()
            .collect();
        Cli::try_parse_args(args).unwrap_or_else(|e| panic!("{cmd:?}: {e}")).command
    };
    use aeroident::cli::auto_window::WindowSpec;
    let spans = |specs: &[WindowSpec]| -> Vec<(f64, f64)> {
        specs
            .iter()
            .map(|s| match s {
                WindowSpec::Span(w) => (w.start_s, w.end_s),
                WindowSpec::Auto | WindowSpec::AutoBest(_) => panic!("{specs:?}"),
            })
            .collect()
    };
    match window(&["replay", "r.csv", "--map", "m.toml"]) {
        Command::Replay(a) => assert_eq!(spans(&a.window_specs), [(-10.0, 5.0), (-2.5, -1.0)]),
        c => panic!("{c:?}"),
    }
    match window(&["compat", "r.csv", "--map", "m.toml"]) {
        Command::Compat(a) => assert_eq!(spans(&a.windows), [(-10.0, 5.0), (-2.5, -1.0)]),
        c => panic!("{c:?}"),
    }
    match window(&["freqresp", "r.csv", "--map", "m.toml", "--input", "de", "--output", "q"]) {
        Command::Freqresp(a) => assert_eq!(a.windows.len(), 2),
        c => panic!("{c:?}"),
    }
}

/// Two settings of one thing are refused by name before any work, not resolved silently:
/// `design` with a surface twice in `--throw-deg`, or with a model-file aircraft's options
/// beside the default F-16 (it designed for the F-16 at its own condition); `compat` with the
/// AHRS lag and the gyros' own shifts (the shifts were dropped); `live` with `--speed` and
/// `--realtime` (paced at 1×). A throw beyond a right angle is a form error.
#[test]
fn exit_two_settings_of_one_thing_are_refused() {
    expect(&["design", "--throw-deg", "de=25,da=20,de=30"], 1, &["--throw-deg gives de twice"]);
    expect(&["design", "--vt-mps", "55", "--alt-m", "1200"], 1, &["--vt-mps, --alt-m", "F-16"]);
    let err = expect(&["design", "--throw-deg", "de=1e9"], 2, &[]);
    assert!(err.contains("at most 90°"), "{err}");
    let (good, min) =
        (repo("crates/io/tests/data/good.csv"), repo("crates/io/tests/data/min.toml"));
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let (good, min) = (s(&good), s(&min));
    expect(
        &["compat", &good, "--map", &min, "--ahrs-lag", "--gyro-time-shifts"],
        1,
        &["--ahrs-lag", "--gyro-time-shifts", "give one"],
    );
    let d = scratch("live-speed");
    let out = s(&d.join("out"));
    expect(
        &["live", &good, "--map", &min, "--out", &out, "--speed", "100", "--realtime"],
        1,
        &["--speed 100", "--realtime", "give one"],
    );
    assert!(!d.join("out").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// Finite but absurd options are refused with their physical bound, the number in short form
/// (a 1e300 was printed in 301 digits, when it was refused at all): a reference speed, area,
/// throws and stall angles of the exports, the live view's σ fraction, and the design's
/// flight condition, cg and amplitude.
#[test]
fn exit_absurd_finite_options_are_bounded() {
    let d = scratch("absurd");
    let summary = d.join("summary.json");
    std::fs::write(
        &summary,
        r#"{"estimator":"oe","model":"m","status":"converged","parameters":[{"name":"Cm_de","estimate":-1.2,"std_error":0.1}]}"#,
    )
    .unwrap();
    let s = summary.to_str().unwrap();
    let geometry = ["--area-m2", "0.5", "--span-m", "2", "--chord-m", "0.25"];
    let inertia = ["--mass-kg", "3", "--ixx-kgm2", "0.2", "--iyy-kgm2", "0.3", "--izz-kgm2", "0.4"];
    let mass = [&geometry[..], &inertia].concat();
    let export = |target: &str, extra: &[&str], needles: &[&str]| {
        let mut args = vec!["export", target, "--summary", s];
        let needed: &[&str] = match target {
            "jsbsim" => &[],
            "ardupilot" => &mass,
            _ => &geometry,
        };
        // The geometry (and mass), less any option the case gives itself (clap refuses it
        // twice).
        let kept = needed.chunks(2).filter(|pair| !extra.contains(&pair[0]));
        args.extend(kept.flatten());
        args.extend(extra);
        let err = expect(&args, 1, needles);
        let line = err.lines().find(|l| l.starts_with("error: ")).unwrap();
        assert!(line.len() < 200, "{line}");
    };
    export("jsbsim", &["--v0-mps", "1e300"], &["--v0-mps", "at most 1000 m/s", "got 1.000e300"]);
    export(
        "ardupilot",
        &["--area-m2", "1e300"],
        &["reference area S", "at most 2000 m²", "got 1.000e300"],
    );
    export("ardupilot", &["--aileron-throw-deg", "1e9"], &["--aileron-throw-deg", "at most 90°"]);
    export("ardupilot", &["--mass-kg", "1e300"], &["aircraft mass", "at most 1.000e6 kg"]);
    export("ardupilot", &["--ixz-kgm2", "0.5"], &["aircraft inertia", "jxz"]);
    export("gazebo", &["--alpha-stall-deg", "1000"], &["--alpha-stall-deg", "got 1000"]);
    export("gazebo", &["--air-density", "1e300"], &["air density", "at most 2 kg/m³"]);
    let (good, min) =
        (repo("crates/io/tests/data/good.csv"), repo("crates/io/tests/data/min.toml"));
    let out = d.join("out");
    let live = |extra: &[&str], needles: &[&str]| {
        let mut args =
            vec!["live", good.to_str().unwrap(), "--map", min.to_str().unwrap(), "--out"];
        args.push(out.to_str().unwrap());
        args.extend(extra);
        expect(&args, 1, needles);
    };
    live(&["--sigma-fraction", "inf"], &["--sigma-fraction", "at most 1", "got inf"]);
    live(&["--sigma-fraction", "1.5"], &["--sigma-fraction"]);
    live(&["--hold-s", "inf"], &["--hold-s"]);
    // The F-16 design's condition and the model's own errors, short (each was 301 digits).
    for (args, needles) in [
        (["design", "--alt-ft", "1e300"], &["--alt-ft 1.000e300"][..]),
        (["design", "--vt-fps", "1e300"], &["--vt-fps 1.000e300", "at most 2600 ft/s"][..]),
        (["design", "--xcg", "1e300"], &["`xcg` = 1.000e300"][..]),
        (["design", "--amplitude-deg", "1e300"], &["implausible input `de_rad` = 2.738e282"][..]),
    ] {
        let err = expect(&args, 1, needles);
        let line = err.lines().find(|l| l.starts_with("error: ")).unwrap();
        assert!(line.len() < 200, "{line}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
