//! Seeded mutation fuzzing of the binary readers (PX4 ULog, ArduPilot DataFlash, MATLAB
//! level-5 `.mat`): small valid files built here are truncated, bit-flipped, have bytes
//! inserted, deleted or duplicated and size fields set to boundary values, then decoded.
//! Checked per case: no panic; an error names the file; a decoded log keeps its invariants
//! (each field one value per timestamp, timestamps strictly increasing); and memory stays
//! bounded: the process's peak resident set stays under [`MEMORY_LIMIT_KB`] (the readers' own
//! caps on declared sizes; one unchecked size would take gigabytes).
//!
//! Cases per reader: `AEROIDENT_FUZZ_CASES` (default 500; the full campaign is
//! `AEROIDENT_FUZZ_CASES=1000000 cargo test --release -p aeroident-io --test all
//! fuzz_mutations::`).
//! `AEROIDENT_FUZZ_SEED` changes the seed (default 1); a failure names the case to rerun.

use crate::common::logs;

use aeroident_io::dataflash::decode_dataflash;
use aeroident_io::log::read_mat;
use aeroident_io::log_contents::{LogContents, TopicFilter};
use aeroident_io::ulog::decode_ulog;
use logs::{Dataflash, Ulog, mat_compressed, mat_file, mat_matrix};

/// Most resident memory the test process may reach (Linux `VmHWM`, checked after every
/// 1000 cases and at the end). The inputs are a few kB; without the readers' caps one
/// declared size would take gigabytes.
const MEMORY_LIMIT_KB: u64 = 512 * 1024;

/// The process's peak resident set, kB (`None` off Linux).
fn peak_rss_kb() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn cases() -> u64 {
    std::env::var("AEROIDENT_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(500)
}

fn seed() -> u64 {
    std::env::var("AEROIDENT_FUZZ_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(1)
}

/// SplitMix64 (Steele, Lea & Flood 2014): a reproducible stream per case.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values a corrupted size field takes: edges of the field's range and of small sizes.
const SIZES: [u64; 10] = [0, 1, 2, 3, 7, 0x7f, 0xff, 0x7fff, 0xffff, u64::MAX];

/// One to four mutations of `seed`: truncation, bit flips, byte insert/delete, a duplicated
/// or removed stretch, a 1/2/4/8-byte field set to a boundary value.
fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        let n = b.len();
        match rng.below(7) {
            0 => b.truncate(rng.below(n + 1)),
            1 => {
                if n > 0 {
                    let i = rng.below(n);
                    b[i] ^= 1 << rng.below(8);
                }
            }
            2 => {
                let i = rng.below(n + 1);
                b.insert(i, rng.next() as u8);
            }
            3 => {
                if n > 0 {
                    b.remove(rng.below(n));
                }
            }
            4 => {
                let i = rng.below(n + 1);
                let len = rng.below(64).min(n - i);
                let chunk = b[i..i + len].to_vec();
                let j = rng.below(n + 1);
                b.splice(j..j, chunk);
            }
            5 => {
                let i = rng.below(n + 1);
                let len = rng.below(64).min(n - i);
                b.drain(i..i + len);
            }
            _ => {
                let w = [1, 2, 4, 8][rng.below(4)];
                if n >= w {
                    let i = rng.below(n - w + 1);
                    let v = SIZES[rng.below(SIZES.len())].wrapping_add(rng.below(3) as u64);
                    let bytes = if rng.below(2) == 0 { v.to_le_bytes() } else { v.to_be_bytes() };
                    b[i..i + w].copy_from_slice(&bytes[..w]);
                }
            }
        }
    }
    b
}

/// A decoded log's invariants.
fn check_contents(c: &LogContents) -> Result<(), String> {
    for t in &c.topics {
        if !t.t_s.windows(2).all(|w| w[1] > w[0]) {
            return Err(format!("topic `{}`: times not strictly increasing", t.name));
        }
        if let Some((f, v)) = t.fields.iter().find(|(_, v)| v.len() != t.t_s.len()) {
            return Err(format!(
                "topic `{}`: field `{f}` has {} values for {}",
                t.name,
                v.len(),
                t.t_s.len()
            ));
        }
    }
    Ok(())
}

const FILE: &str = "fuzz-case";

/// Runs `cases()` mutations of `seeds` through `decode`; panics naming the first failing
/// case (a panic inside `decode`, memory past the limit, or a broken invariant).
fn campaign(reader: &str, seeds: &[Vec<u8>], decode: impl Fn(&[u8], u64) -> Result<(), String>) {
    let n = cases();
    let s = seed();
    let mut failures = Vec::new();
    for case in 0..n {
        let mut rng = Rng(s.wrapping_mul(0x1000_0000_0001).wrapping_add(case));
        let input = mutate(&seeds[rng.below(seeds.len())], &mut rng);
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| decode(&input, case)));
        let rss = if case % 1000 == 999 || case + 1 == n { peak_rss_kb() } else { None };
        let problem = match r {
            Err(_) => Some("panic".to_string()),
            Ok(Err(m)) => Some(m),
            Ok(Ok(())) if rss.is_some_and(|kb| kb > MEMORY_LIMIT_KB) => {
                Some(format!("peak resident memory {} kB", rss.unwrap_or(0)))
            }
            Ok(Ok(())) => None,
        };
        if let Some(p) = problem {
            failures.push(format!("case {case} (seed {s}, {} bytes): {p}", input.len()));
            if failures.len() >= 5 {
                break;
            }
        }
    }
    eprintln!("{reader}: {n} cases, {} failures", failures.len());
    assert!(failures.is_empty(), "{reader}: {failures:#?}");
}

/// The error (if any) must name the file.
fn named<T>(r: Result<T, aeroident_io::FlightDataError>) -> Result<Option<T>, String> {
    match r {
        Ok(v) => Ok(Some(v)),
        Err(e) if e.to_string().starts_with(FILE) => Ok(None),
        Err(e) => Err(format!("error does not name the file: {e}")),
    }
}

fn ulog_seeds() -> Vec<Vec<u8>> {
    let mut u = Ulog::new();
    u.format("inner:uint8_t a;uint8_t[3] _padding0;");
    u.format("demo:uint64_t timestamp;float x;float[2] v;inner n;");
    let key = b"float PARAM_A";
    let mut p = vec![key.len() as u8];
    p.extend_from_slice(key);
    p.extend_from_slice(&2.5f32.to_le_bytes());
    u.msg(b'P', &p);
    u.subscribe(0, 7, "demo");
    u.subscribe(1, 8, "demo");
    for i in 0..12u64 {
        let mut d = (7 + (i % 2) as u16).to_le_bytes().to_vec();
        d.extend_from_slice(&(2_000_000 + 10_000 * i).to_le_bytes());
        for x in [i as f32, i as f32 + 0.5, i as f32 + 1.0] {
            d.extend_from_slice(&x.to_le_bytes());
        }
        d.extend_from_slice(&[i as u8, 0, 0, 0]);
        u.msg(b'D', &d);
    }
    let mut r = Ulog::new();
    r.format("imu:uint64_t timestamp;float gyro;float accel;");
    r.subscribe(0, 1, "imu");
    r.data_f32(1, 1_000, &[1.0, 2.0]);
    r.format("imu:uint64_t timestamp;float accel;float gyro;");
    r.subscribe(0, 2, "imu");
    r.data_f32(2, 2_000, &[2.0, 1.0]);
    r.data_f32(1, u64::MAX, &[1.0, 2.0]);
    r.data_f32(2, 3_000, &[2.0, 1.0]);
    vec![u.0, r.0]
}

fn dataflash_seeds() -> Vec<Vec<u8>> {
    let mut d = Dataflash::new();
    d.fmt(200, 3 + 8 + 2 + 4 + 4 + 1, "TST", "QcLfB", "TimeUS,Ang,Lat,X,I");
    d.fmt(201, 3 + 8 + 1 + 16 + 16, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds");
    d.fmt(202, 3 + 8 + 16 + 4, "PARM", "QNf", "TimeUS,Name,Value");
    let mut fmtu = 1u64.to_le_bytes().to_vec();
    fmtu.push(200);
    let mut units = b"s---#".to_vec();
    units.resize(16, 0);
    fmtu.extend_from_slice(&units);
    fmtu.extend_from_slice(&[0u8; 16]);
    d.msg(201, &fmtu);
    let mut parm = 2u64.to_le_bytes().to_vec();
    let mut name = b"SCHED_LOOP_RATE".to_vec();
    name.resize(16, 0);
    parm.extend_from_slice(&name);
    parm.extend_from_slice(&50f32.to_le_bytes());
    d.msg(202, &parm);
    for i in 0..12u64 {
        let mut p = (1_000_000 + 20_000 * i).to_le_bytes().to_vec();
        p.extend_from_slice(&(100 * i as i16).to_le_bytes());
        p.extend_from_slice(&(10_000_000 * i as i32).to_le_bytes());
        p.extend_from_slice(&(i as f32).to_le_bytes());
        p.push((i % 2) as u8);
        d.msg(200, &p);
        if i == 6 {
            d.fmt(200, 3 + 8 + 4, "TST", "Qf", "TimeUS,X");
        }
        if i > 6 {
            d.0.truncate(d.0.len() - 7);
        }
    }
    vec![d.0]
}

fn mat_seeds() -> Vec<Vec<u8>> {
    let data: Vec<f64> = (0..12).map(|i| f64::from(i) * 0.25).collect();
    let m = mat_matrix("rec", &[4, 3], &data);
    let t = mat_matrix("t", &[4, 1], &data[..4]);
    let v = mat_matrix("V", &[1, 4], &data[4..8]);
    vec![
        mat_file(std::slice::from_ref(&m)),
        mat_file(&[mat_compressed(&m)]),
        mat_file(&[mat_compressed(&t), mat_compressed(&v)]),
        mat_file(&[t, v]),
    ]
}

#[test]
fn fuzz_ulog_mutations() {
    let filter = TopicFilter::columns(["demo.x", "demo[1].n.a", "imu.gyro"], []);
    campaign("ulog", &ulog_seeds(), |b, case| {
        let f = if case % 2 == 0 { TopicFilter::all() } else { filter.clone() };
        named(decode_ulog(b, FILE, &f))?.map_or(Ok(()), |c| check_contents(&c))
    });
}

#[test]
fn fuzz_dataflash_mutations() {
    let filter = TopicFilter::columns(["TST.X", "TST[1].Ang", "TST#2.X"], []);
    campaign("dataflash", &dataflash_seeds(), |b, case| {
        let f = if case % 2 == 0 { TopicFilter::all() } else { filter.clone() };
        named(decode_dataflash(b, FILE, &f))?.map_or(Ok(()), |c| check_contents(&c))
    });
}

#[test]
fn fuzz_mat_mutations() {
    campaign("mat", &mat_seeds(), |b, _| {
        let Some(t) = named(read_mat(b, FILE, None))? else { return Ok(()) };
        if t.names.len() != t.columns.len() {
            return Err(format!("{} names for {} columns", t.names.len(), t.columns.len()));
        }
        Ok(())
    });
}

#[test]
fn analytic_seeds_are_valid() {
    for s in ulog_seeds() {
        let c = decode_ulog(s.as_slice(), FILE, &TopicFilter::all()).unwrap();
        assert!(c.truncated_at.is_none() && !c.topics.is_empty());
    }
    let c = decode_dataflash(dataflash_seeds()[0].as_slice(), FILE, &TopicFilter::all()).unwrap();
    assert!(c.skipped.is_empty() && c.truncated_at.is_none(), "{c:?}");
    let names: Vec<&str> = c.topics.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, ["FMTU", "PARM", "TST", "TST[1]", "TST#2"]);
    for s in mat_seeds() {
        read_mat(s.as_slice(), FILE, None).unwrap();
    }
}
