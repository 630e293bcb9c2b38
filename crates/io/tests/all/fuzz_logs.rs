//! Fuzzing of the binary log readers (PX4 ULog, ArduPilot DataFlash) on random bytes and on
//! truncated and bit-flipped valid logs built here. Bounded for CI by `PROPTEST_CASES`
//! (default 64). Checked: no panic; an error names the file and a byte offset inside (or at
//! the end of) the input; a truncation of a valid log keeps a prefix of its samples, never a
//! changed value.

use aeroident_io::FlightDataError;
use aeroident_io::dataflash::parse_dataflash;
use aeroident_io::ulog::parse_ulog;
use proptest::prelude::*;

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64)
}

const FILE: &str = "fuzz-target.log";

/// A minimal valid ULog (PX4 "ULog File Format"): header, one format with a float array and a
/// nested type, one subscription, `n` data messages with `x = i`, `v[k] = i + k`.
pub fn tiny_ulog(n: usize) -> Vec<u8> {
    let mut b = vec![0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01];
    b.extend_from_slice(&1_000_000u64.to_le_bytes());
    let msg = |t: u8, payload: &[u8], b: &mut Vec<u8>| {
        b.extend_from_slice(&(payload.len() as u16).to_le_bytes());
        b.push(t);
        b.extend_from_slice(payload);
    };
    // Flag bits: 8 compat, 8 incompat, 3 appended offsets.
    msg(b'B', &[0u8; 40], &mut b);
    msg(b'F', b"inner:uint8_t a;uint8_t[3] _padding0;", &mut b);
    msg(b'F', b"demo:uint64_t timestamp;float x;float[2] v;inner n;", &mut b);
    // Parameter: key length, key "<type> <name>", value.
    let key = b"float PARAM_A";
    let mut p = vec![key.len() as u8];
    p.extend_from_slice(key);
    p.extend_from_slice(&2.5f32.to_le_bytes());
    msg(b'P', &p, &mut b);
    let mut sub = vec![0u8];
    sub.extend_from_slice(&7u16.to_le_bytes());
    sub.extend_from_slice(b"demo");
    msg(b'A', &sub, &mut b);
    for i in 0..n {
        let mut d = 7u16.to_le_bytes().to_vec();
        d.extend_from_slice(&(2_000_000u64 + 10_000 * i as u64).to_le_bytes());
        d.extend_from_slice(&(i as f32).to_le_bytes());
        d.extend_from_slice(&(i as f32 + 0.0).to_le_bytes());
        d.extend_from_slice(&(i as f32 + 1.0).to_le_bytes());
        d.extend_from_slice(&[i as u8, 0, 0, 0]);
        msg(b'D', &d, &mut b);
    }
    b
}

fn offset_ok(e: &FlightDataError, len: usize) -> Result<(), TestCaseError> {
    let s = e.to_string();
    prop_assert!(s.starts_with(FILE), "{}", s);
    if let FlightDataError::LogDecode { offset, .. } = e {
        prop_assert!(*offset <= len as u64, "{} > {}", offset, len);
    }
    Ok(())
}

#[test]
fn analytic_tiny_ulog_decodes_to_its_values() {
    let c = parse_ulog(&tiny_ulog(5), FILE).unwrap();
    assert_eq!(c.topics.len(), 1);
    let t = &c.topics[0];
    assert_eq!(t.name, "demo");
    let names: Vec<&str> = t.fields.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["x", "v[0]", "v[1]", "n.a"]);
    assert_eq!(t.t_s, [2.0, 2.01, 2.02, 2.03, 2.04]);
    assert_eq!(t.fields[0].1, [0.0, 1.0, 2.0, 3.0, 4.0]);
    assert_eq!(t.fields[2].1, [1.0, 2.0, 3.0, 4.0, 5.0]);
    assert_eq!(t.fields[3].1, [0.0, 1.0, 2.0, 3.0, 4.0]);
    assert_eq!(c.parameters["PARAM_A"], 2.5);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn ulog_random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2048)) {
        if let Err(e) = parse_ulog(&bytes, FILE) {
            offset_ok(&e, bytes.len())?;
        }
    }

    #[test]
    fn ulog_truncated_keeps_a_prefix_of_the_samples(cut in 0usize..400) {
        let full = tiny_ulog(8);
        let cut = cut.min(full.len());
        match parse_ulog(&full[..cut], FILE) {
            Ok(c) => {
                let want = parse_ulog(&full, FILE).unwrap();
                for t in &c.topics {
                    let w = &want.topics[0];
                    prop_assert!(t.t_s.len() <= w.t_s.len());
                    prop_assert_eq!(&t.t_s[..], &w.t_s[..t.t_s.len()]);
                    for ((_, a), (_, b)) in t.fields.iter().zip(&w.fields) {
                        prop_assert_eq!(&a[..], &b[..a.len()]);
                    }
                }
            }
            Err(e) => offset_ok(&e, cut)?,
        }
    }

    #[test]
    fn ulog_bit_flips_never_panic(flips in prop::collection::vec((0usize..400, any::<u8>()), 1..8)) {
        let mut b = tiny_ulog(8);
        for (at, x) in flips {
            let i = at % b.len();
            b[i] ^= x;
        }
        if let Err(e) = parse_ulog(&b, FILE) {
            offset_ok(&e, b.len())?;
        }
    }
}

/// A minimal valid DataFlash log (ArduPilot LogStructure.h): the `FMT` of `FMT`, one type
/// `TST` (TimeUS `Q`, angle `c` centi-units, `L` lat, `f`), `n` messages with `i` in each.
pub fn tiny_dataflash(n: usize) -> Vec<u8> {
    let fmt = |id: u8, len: u8, name: &[u8], chars: &[u8], cols: &[u8]| {
        let mut m = vec![0xA3, 0x95, 128, id, len];
        let mut field = |b: &[u8], w: usize| {
            let mut v = b.to_vec();
            v.resize(w, 0);
            m.extend_from_slice(&v);
        };
        field(name, 4);
        field(chars, 16);
        field(cols, 64);
        m
    };
    let mut b = fmt(128, 89, b"FMT", b"BBnNZ", b"Type,Length,Name,Format,Columns");
    b.extend(fmt(200, 3 + 8 + 2 + 4 + 4, b"TST", b"QcLf", b"TimeUS,Ang,Lat,X"));
    for i in 0..n {
        b.extend_from_slice(&[0xA3, 0x95, 200]);
        b.extend_from_slice(&(1_000_000u64 + 20_000 * i as u64).to_le_bytes());
        b.extend_from_slice(&(100 * i as i16).to_le_bytes());
        b.extend_from_slice(&(10_000_000 * i as i32).to_le_bytes());
        b.extend_from_slice(&(i as f32).to_le_bytes());
    }
    b
}

#[test]
fn analytic_tiny_dataflash_decodes_to_its_values() {
    let c = parse_dataflash(&tiny_dataflash(4), FILE).unwrap();
    assert_eq!(c.topics.len(), 1);
    let t = &c.topics[0];
    assert_eq!(t.name, "TST");
    assert_eq!(t.t_s, [1.0, 1.02, 1.04, 1.06]);
    let names: Vec<&str> = t.fields.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["Ang", "Lat", "X"]);
    assert_eq!(t.fields[0].1, [0.0, 1.0, 2.0, 3.0]);
    assert_eq!(t.fields[1].1, [0.0, 1.0, 2.0, 3.0]);
    assert_eq!(t.fields[2].1, [0.0, 1.0, 2.0, 3.0]);
    assert!(c.skipped.is_empty() && c.truncated_at.is_none());
}

#[test]
fn dataflash_garbage_between_messages_is_skipped_and_reported() {
    let mut b = tiny_dataflash(2);
    let at = b.len();
    b.extend_from_slice(&[0x11, 0xA3, 0x00, 0x42]);
    b.extend(tiny_dataflash(3).split_off(2 * 89 + 2 * 21));
    let c = parse_dataflash(&b, FILE).unwrap();
    assert_eq!(c.skipped, vec![(at as u64, 4)]);
    // The third message (i = 2) repeats the time of i = 2 of the first run: 1.04 s.
    assert_eq!(c.topics[0].t_s, [1.0, 1.02, 1.04]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn dataflash_random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2048)) {
        if let Err(e) = parse_dataflash(&bytes, FILE) {
            offset_ok(&e, bytes.len())?;
        }
    }

    #[test]
    fn dataflash_truncated_keeps_a_prefix_of_the_samples(cut in 0usize..400) {
        let full = tiny_dataflash(8);
        let cut = cut.min(full.len());
        match parse_dataflash(&full[..cut], FILE) {
            Ok(c) => {
                let want = parse_dataflash(&full, FILE).unwrap();
                for t in &c.topics {
                    let w = &want.topics[0];
                    prop_assert_eq!(&t.t_s[..], &w.t_s[..t.t_s.len()]);
                    for ((_, a), (_, b)) in t.fields.iter().zip(&w.fields) {
                        prop_assert_eq!(&a[..], &b[..a.len()]);
                    }
                }
            }
            Err(e) => offset_ok(&e, cut)?,
        }
    }

    #[test]
    fn dataflash_bit_flips_never_panic(flips in prop::collection::vec((0usize..400, any::<u8>()), 1..8)) {
        let mut b = tiny_dataflash(8);
        for (at, x) in flips {
            let i = at % b.len();
            b[i] ^= x;
        }
        if let Err(e) = parse_dataflash(&b, FILE) {
            offset_ok(&e, b.len())?;
        }
    }
}
