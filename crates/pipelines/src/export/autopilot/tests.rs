//! The autopilot forms against conversions written here from their sources: the Lua script
//! run under Lua 5.3 (ArduPilot's scripting language) with ArduPilot's API stubbed, so what it
//! commands is seen, and the PX4 table parsed back.

use super::*;
use crate::export::design::{DesignSpec, Waveform, design};
use mlua::{Function, Lua, Table};
use std::sync::OnceLock;

/// Throws of the tests, degrees.
const THROWS_DEG: [(Surface, f64); 3] =
    [(Surface::De, 25.0), (Surface::Da, 20.0), (Surface::Dr, 30.0)];

/// A three-surface F-16 design, 3 s at 25 Hz, 2° (computed once).
fn three_surfaces() -> &'static Design {
    static D: OnceLock<Design> = OnceLock::new();
    D.get_or_init(|| {
        design(&DesignSpec {
            surfaces: vec![Surface::De, Surface::Da, Surface::Dr],
            amplitude_rad: 2f64.to_radians(),
            duration_s: 4.0,
            rate_hz: 25.0,
            band_hz: (0.25, 3.0),
            alt_ft: 20000.0,
            vt_fps: 675.0,
            xcg: 0.3,
            turbulence: None,
            signal: Waveform::Multisine,
        })
        .unwrap()
    })
}

fn options(start: Start) -> AutopilotOptions {
    AutopilotOptions {
        throws: THROWS_DEG.iter().map(|(s, d)| (*s, d.to_radians())).collect(),
        start,
    }
}

/// ArduPilot's API as the script uses it: parameters, RC, the vehicle's scaled outputs and
/// arming state as globals the test sets; every override, log record and message kept.
/// Outputs: 1 aileron, 2 elevator (reversed), 3 throttle, 4 rudder, 5 a second aileron
/// (reversed, other limits).
const STUB: &str = r#"
now = 0
armed = true
rc_pwm = {}
params = {
  SCR_USER1 = 0,
  SERVO1_FUNCTION = 4, SERVO1_MIN = 1000, SERVO1_TRIM = 1500, SERVO1_MAX = 2000, SERVO1_REVERSED = 0,
  SERVO2_FUNCTION = 19, SERVO2_MIN = 1100, SERVO2_TRIM = 1520, SERVO2_MAX = 1900, SERVO2_REVERSED = 1,
  SERVO3_FUNCTION = 70, SERVO3_MIN = 1000, SERVO3_TRIM = 1000, SERVO3_MAX = 2000, SERVO3_REVERSED = 0,
  SERVO4_FUNCTION = 21, SERVO4_MIN = 1050, SERVO4_TRIM = 1480, SERVO4_MAX = 1950, SERVO4_REVERSED = 0,
  SERVO5_FUNCTION = 4, SERVO5_MIN = 1200, SERVO5_TRIM = 1510, SERVO5_MAX = 1800, SERVO5_REVERSED = 1,
}
base = { [4] = 120.0, [19] = -300.0, [21] = 45.0 }
sets, logs, texts, severities = {}, {}, {}, {}
param = {}
-- ArduPilot's param:get returns floats
function param:get(name)
  local v = params[name]
  if v == nil then return nil end
  return v + 0.0
end
rc = {}
function rc:get_pwm(chan) return rc_pwm[chan] end
arming = {}
function arming:is_armed() return armed end
function millis() return { tofloat = function(self) return now end } end
SRV_Channels = {}
function SRV_Channels:get_output_scaled(func) return base[func] end
function SRV_Channels:set_output_pwm_chan_timeout(chan, pwm, timeout)
  assert(math.type(pwm) == 'integer', 'PWM must be an integer')
  sets[#sets + 1] = { chan = chan, pwm = pwm, timeout = timeout }
end
logger = {}
function logger:write(name, labels, format, ...)
  logs[#logs + 1] = { name = name, labels = labels, format = format, values = { ... } }
end
gcs = {}
function gcs:send_text(severity, text)
  texts[#texts + 1] = text
  severities[#severities + 1] = severity
end
"#;

/// Output channels (0-based) of the stub: (servo function, min, trim, max, reversed).
const OUTPUTS: [(u8, u8, f64, f64, f64, bool); 4] = [
    (0, 4, 1000.0, 1500.0, 2000.0, false),
    (1, 19, 1100.0, 1520.0, 1900.0, true),
    (3, 21, 1050.0, 1480.0, 1950.0, false),
    (4, 4, 1200.0, 1510.0, 1800.0, true),
];

/// The stub's scaled output of a servo function.
fn base_of(func: u8) -> f64 {
    match func {
        4 => 120.0,
        19 => -300.0,
        _ => 45.0,
    }
}

/// `SRV_Channel::pwm_from_angle` (libraries/SRV_Channel/SRV_Channel.cpp), range 4500.
fn pwm_from_angle(min: f64, trim: f64, max: f64, reversed: bool, scaled: f64) -> i64 {
    let s = if reversed { -scaled } else { scaled }.clamp(-4500.0, 4500.0);
    if s > 0.0 {
        (trim + (s * (max - trim) / 4500.0).trunc()) as i64
    } else {
        (trim - (-s * (trim - min) / 4500.0).trunc()) as i64
    }
}

/// The script loaded under the stub: its update function.
fn load(lua: &Lua, script: &str) -> Function {
    lua.load(STUB).exec().unwrap();
    let (f, delay): (Function, i64) =
        lua.load(script).set_name("ardupilot_sysid.lua").call(()).unwrap();
    assert_eq!(delay, 100);
    f
}

/// Calls the script once at `now_ms` after clearing the recorded calls; the next function.
fn step(lua: &Lua, f: &Function, now_ms: f64) -> Function {
    step_delay(lua, f, now_ms).0
}

/// As [`step`], with the delay the script asks before its next call, ms.
fn step_delay(lua: &Lua, f: &Function, now_ms: f64) -> (Function, i64) {
    let g = lua.globals();
    g.set("now", now_ms).unwrap();
    for t in ["sets", "logs"] {
        g.set(t, lua.create_table().unwrap()).unwrap();
    }
    f.call(()).unwrap()
}

fn sets(lua: &Lua) -> Vec<(u8, i64, i64)> {
    let t: Table = lua.globals().get("sets").unwrap();
    t.sequence_values::<Table>()
        .map(|r| {
            let r = r.unwrap();
            (r.get("chan").unwrap(), r.get("pwm").unwrap(), r.get("timeout").unwrap())
        })
        .collect()
}

/// The AIDI records of the last call (one per played row).
fn log_values(lua: &Lua) -> Vec<Vec<f64>> {
    records(lua, "AIDI")
}

/// The values of the last call's log records named `name`.
fn records(lua: &Lua, name: &str) -> Vec<Vec<f64>> {
    let t: Table = lua.globals().get("logs").unwrap();
    t.sequence_values::<Table>()
        .map(|r| r.unwrap())
        .filter(|r| r.get::<String>("name").unwrap() == name)
        .map(|r| {
            let v: Table = r.get("values").unwrap();
            v.sequence_values::<f64>().map(|x| x.unwrap()).collect()
        })
        .collect()
}

fn set_param(lua: &Lua, name: &str, v: f64) {
    let p: Table = lua.globals().get("params").unwrap();
    p.set(name, v).unwrap();
}

/// The row due `elapsed_ms` after the start: the last whose time is not later (from the
/// design's own times, not the script's rate arithmetic).
fn due_row(d: &Design, elapsed_ms: f64) -> Option<usize> {
    let last = d.t_s.iter().rposition(|t| t * 1000.0 <= elapsed_ms + 1e-9)?;
    (elapsed_ms < (d.t_s[last] + d.plan.manoeuvres[0].dt_s) * 1000.0 - 1e-9).then_some(last)
}

/// Played under the stub, every call commands on every output of each surface's function the
/// vehicle's scaled output plus `−δ/δmax · 4500` of the row due at that time, as PWM through
/// the output's limits and reversal; the log holds the row, the offset (the injection
/// table's centidegrees) and the scaled command. Checked every 13 ms over the whole record
/// against the design's radians converted here.
#[test]
fn the_lua_script_plays_the_table_scaled_and_signed_on_every_output() {
    let d = three_surfaces();
    let lua = Lua::new();
    let mut f = load(&lua, &ardupilot_lua(d, &options(Start::ScrUser1)).unwrap());
    f = step(&lua, &f, 500.0);
    assert!(sets(&lua).is_empty(), "nothing before the start");
    set_param(&lua, "SCR_USER1", 1.0);
    let t0 = 1000.0;
    let end_ms = d.t_s.len() as f64 * 40.0;
    let mut elapsed = 0.0;
    let mut rows_seen = std::collections::BTreeSet::new();
    while elapsed < end_ms {
        f = step(&lua, &f, t0 + elapsed);
        let k = due_row(d, elapsed).expect("a row is due inside the record");
        rows_seen.insert(k);
        let logs = log_values(&lua);
        assert_eq!(logs.len(), 1, "one log record per call");
        let log = &logs[0];
        assert_eq!((log[0], log[1]), (elapsed.floor(), k as f64), "t {elapsed}");
        let mut expected = Vec::new();
        for (i, (s, u)) in d.inputs.iter().enumerate() {
            let throw = THROWS_DEG.iter().find(|(x, _)| x == s).unwrap().1.to_radians();
            let func = servo_function(*s);
            let scaled = base_of(func) - u[k] / throw * 4500.0;
            assert_eq!(log[2 + 2 * i], (u[k].to_degrees() * 100.0).round(), "{s:?} cdeg");
            // The script scales the table's centidegrees: half a centidegree of rounding.
            let tolerance = 0.005 / throw.to_degrees() * 4500.0 + 1e-9;
            let err = (log[3 + 2 * i] - scaled).abs();
            assert!(err <= tolerance, "{s:?} t {elapsed}: {} vs {scaled}", log[3 + 2 * i]);
            for &(chan, f_, min, trim, max, rev) in &OUTPUTS {
                if f_ == func {
                    expected.push((chan, pwm_from_angle(min, trim, max, rev, scaled)));
                }
            }
        }
        let got = sets(&lua);
        assert_eq!(got.len(), expected.len(), "t {elapsed}: {got:?}");
        for ((chan, pwm, timeout), (e_chan, e_pwm)) in got.iter().zip(&expected) {
            assert_eq!(*chan, *e_chan);
            assert!((pwm - e_pwm).abs() <= 1, "chan {chan} t {elapsed}: {pwm} vs {e_pwm}");
            assert_eq!(*timeout, 120, "three periods of 40 ms");
        }
        elapsed += 13.0;
    }
    assert_eq!(rows_seen.len(), d.t_s.len(), "13 ms steps see every 40 ms row");
    // Past the last row: every output handed back (zero timeout), once; no restart while the
    // switch stays on.
    step(&lua, &f, t0 + end_ms + 1.0);
    let got = sets(&lua);
    assert_eq!(got.len(), OUTPUTS.len());
    assert!(got.iter().all(|(_, _, timeout)| *timeout == 0), "{got:?}");
    assert!(log_values(&lua).is_empty());
    let f = step(&lua, &f, t0 + end_ms + 200.0);
    assert!(sets(&lua).is_empty(), "played once per start");
    let texts: Table = lua.globals().get("texts").unwrap();
    let texts: Vec<String> = texts.sequence_values().map(|t| t.unwrap()).collect();
    assert!(texts.iter().any(|t| t.contains("finished")), "{texts:?}");
    // Called faster than the rows change, each row is counted once.
    assert!(texts.iter().any(|t| t.contains("played 101 of 101 rows at 77.0 Hz")), "{texts:?}");
    assert!(f.call::<(Function, i64)>(()).is_ok());
}

/// Some signs and scalings the comparison above would miss if both sides shared a mistake:
/// a positive elevator offset (trailing edge down) is a negative scaled elevator output, a
/// nose-down command; on the reversed elevator output that is a PWM above trim.
#[test]
fn a_trailing_edge_down_elevator_offset_is_a_nose_down_scaled_command() {
    let d = three_surfaces();
    let (_, u) = &d.inputs[0];
    let k = u.iter().enumerate().fold(0, |b, (i, v)| if *v > u[b] { i } else { b });
    assert!(u[k] > 1f64.to_radians());
    let lua = Lua::new();
    let mut f = load(&lua, &ardupilot_lua(d, &options(Start::ScrUser1)).unwrap());
    f = step(&lua, &f, 0.0);
    set_param(&lua, "SCR_USER1", 1.0);
    f = step(&lua, &f, 10_000.0);
    step(&lua, &f, 10_000.0 + k as f64 * 40.0);
    let log = &log_values(&lua)[0];
    assert_eq!(log[1], k as f64);
    let offset_scaled = log[3] - base_of(19);
    let expected = -u[k].to_degrees() / 25.0 * 4500.0;
    let tolerance = 0.005 / 25.0 * 4500.0;
    assert!(offset_scaled < -100.0 && (offset_scaled - expected).abs() <= tolerance);
    let elevator = sets(&lua).into_iter().find(|s| s.0 == 1).unwrap();
    assert!(elevator.1 > 1520 + 10, "reversed output above trim: {}", elevator.1);
}

/// The start and stop rules: a switch already on at boot starts nothing until it has been off;
/// off mid-record or a disarm hands the outputs back at once; with `--arm-rc` the RC
/// channel's PWM is the switch.
#[test]
fn the_script_starts_only_on_a_fresh_switch_and_stops_on_switch_or_disarm() {
    let d = three_surfaces();
    let lua = Lua::new();
    let mut f = load(&lua, &ardupilot_lua(d, &options(Start::ScrUser1)).unwrap());
    set_param(&lua, "SCR_USER1", 1.0);
    f = step(&lua, &f, 0.0);
    f = step(&lua, &f, 100.0);
    assert!(sets(&lua).is_empty(), "on at boot: nothing");
    set_param(&lua, "SCR_USER1", 0.0);
    f = step(&lua, &f, 200.0);
    set_param(&lua, "SCR_USER1", 1.0);
    f = step(&lua, &f, 300.0);
    assert_eq!(log_values(&lua)[0][1], 0.0, "fresh switch: row 0");
    set_param(&lua, "SCR_USER1", 0.0);
    f = step(&lua, &f, 400.0);
    assert!(sets(&lua).iter().all(|s| s.2 == 0) && sets(&lua).len() == OUTPUTS.len());
    set_param(&lua, "SCR_USER1", 1.0);
    f = step(&lua, &f, 500.0);
    assert_eq!(log_values(&lua)[0][1], 0.0, "a new start plays from row 0");
    lua.globals().set("armed", false).unwrap();
    step(&lua, &f, 600.0);
    assert!(sets(&lua).iter().all(|s| s.2 == 0) && log_values(&lua).is_empty(), "disarmed");

    let lua = Lua::new();
    let mut f = load(&lua, &ardupilot_lua(d, &options(Start::RcChannel(7))).unwrap());
    f = step(&lua, &f, 0.0);
    set_param(&lua, "SCR_USER1", 1.0);
    f = step(&lua, &f, 100.0);
    assert!(sets(&lua).is_empty(), "SCR_USER1 is not the switch with --arm-rc");
    let rc: Table = lua.globals().get("rc_pwm").unwrap();
    rc.set(7, 1900).unwrap();
    step(&lua, &f, 200.0);
    assert_eq!(log_values(&lua)[0][1], 0.0);
}

/// A design beyond a throw is refused naming the surface and `--throw-deg`, the trim
/// deflection of the design's condition counted: a throw above the amplitude but below
/// amplitude + |trim| is refused, one just above the sum accepted. A missing throw, a
/// non-positive one and an RC channel outside 1–16 are refused by name.
#[test]
fn errors_a_design_beyond_a_throw_names_the_surface_and_counts_the_trim() {
    let d = three_surfaces();
    let trim = d.plan.condition.de_rad;
    assert!(trim.abs() > 0.2f64.to_radians(), "the F-16 trims with elevator: {trim}");
    let peak = d.inputs[0].1.iter().fold(0f64, |a, v| a.max((trim + v).abs()));
    let amp = d.inputs[0].1.iter().fold(0f64, |a, v| a.max(v.abs()));
    assert!(peak > amp + 0.1f64.to_radians());
    let with_de = |de_rad: f64| {
        let mut o = options(Start::ScrUser1);
        o.throws[0].1 = de_rad;
        o
    };
    let e = ardupilot_lua(d, &with_de(0.5 * (amp + peak))).unwrap_err().to_string();
    for w in ["--throw-deg de=", "`de`", "trim", "beyond its throw"] {
        assert!(e.contains(w), "{w:?} not in {e}");
    }
    assert!(px4_torque_table(d, &with_de(0.5 * (amp + peak))).is_err());
    assert!(ardupilot_lua(d, &with_de(peak * 1.001)).is_ok());
    let mut no_dr = options(Start::ScrUser1);
    no_dr.throws.retain(|(s, _)| *s != Surface::Dr);
    let cases = [
        (no_dr, vec!["--throw-deg", "`dr`"]),
        (with_de(-0.1), vec!["--throw-deg de=", "positive"]),
        (with_de(f64::NAN), vec!["--throw-deg de="]),
        (with_de(100f64.to_radians()), vec!["--throw-deg de=", "90"]),
        (options(Start::RcChannel(0)), vec!["--arm-rc 0", "1–16"]),
        (options(Start::RcChannel(17)), vec!["--arm-rc 17"]),
    ];
    for (o, words) in cases {
        let e = ardupilot_lua(d, &o).unwrap_err().to_string();
        for w in words {
            assert!(e.contains(w), "{w:?} not in {e}");
        }
    }
}

/// The PX4 table parsed back: times in µs, and roll, pitch, yaw = −δa/δa_max, −δe/δe_max,
/// −δr/δr_max row by row; an axis without a designed surface is 0.
#[test]
fn the_px4_table_is_the_design_as_signed_fractions_of_the_throws() {
    let d = three_surfaces();
    let mut two = d.clone();
    two.inputs.retain(|(s, _)| *s != Surface::Dr);
    for design in [d, &two] {
        let table = px4_torque_table(design, &options(Start::ScrUser1)).unwrap();
        let mut lines = table.lines();
        assert_eq!(lines.next(), Some("t_us,roll,pitch,yaw"));
        let column = |s: Surface| design.inputs.iter().find(|(x, _)| *x == s).map(|(_, u)| u);
        let rows: Vec<Vec<f64>> =
            lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
        assert_eq!(rows.len(), design.t_s.len());
        for (k, r) in rows.iter().enumerate() {
            assert_eq!(r[0], (design.t_s[k] * 1e6).round());
            for (j, (s, throw_deg)) in
                [(Surface::Da, 20.0), (Surface::De, 25.0), (Surface::Dr, 30.0)].iter().enumerate()
            {
                let expected = column(*s).map_or(0.0, |u| -u[k].to_degrees() / throw_deg);
                assert!((r[1 + j] - expected).abs() < 1e-6, "row {k} {s:?}: {}", r[1 + j]);
                assert!(r[1 + j].abs() <= 1.0);
            }
        }
        if design.inputs.len() == 2 {
            assert!(rows.iter().all(|r| r[3] == 0.0), "no rudder designed: yaw 0");
        }
        assert!(!table.contains("-0.000000,") && !table.ends_with("-0.000000\n"));
    }
}

#[test]
fn the_script_header_names_the_design_and_its_log_columns() {
    let d = three_surfaces();
    let lua = ardupilot_lua(d, &options(Start::ScrUser1)).unwrap();
    let rows = d.t_s.len();
    assert_eq!(rows, 101, "0 to 4 s at 25 Hz");
    let header = format!(
        "Design: 101 rows at 25 Hz ({} s), surfaces de, da, dr; full throws de ",
        d.t_s[100]
    );
    assert!(lua.contains(&header), "{lua}");
    assert!(lua.contains("(SIGN -1, servo functions de 19, da 4, dr 21)."), "{lua}");
    assert!(lua.contains("The table was designed at 25 Hz, a row every 40 ms"), "{lua}");
    assert!(lua.contains("local RATE_HZ = 25\n") && lua.contains("local ROWS = 101\n"), "{lua}");
    assert!(lua.contains("local PERIOD_MS = 40\n") && lua.contains("local OVERRIDE_MS = 120\n"));
    let log = "logger:write('AIDI', 'TMs,Row,DeC,DeS,DaC,DaS,DrC,DrS', 'Iiififif', ";
    assert!(lua.contains(log), "{lua}");
    let first = format!("offsets_cdeg = {{ {}", centidegrees(d.inputs[0].1[0]));
    assert!(lua.contains(&first), "{lua}");
    let lines: Vec<&str> = lua
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c == '-' || c.is_ascii_digit()))
        .collect();
    assert!(
        lines.iter().any(|l| l.split(',').filter(|v| !v.trim().is_empty()).count() == 20),
        "{lines:?}"
    );
}

#[test]
fn a_design_reaching_exactly_its_throw_is_accepted() {
    let d = three_surfaces();
    let trim = d.plan.condition.de_rad;
    let peak = d.inputs[0].1.iter().map(|v| (trim + v).abs()).fold(0.0, f64::max);
    let mut o = options(Start::ScrUser1);
    o.throws[0].1 = peak;
    assert!(check_limits(d, &o).is_ok());
    o.throws[0].1 = 90f64.to_radians();
    assert!(check_limits(d, &o).is_ok());
    o.throws[0].1 = 0.0;
    assert!(
        check_limits(d, &o).unwrap_err().to_string().contains("--throw-deg de=0: give a positive")
    );
    o.throws[0].1 = 90.001f64.to_radians();
    assert!(check_limits(d, &o).unwrap_err().to_string().contains("positive throw up to 90°"));
    for c in [1, 16] {
        assert!(check_limits(d, &options(Start::RcChannel(c))).is_ok(), "{c}");
    }
}

/// A 50 Hz design of 3 s (151 rows), elevator and aileron (computed once).
fn fifty_hz() -> &'static Design {
    static D: OnceLock<Design> = OnceLock::new();
    D.get_or_init(|| {
        design(&DesignSpec {
            surfaces: vec![Surface::De, Surface::Da],
            amplitude_rad: 2f64.to_radians(),
            duration_s: 3.0,
            rate_hz: 50.0,
            band_hz: (0.25, 3.0),
            alt_ft: 20000.0,
            vt_fps: 675.0,
            xcg: 0.3,
            turbulence: None,
            signal: Waveform::Multisine,
        })
        .unwrap()
    })
}

/// A record played under the stub's clock: the ms since the start of every call while
/// playing, the rows each played (`None`: none, the finishing call), the texts sent with
/// their severity and the index of the call they came at, and the one AIDR record.
struct Played {
    calls_ms: Vec<f64>,
    rows: Vec<Option<usize>>,
    texts: Vec<(u8, String, usize)>,
    aidr: Vec<f64>,
}

/// The millisecond the script is started at.
const T0_MS: f64 = 1000.0;

/// Plays `d` from `T0_MS` to its end, each call at `next(now_ms, asked_delay_ms)` (ArduPilot's
/// scheduler as the test wants it: honouring the delay, or slower).
fn play_scheduled(d: &Design, mut next: impl FnMut(f64, i64) -> f64) -> Played {
    let lua = Lua::new();
    let mut f = load(&lua, &ardupilot_lua(d, &options(Start::ScrUser1)).unwrap());
    f = step(&lua, &f, 0.0);
    set_param(&lua, "SCR_USER1", 1.0);
    let mut p = Played { calls_ms: vec![], rows: vec![], texts: vec![], aidr: vec![] };
    let mut now = T0_MS;
    while p.aidr.is_empty() {
        assert!(now < T0_MS + 60_000.0, "never finished");
        let (g, delay) = step_delay(&lua, &f, now);
        f = g;
        let call = p.calls_ms.len();
        p.calls_ms.push(now - T0_MS);
        p.rows.push(log_values(&lua).first().map(|l| l[1] as usize));
        p.aidr = records(&lua, "AIDR").pop().unwrap_or_default();
        let texts: Table = lua.globals().get("texts").unwrap();
        let severities: Table = lua.globals().get("severities").unwrap();
        for i in p.texts.len() + 1..=texts.raw_len() {
            p.texts.push((severities.get(i).unwrap(), texts.get(i).unwrap(), call));
        }
        now = next(now, delay);
    }
    p
}

impl Played {
    /// The texts containing `word`.
    fn with(&self, word: &str) -> Vec<&(u8, String, usize)> {
        self.texts.iter().filter(|t| t.1.contains(word)).collect()
    }

    /// The played count and the rate of the end text "played P of N rows at H Hz".
    fn end_text(&self, rows: usize) -> (usize, f64) {
        let t = &self.with("played")[0].1;
        let rest = t.split("played ").nth(1).unwrap();
        let played = rest.split(' ').next().unwrap().parse().unwrap();
        assert!(rest.contains(&format!(" of {rows} rows at ")), "{t}");
        let hz = rest.split(" at ").nth(1).unwrap().trim_end_matches(" Hz").parse().unwrap();
        (played, hz)
    }
}

/// The distinct rows due at the calls (an independent count from the design's times): the
/// rows a player that plays the row due at each call plays.
fn distinct_due_rows(d: &Design, calls_ms: &[f64]) -> std::collections::BTreeSet<usize> {
    calls_ms.iter().filter_map(|t| due_row(d, *t)).collect()
}

/// Called as often as it asks (the 25 Hz and 50 Hz designs, 40 and 20 ms), the script plays
/// every row, sends no warning, and ends with "played N of N rows" at the design rate; its
/// AIDR record says so. Every text fits MAVLink's 50-character STATUSTEXT.
#[test]
fn called_at_the_design_rate_every_row_is_played_and_nothing_is_warned() {
    for (d, rate) in [(three_surfaces(), 25.0), (fifty_hz(), 50.0)] {
        let rows = d.t_s.len();
        let p = play_scheduled(d, |now, delay| now + delay as f64);
        assert_eq!(distinct_due_rows(d, &p.calls_ms).len(), rows);
        let (played, hz) = p.end_text(rows);
        assert_eq!(played, rows, "{:?}", p.texts);
        assert!((hz - rate).abs() < 0.05, "{hz} Hz");
        assert!(p.texts.iter().all(|t| t.0 != 4), "no warning: {:?}", p.texts);
        assert!(p.with("behind").is_empty() && p.with("not the designed").is_empty());
        let (r, due, pl, gap, slow) = (p.aidr[0], p.aidr[1], p.aidr[2], p.aidr[4], p.aidr[5]);
        assert_eq!((r, due, pl, slow), (rows as f64, rows as f64, rows as f64, 0.0));
        assert!((p.aidr[3] - rate).abs() < 1e-9 * rate, "AIDR Hz {}", p.aidr[3]);
        assert_eq!(gap, 1000.0 / rate, "largest gap one period");
        assert!(p.texts.iter().all(|t| t.1.len() <= 50), "{:?}", p.texts);
    }
}

/// Called at 30 Hz (a loaded autopilot, the millisecond clock read as an integer) for a 50 Hz
/// design, rows are skipped: the warning comes once, at the first call at which more than
/// 5 % of the 151 rows have been skipped (counted here from the design's times), and the
/// script keeps playing to the end; the end text's count is the number of distinct rows due
/// at the calls, AIDR's rate is 30 Hz within 1 %, and the end says it is not the design.
#[test]
fn called_at_30_hz_a_50_hz_design_warns_once_and_counts_the_rows_played() {
    let d = fifty_hz();
    let rows = d.t_s.len();
    let mut k = 0.0;
    let p = play_scheduled(d, |_, _| {
        k += 1.0;
        (T0_MS + k * 1000.0 / 30.0).floor()
    });
    let due = distinct_due_rows(d, &p.calls_ms);
    let (played, hz) = p.end_text(rows);
    assert_eq!(played, due.len(), "{:?}", p.texts);
    assert!(played < rows * 2 / 3 && played > rows / 2, "{played}");
    assert!((p.aidr[3] - 30.0).abs() <= 0.01 * 30.0, "AIDR Hz {}", p.aidr[3]);
    assert!((hz - 30.0).abs() <= 0.3, "{hz}");
    assert_eq!((p.aidr[0], p.aidr[1], p.aidr[2]), (rows as f64, rows as f64, played as f64));
    assert_eq!(p.aidr[5], 1.0, "Slow");
    let behind = p.with("behind");
    assert_eq!(behind.len(), 1, "once: {:?}", p.texts);
    assert_eq!(behind[0].0, 4, "MAV_WARNING");
    assert_eq!(p.with("not the designed manoeuvre").len(), 1);
    // The first call at which the rows due so far less those played exceed 5 % of all.
    let mut seen = std::collections::BTreeSet::new();
    let mut first_late = None;
    for (i, t) in p.calls_ms.iter().enumerate() {
        let Some(k) = due_row(d, *t) else { break };
        seen.insert(k);
        if (k + 1 - seen.len()) as f64 > 0.05 * rows as f64 {
            first_late = Some(i);
            break;
        }
    }
    let first_late = first_late.expect("rows skipped at 30 Hz");
    assert!(first_late < p.calls_ms.len() / 3, "{first_late}");
    assert_eq!(behind[0].2, first_late, "at once");
    assert!(p.rows.iter().rev().skip(1).all(Option::is_some), "kept playing to the end");
    assert!(p.texts.iter().all(|t| t.1.len() <= 50), "{:?}", p.texts);
}

/// A single stall longer than two table periods warns, though it skips fewer than 5 % of the
/// rows; one of exactly two periods does not (the rule is "more than two").
#[test]
fn one_gap_of_more_than_two_periods_warns_though_few_rows_are_skipped() {
    let d = three_surfaces();
    let rows = d.t_s.len();
    for (stall_ms, warned) in [(81.0, true), (80.0, false), (120.0, true)] {
        let mut calls = 0;
        let p = play_scheduled(d, |now, delay| {
            calls += 1;
            now + if calls == 20 { stall_ms } else { delay as f64 }
        });
        let (played, _) = p.end_text(rows);
        let skipped = rows - played;
        assert!((skipped as f64) < 0.05 * rows as f64, "{stall_ms}: {skipped}");
        assert_eq!(played, distinct_due_rows(d, &p.calls_ms).len());
        assert_eq!(p.with("behind").len(), usize::from(warned), "{stall_ms}: {:?}", p.texts);
        assert_eq!(p.aidr[4], stall_ms, "largest gap");
        assert_eq!(p.aidr[5], f64::from(u8::from(warned)));
    }
}

/// A design faster than the scripting scheduler's millisecond can time is refused, naming
/// `--rate-hz` and the limit; 1000 Hz itself is accepted.
#[test]
fn a_design_faster_than_a_row_a_millisecond_is_refused() {
    let mut d = three_surfaces().clone();
    d.plan.manoeuvres[0].dt_s = 1.0 / 2000.0;
    let e = ardupilot_lua(&d, &options(Start::ScrUser1)).unwrap_err().to_string();
    for w in ["--rate-hz 2000", "1000 Hz"] {
        assert!(e.contains(w), "{w:?} not in {e}");
    }
    assert!(check_script_rate(&d).is_err());
    assert!(px4_torque_table(&d, &options(Start::ScrUser1)).is_ok(), "PX4 has no such limit");
    d.plan.manoeuvres[0].dt_s = 1.0 / 1000.0;
    assert!(check_script_rate(&d).is_ok());
    let lua = ardupilot_lua(&d, &options(Start::ScrUser1)).unwrap();
    assert!(lua.contains("local PERIOD_MS = 1\n"), "{lua}");
}
