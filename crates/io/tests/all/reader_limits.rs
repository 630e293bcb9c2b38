//! The binary log readers against hostile layouts: declared sizes and nesting no message can
//! hold, formats redefined mid-log, absurd timestamps, files cut in their definitions, types
//! redefined thousands of times. Each expected value is computed here from how the file was
//! built, not captured from the reader.

use crate::common::logs;

use aeroident_io::dataflash::parse_dataflash;
use aeroident_io::reader_report::DropKind;
use aeroident_io::ulog::parse_ulog;
use aeroident_io::{FlightDataError, Mapping, RecordEvent, open_log_with_report};
use logs::{Dataflash, Ulog, mapping_text};
use std::path::PathBuf;
use std::time::Instant;

/// A file in a fresh temporary directory.
fn temp_file(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("aeroident-reader-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn decode_error(e: FlightDataError) -> (u64, String) {
    match e {
        FlightDataError::LogDecode { offset, message, .. } => (offset, message),
        other => panic!("not a decode error: {other}"),
    }
}

#[test]
fn errors_ulog_nested_arrays_beyond_a_message_are_refused_before_allocating() {
    // Eight levels of 8-element arrays: 8⁹ bytes declared (134 MB of leaves, GBs of names).
    let mut u = Ulog::new();
    u.format("n0:uint8_t[8] x;");
    for k in 1..8 {
        u.format(&format!("n{k}:n{}[8] e;", k - 1));
    }
    u.format("deep:uint64_t timestamp;n7[8] e;");
    let sub_at = u.0.len() as u64;
    u.subscribe(0, 1, "deep");
    let started = Instant::now();
    let (offset, msg) = decode_error(parse_ulog(&u.0, "deep.ulg").unwrap_err());
    assert!(started.elapsed().as_secs_f64() < 1.0, "refused before expanding");
    assert_eq!(offset, sub_at);
    assert!(msg.contains("subscription 1 (`deep`)"), "{msg}");
    assert!(msg.contains("larger than 65533 bytes"), "{msg}");
    // 65535 × 65535: the product overflows what a message holds at the second level.
    let mut u = Ulog::new();
    u.format("wide:uint8_t[60000] x;");
    u.format("huge:uint64_t timestamp;wide[65535] w;");
    u.subscribe(0, 2, "huge");
    let (_, msg) = decode_error(parse_ulog(&u.0, "huge.ulg").unwrap_err());
    assert!(msg.contains("format `huge`: field `wide[65535] w`"), "{msg}");
    // A nested format with no bytes would let an array loop without bound.
    let mut u = Ulog::new();
    u.format("empty:");
    u.format("z:uint64_t timestamp;empty[65535] e;");
    u.subscribe(0, 3, "z");
    let (_, msg) = decode_error(parse_ulog(&u.0, "z.ulg").unwrap_err());
    assert!(msg.contains("nested format `empty` has no bytes"), "{msg}");
    // A format that contains itself.
    let mut u = Ulog::new();
    u.format("loop:uint64_t timestamp;loop inner;");
    u.subscribe(0, 4, "loop");
    let (_, msg) = decode_error(parse_ulog(&u.0, "loop.ulg").unwrap_err());
    assert!(msg.contains("nests deeper than 8 levels"), "{msg}");
    // Long field names repeated by nesting: under the byte limit, over the name limit.
    let long = "n".repeat(4000);
    let mut u = Ulog::new();
    u.format(&format!("leaf:uint8_t[16] {long};"));
    u.format(&format!("mid:leaf[16] {long};"));
    u.format("names:uint64_t timestamp;mid[16] m;");
    u.subscribe(0, 5, "names");
    let (_, msg) = decode_error(parse_ulog(&u.0, "names.ulg").unwrap_err());
    assert!(msg.contains("flattened field names pass 1048576 bytes"), "{msg}");
}

#[test]
fn val_ulog_format_redefined_in_another_field_order_is_decoded_by_its_own_definition() {
    let mut u = Ulog::new();
    u.format("imu:uint64_t timestamp;float gyro;float accel;");
    u.subscribe(0, 1, "imu");
    for i in 0..5u64 {
        u.data_f32(1, 1_000 * i, &[i as f32, 100.0 + i as f32]);
    }
    // Same fields, other order, new msg_id.
    u.format("imu:uint64_t timestamp;float accel;float gyro;");
    u.subscribe(0, 2, "imu");
    for i in 5..10u64 {
        u.data_f32(2, 1_000 * i, &[100.0 + i as f32, i as f32]);
    }
    // Other fields: a topic of its own.
    u.format("imu:uint64_t timestamp;float accel;float gyro;float temp;");
    u.subscribe(0, 3, "imu");
    u.data_f32(3, 20_000, &[1.0, 2.0, 3.0]);
    let c = parse_ulog(&u.0, "redef.ulg").unwrap();
    let imu = c.topics.iter().find(|t| t.name == "imu").unwrap();
    let field = |n: &str| &imu.fields.iter().find(|(f, _)| f == n).unwrap().1;
    let want: Vec<f64> = (0..10).map(f64::from).collect();
    assert_eq!(field("gyro"), &want);
    assert_eq!(field("accel"), &want.iter().map(|g| g + 100.0).collect::<Vec<_>>());
    let v3 = c.topics.iter().find(|t| t.name == "imu#2").unwrap();
    assert_eq!(v3.fields.len(), 3);
    assert_eq!(v3.fields[2], ("temp".to_string(), vec![3.0]));
}

/// A ULog of one topic `imu` (fields `v`, `a`) at 1 kHz, 2001 samples, sample `bad` stamped
/// `u64::MAX`; returns the file and the byte offset of that sample.
fn ulog_with_absurd_timestamp(bad: usize) -> (Vec<u8>, u64) {
    let mut u = Ulog::new();
    u.format("imu:uint64_t timestamp;float v;float a;");
    u.subscribe(0, 1, "imu");
    let mut at = 0;
    for i in 0..2001u64 {
        let t = if i as usize == bad { u64::MAX } else { 1_000_000 + 1_000 * i };
        if i as usize == bad + 1 {
            at = u.0.len() as u64;
        }
        u.data_f32(1, t, &[50.0 + i as f32 * 0.001, 0.05]);
    }
    (u.0, at)
}

#[test]
fn val_one_absurd_timestamp_costs_one_sample_and_is_counted_in_the_report() {
    let (bytes, descent_at) = ulog_with_absurd_timestamp(600);
    let c = parse_ulog(&bytes, "t.ulg").unwrap();
    assert_eq!(c.topics[0].t_s.len(), 2000);
    assert_eq!(c.dropped["imu"], 1);
    assert_eq!(c.dropped_at["imu"], (600, descent_at));
    // Through the mapping: the report carries the drop; rows span the whole record.
    let path = temp_file("absurd.ulg", &bytes);
    let m = Mapping::from_toml_str(&mapping_text("imu", 1000.0), "m.toml").unwrap();
    let (reader, report) = open_log_with_report(path.to_str().unwrap(), None, &m).unwrap();
    let d = &report.dropped;
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!(d[0].kind, DropKind::TimestampOrder);
    assert_eq!((d[0].topic.as_deref(), d[0].count, d[0].of), (Some("imu"), 1, Some(2001)));
    assert_eq!((d[0].first_sample, d[0].first_byte), (Some(600), Some(descent_at)));
    let json = serde_json::to_value(&report).unwrap();
    assert_eq!(json["dropped"][0]["kind"], "timestamp_order");
    let samples = reader.filter(|e| matches!(e, Ok(RecordEvent::Sample { .. }))).count();
    // 2000 ms of samples at 1 kHz: 2001 output rows over [1.000, 3.000] s; the one at the
    // dropped sample's time is interpolated, not lost.
    assert_eq!(samples, 2001);
}

/// The error opening `bytes` (written as `name`) with a mapping reading `imu.v` and `imu.a`.
fn open_error(name: &str, bytes: &[u8]) -> String {
    let m = Mapping::from_toml_str(&mapping_text("imu", 100.0), "m.toml").unwrap();
    let path = temp_file(name, bytes);
    open_log_with_report(path.to_str().unwrap(), None, &m).err().unwrap().to_string()
}

#[test]
fn errors_a_log_cut_in_its_definitions_leads_with_the_cut() {
    let mut u = Ulog::new();
    u.format("other:uint64_t timestamp;float x;");
    u.subscribe(0, 1, "other");
    u.data_f32(1, 1_000, &[1.0]);
    let cut_at = u.0.len();
    u.format("imu:uint64_t timestamp;float v;float a;");
    let e = open_error("cut.ulg", &u.0[..cut_at + 10]);
    let lead = format!(
        "`imu.v` for channel `vt`: the file ends inside a message at byte {cut_at}: no \
         topic/message `imu` was found before byte {cut_at} (it has: other)"
    );
    assert!(e.ends_with(&lead), "{e}");
    // DataFlash cut inside the FMT of the type the mapping needs: no topic at all.
    let mut d = Dataflash::new();
    let cut_at = d.0.len();
    d.fmt(200, 3 + 8 + 8, "imu", "Qff", "TimeUS,v,a");
    let e = open_error("cut.bin", &d.0[..cut_at + 40]);
    let lead = format!(
        "`imu.v` for channel `vt`: the file ends inside a message at byte {cut_at}: no \
         topic/message `imu` was found before byte {cut_at} (it has: none)"
    );
    assert!(e.ends_with(&lead), "{e}");
    // DataFlash whose `imu` FMT is overwritten by 40 corrupt bytes: its messages are skipped
    // as well (a type with no FMT); the first joins the junk, the others are stretches of
    // their own between `oth` messages.
    let mut d = Dataflash::new();
    d.fmt(201, 3 + 8 + 4, "oth", "Qf", "TimeUS,x");
    let junk_at = d.0.len();
    d.0.extend([0x5a; 40]);
    for i in 0..3u64 {
        d.msg(200, &[(1_000 * i).to_le_bytes().as_slice(), &[0u8; 8]].concat());
        d.msg(201, &[(1_000 * i).to_le_bytes().as_slice(), &1f32.to_le_bytes()].concat());
    }
    let total = 40 + 3 * (3 + 16);
    let e = open_error("junk.bin", &d.0);
    let lead = format!(
        "`imu.v` for channel `vt`: 3 corrupt stretches of {total} bytes in all (the first at \
         byte {junk_at}) were skipped: no topic/message `imu` was found outside the skipped \
         bytes (it has: oth)"
    );
    assert!(e.ends_with(&lead), "{e}");
    // A topic that is there but lacks the field: the cut is a trailing note.
    let mut u = Ulog::new();
    u.format("imu:uint64_t timestamp;float v;");
    u.subscribe(0, 1, "imu");
    u.data_f32(1, 1_000, &[1.0]);
    let cut_at = u.0.len();
    u.data_f32(1, 2_000, &[1.0]);
    let e = open_error("field.ulg", &u.0[..cut_at + 5]);
    assert!(e.contains("`alpha`: topic `imu` has no field `a` (it has: v)"), "{e}");
    let note = format!(
        "; note: the file ends inside a message at byte {cut_at} (what the file holds there is \
         missing)"
    );
    assert!(e.ends_with(&note), "{e}");
}

#[test]
fn val_dataflash_type_redefined_20000_times_reads_in_linear_time() {
    // Two layouts of `TST` alternate: a definition, then one message, 20 000 times.
    let mut d = Dataflash::new();
    for i in 0..20_000u64 {
        let (chars, cols) = if i % 2 == 0 { ("Qf", "TimeUS,X") } else { ("Qff", "TimeUS,X,Y") };
        d.fmt(200, 3 + 8 + 4 * chars.len() as u8 - 4, "TST", chars, cols);
        let mut p = (1_000 + 10 * i).to_le_bytes().to_vec();
        p.extend_from_slice(&(i as f32).to_le_bytes());
        if i % 2 == 1 {
            p.extend_from_slice(&(-(i as f32)).to_le_bytes());
        }
        d.msg(200, &p);
    }
    let started = Instant::now();
    let c = parse_dataflash(&d.0, "redef.bin").unwrap();
    let secs = started.elapsed().as_secs_f64();
    eprintln!("20 000 DataFlash redefinitions ({} bytes) read in {secs:.3} s", d.0.len());
    // Quadratic handling took about a minute here; linear is well under a second even
    // unoptimised.
    assert!(secs < 5.0, "{secs} s");
    let names: Vec<&str> = c.topics.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, ["TST", "TST#2"]);
    let want: Vec<f64> = (0..20_000).step_by(2).map(f64::from).collect();
    assert_eq!(c.topics[0].fields[0].1, want);
    let y: Vec<f64> = (1..20_000).step_by(2).map(|i| -f64::from(i)).collect();
    assert_eq!(c.topics[1].fields[1].1, y);
}

#[test]
fn val_filtered_read_keeps_only_what_the_mapping_reads() {
    let mut u = Ulog::new();
    u.format("imu:uint64_t timestamp;float v;float a;float unused;");
    u.format("big:uint64_t timestamp;float[8] x;");
    u.subscribe(0, 1, "imu");
    u.subscribe(0, 2, "big");
    for i in 0..100u64 {
        u.data_f32(1, 1_000 * i, &[1.0, 2.0, 3.0]);
        u.data_f32(2, 1_000 * i, &[0.0; 8]);
    }
    let filter = aeroident_io::log_contents::TopicFilter::columns(["imu.v", "imu.a"], []);
    let c = aeroident_io::ulog::decode_ulog(u.0.as_slice(), "f.ulg", &filter).unwrap();
    assert_eq!(c.topics.len(), 1);
    let names: Vec<&str> = c.topics[0].fields.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["v", "a"]);
    let cat: Vec<(&str, usize, usize)> =
        c.catalogue.iter().map(|t| (t.name.as_str(), t.fields.len(), t.messages)).collect();
    assert_eq!(cat, [("imu", 3, 100), ("big", 8, 100)]);
}

#[test]
fn val_ulog_formats_redefined_and_wide_formats_read_in_linear_time() {
    // 20 000 redefinitions, each subscribed under a new msg_id with one sample, two layouts.
    let mut u = Ulog::new();
    for i in 0..20_000u64 {
        let f = if i % 2 == 0 {
            "t:uint64_t timestamp;float x;"
        } else {
            "t:uint64_t timestamp;float x;float y;"
        };
        u.format(f);
        u.subscribe(0, (i % 60_000) as u16, "t");
        let fields: &[f32] = if i % 2 == 0 { &[1.0] } else { &[1.0, 2.0] };
        u.data_f32((i % 60_000) as u16, 1_000 + i, fields);
    }
    // A format of 65 000 one-byte fields (an array, flattened), all kept.
    let wide = "wide:uint64_t timestamp;uint8_t[65000] a;";
    u.format(wide);
    u.subscribe(0, 60_001, "wide");
    let started = Instant::now();
    let c = parse_ulog(&u.0, "many.ulg").unwrap();
    let secs = started.elapsed().as_secs_f64();
    assert!(secs < 10.0, "{secs} s");
    let names: Vec<(&str, usize)> =
        c.topics.iter().map(|t| (t.name.as_str(), t.t_s.len())).collect();
    assert_eq!(names, [("t", 10_000), ("t#2", 10_000)]);
    assert_eq!(c.catalogue.len(), 2, "the wide topic has no message");
}

#[test]
fn errors_many_subscriptions_to_a_wide_format_are_refused_before_their_fields_are_built() {
    // 65 000 fields a subscription, resubscribed under new ids: a few kB of file.
    let mut u = Ulog::new();
    u.format("wide:uint64_t timestamp;uint8_t[65000] a;");
    for id in 0..40u16 {
        u.subscribe(0, id, "wide");
    }
    let (_, msg) = decode_error(parse_ulog(&u.0, "wide.ulg").unwrap_err());
    assert!(msg.contains("(`wide`): format `wide` (65008 bytes) would take the fields"), "{msg}");
    assert!(msg.contains("past 2000000 in all"), "{msg}");
    // Resubscribing the same id replaces the subscription: no limit reached.
    let mut u = Ulog::new();
    u.format("wide:uint64_t timestamp;uint8_t[65000] a;");
    for _ in 0..40 {
        u.subscribe(0, 1, "wide");
    }
    assert!(parse_ulog(&u.0, "wide.ulg").is_ok());
    // DataFlash: a timed type whose instance field takes a new value in every message.
    let mut d = Dataflash::new();
    d.fmt(200, 3 + 8 + 4 + 32 * 2, "INS", "Qia", "TimeUS,I,A");
    d.fmt(201, 3 + 8 + 1 + 16 + 16, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds");
    let mut fmtu = 1u64.to_le_bytes().to_vec();
    fmtu.push(200);
    fmtu.extend_from_slice(b"s#\0\0\0\0\0\0\0\0\0\0\0\0\0\0");
    fmtu.extend_from_slice(&[0u8; 16]);
    d.msg(201, &fmtu);
    for i in 0..70_000i32 {
        let mut p = (i as u64).to_le_bytes().to_vec();
        p.extend_from_slice(&i.to_le_bytes());
        p.extend_from_slice(&[0u8; 64]);
        d.msg(200, &p);
    }
    let (_, msg) = decode_error(parse_dataflash(&d.0, "ins.bin").unwrap_err());
    assert!(msg.contains("pass 2000000 fields in all"), "{msg}");
}

/// A ULog whose formats `p0` … `p6` nest one in the next, each through a field with a
/// 60 000-character name (`p0` holds `uint8_t[leaf_len]`), and whose topic `pad` carries
/// `p6[count] _padding0` between its timestamp and a `float v`; one sample, `v` = 2.5.
fn ulog_with_named_padding(leaf_len: usize, count: usize) -> Vec<u8> {
    let long = |k: usize| format!("{k}{}", "n".repeat(60_000));
    let mut u = Ulog::new();
    u.format(&format!("p0:uint8_t[{leaf_len}] {};", long(0)));
    for k in 1..7 {
        u.format(&format!("p{k}:p{} {};", k - 1, long(k)));
    }
    u.format(&format!("pad:uint64_t timestamp;p6[{count}] _padding0;float v;"));
    u.subscribe(0, 1, "pad");
    let mut p = 1u16.to_le_bytes().to_vec();
    p.extend_from_slice(&5_000u64.to_le_bytes());
    p.resize(p.len() + count * leaf_len, 0xee);
    p.extend_from_slice(&2.5f32.to_le_bytes());
    u.msg(b'D', &p);
    u.0
}

#[test]
fn val_ulog_padding_is_skipped_by_its_size_without_building_names() {
    // One padding element would expand to three leaves of 6 × 60 000 + … bytes of name each:
    // more than the 1 MiB a topic's names may have, were padding named.
    let c = parse_ulog(&ulog_with_named_padding(3, 20_000), "pad3.ulg").unwrap();
    assert_eq!(c.topics.len(), 1);
    assert_eq!(c.topics[0].fields, [("v".to_string(), vec![2.5])]);
    assert_eq!(c.topics[0].t_s, [0.005]);
    // The probe's shape: 65 000 one-byte elements of 420 kB of name each (27 GB of names,
    // half a minute per subscription when padding was expanded). Four subscriptions.
    let mut bytes = ulog_with_named_padding(1, 65_000);
    let mut u = Ulog(Vec::new());
    for id in 2..5 {
        u.subscribe(0, id, "pad");
    }
    bytes.extend_from_slice(&u.0);
    let c = parse_ulog(&bytes, "pad1.ulg").unwrap();
    assert_eq!(c.topics[0].fields, [("v".to_string(), vec![2.5])]);
}

#[test]
fn errors_subscriptions_rebuilding_a_megabyte_of_names_each_are_refused_in_all() {
    // 112 leaves of ~8 kB of name: under the 1 MiB a topic may have, each resubscription
    // (8 bytes of file) builds them again.
    let long = "n".repeat(8_000);
    let mut u = Ulog::new();
    u.format(&format!("leaf:uint8_t[8] {long};"));
    u.format("mid:leaf[14] m;");
    u.format("names:uint64_t timestamp;mid m;");
    let leaf_names: usize = (0..14)
        .flat_map(|i| (0..8).map(move |j| (i, j)))
        .map(|(i, j)| format!("m.m[{i}].{long}[{j}]").len())
        .sum();
    let mut at = Vec::new();
    for _ in 0..200 {
        at.push(u.0.len() as u64);
        u.subscribe(0, 1, "names");
    }
    let (offset, msg) = decode_error(parse_ulog(&u.0, "names.ulg").unwrap_err());
    assert!(msg.contains("subscription 1 (`names`)"), "{msg}");
    assert!(msg.contains("names of this log's subscriptions pass 67108864 bytes in all"), "{msg}");
    // At least the leaves' names are built per subscription, at most the topic's 1 MiB.
    let k = at.iter().position(|&a| a == offset).unwrap();
    assert!(k >= 64 && k <= (64 << 20) / leaf_names, "refused at subscription {k}");
}

/// Every topic's first message stamped one day before the rest (a clock not yet set when
/// logging began): the first samples are time outliers, counted in the reader report with the
/// topic, and the record spans the topics' own time; before, the day-long span was refused.
#[test]
fn errors_every_topics_first_sample_a_day_early_is_dropped_and_counted() {
    let day = 86_400_000_000u64;
    let mut u = Ulog::new();
    u.format("imu:uint64_t timestamp;float v;float a;");
    u.format("gps:uint64_t timestamp;float v;float a;");
    u.subscribe(0, 1, "imu");
    u.subscribe(0, 2, "gps");
    u.data_f32(1, 1_000_000, &[1.0, 1.0]);
    u.data_f32(2, 1_000_500, &[1.0, 1.0]);
    for i in 0..1001u64 {
        u.data_f32(1, day + 1_000 * i, &[50.0 + i as f32 * 0.001, 0.05]);
        if i % 10 == 0 {
            u.data_f32(2, day + 1_000 * i, &[0.0, 0.0]);
        }
    }
    let c = parse_ulog(&u.0, "early.ulg").unwrap();
    assert_eq!(c.early_time_outliers["imu"], (1, 1.0));
    assert_eq!(c.early_time_outliers["gps"], (1, 1.0005));
    let path = temp_file("early.ulg", &u.0);
    let m = Mapping::from_toml_str(&mapping_text("imu", 1000.0), "m.toml").unwrap();
    let (reader, report) = open_log_with_report(path.to_str().unwrap(), None, &m).unwrap();
    let d = &report.dropped;
    assert_eq!(d.len(), 1, "only the mapped topic is kept: {d:?}");
    assert_eq!(d[0].kind, DropKind::TimeOutlier);
    assert_eq!((d[0].topic.as_deref(), d[0].count, d[0].of), (Some("imu"), 1, Some(1002)));
    assert_eq!((d[0].first_sample, d[0].first_time_s), (Some(0), Some(1.0)));
    let json = serde_json::to_value(&report).unwrap();
    assert_eq!(json["dropped"][0]["kind"], "time_outlier");
    let samples: Vec<f64> = reader
        .filter_map(|e| match e {
            Ok(RecordEvent::Sample { sample, .. }) => Some(sample.vt_mps),
            _ => None,
        })
        .collect();
    // 1 s at 1 kHz: 1001 rows, the first the first sample of the day (v = 50).
    assert_eq!(samples.len(), 1001);
    assert_eq!(samples[0], 50.0);
}

/// An `R` (remove logged message) message for `msg_id` `id`.
fn remove_subscription(u: &mut Ulog, id: u16) {
    u.msg(b'R', &id.to_le_bytes());
}

/// A `msg_id` still subscribed to topic `a` and subscribed again to `b` (another format, another
/// instance) with no `R` between: the data after it could be either topic's, so the log is
/// refused at that subscription, naming the id and both topics (the reader used to hand every
/// later sample of the id to `b`).
#[test]
fn errors_ulog_msg_id_reused_for_another_topic_without_removal_is_refused() {
    let mut u = Ulog::new();
    u.format("a:uint64_t timestamp;float x;");
    u.format("b:uint64_t timestamp;float y;");
    let first = u.0.len() as u64;
    u.subscribe(0, 3, "a");
    u.data_f32(3, 1_000, &[1.0]);
    let second = u.0.len() as u64;
    u.subscribe(1, 3, "b");
    u.data_f32(3, 2_000, &[2.0]);
    let e = parse_ulog(&u.0, "reuse.ulg").unwrap_err();
    let text = e.to_string();
    let (offset, msg) = decode_error(e);
    assert_eq!(offset, second);
    assert!(text.starts_with(&format!("reuse.ulg: byte {second}: ")), "{text}");
    assert!(
        msg.contains(&format!(
            "the subscription at byte {second} re-uses msg_id 3 of topic `a` (instance 0, subscribed at byte {first}) for `b` (instance 1) without removing it first"
        )),
        "{msg}"
    );
    // The same topic and instance under another format is still another subscription.
    let mut u = Ulog::new();
    u.format("a:uint64_t timestamp;float x;");
    u.subscribe(0, 3, "a");
    u.subscribe(1, 3, "a");
    let (_, msg) = decode_error(parse_ulog(&u.0, "reuse.ulg").unwrap_err());
    assert!(
        msg.contains("msg_id 3 of topic `a` (instance 0") && msg.contains("for `a` (instance 1)")
    );
}

/// An `R` frees its `msg_id`: the data before it are `a`'s, the data after a new subscription
/// `b`'s; a data message between the two (the id subscribed to nothing) is refused naming the
/// id and where it was removed, where the reader used to give it to `a`.
#[test]
fn val_ulog_removed_msg_id_may_be_subscribed_again() {
    let mut u = Ulog::new();
    u.format("a:uint64_t timestamp;float x;");
    u.format("b:uint64_t timestamp;float y;float z;");
    u.subscribe(0, 3, "a");
    u.data_f32(3, 1_000, &[1.0]);
    u.data_f32(3, 2_000, &[2.0]);
    let removed = u.0.len() as u64;
    remove_subscription(&mut u, 3);
    let mut stray = Ulog(u.0.clone());
    u.subscribe(0, 3, "b");
    u.data_f32(3, 3_000, &[3.0, 4.0]);
    let c = parse_ulog(&u.0, "removed.ulg").unwrap();
    let topic = |n: &str| c.topics.iter().find(|t| t.name == n).unwrap();
    assert_eq!(topic("a").t_s, [0.001, 0.002]);
    assert_eq!(topic("a").fields, [("x".to_string(), vec![1.0, 2.0])]);
    assert_eq!(topic("b").t_s, [0.003]);
    assert_eq!(topic("b").fields, [("y".to_string(), vec![3.0]), ("z".to_string(), vec![4.0])]);
    // Data for the removed id before it is subscribed again.
    let at = stray.0.len() as u64;
    stray.data_f32(3, 3_000, &[3.0]);
    let (offset, msg) = decode_error(parse_ulog(&stray.0, "stray.ulg").unwrap_err());
    assert_eq!(offset, at);
    assert!(
        msg.contains(&format!(
            "data message for msg_id 3, whose subscription to `a` (instance 0) was removed at byte {removed}"
        )),
        "{msg}"
    );
}

/// A MAVLink telemetry log replays through a mapping as a ULog does: `ATTITUDE` (v2 frames)
/// and `VFR_HUD` (v1) at 50 Hz, aligned on their common 50-Hz grid, give at every row the
/// values written at that time (Unix seconds), and a frame of a message id the dialect does
/// not know is skipped and counted in the reader's report.
#[test]
fn val_a_tlog_replays_its_messages_at_their_times() {
    use mavlink::MavlinkVersion::{V1, V2};
    use mavlink::dialects::ardupilotmega::{ATTITUDE_DATA, MavMessage, VFR_HUD_DATA};
    let unknown_id = 16_000u32;
    use mavlink::Message as _;
    let known = MavMessage::default_message_from_id(unknown_id);
    assert!(known.is_none(), "the test needs an unknown id");
    let t0_us = 1_700_000_000_000_000u64;
    let w = std::f64::consts::PI;
    let roll = |t: f64| 0.1 * (w * t).sin();
    let vt = |t: f64| 20.0 + 0.5 * t;
    let mut b = Vec::new();
    let n = 200u64;
    for k in 0..n {
        let (t_us, t) = (t0_us + k * 20_000, k as f64 * 0.02);
        let att = ATTITUDE_DATA {
            roll: roll(t) as f32,
            rollspeed: (0.1 * w * (w * t).cos()) as f32,
            pitch: 0.05,
            ..Default::default()
        };
        logs::tlog_record(&mut b, t_us, V2, &MavMessage::ATTITUDE(att));
        let hud = VFR_HUD_DATA { airspeed: vt(t) as f32, ..Default::default() };
        logs::tlog_record(&mut b, t_us, V1, &MavMessage::VFR_HUD(hud));
        if k == 50 {
            b.extend((t_us + 1).to_be_bytes());
            let id = unknown_id.to_le_bytes();
            b.extend([0xFD, 1, 0, 0, 0, 1, 1, id[0], id[1], id[2], 7, 0x12, 0x34]);
        }
    }
    let path = temp_file("link.tlog", &b);
    let text = "nominal_dt_s = 0.02\n[time]\ncolumn = \"time_s\"\nunit = \"s\"\n[align]\nrate_hz = 50.0\nmethod = \"linear\"\n[channels]\nvt = { column = \"VFR_HUD.airspeed\", unit = \"m/s\" }\nalpha = { column = \"ATTITUDE.pitch\", unit = \"rad\" }\np = { column = \"ATTITUDE.rollspeed\", unit = \"rad/s\" }\nphi = { column = \"ATTITUDE.roll\", unit = \"rad\" }\nmass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\n";
    let m = Mapping::from_toml_str(text, "m.toml").unwrap();
    let (reader, report) = open_log_with_report(path.to_str().unwrap(), None, &m).unwrap();
    assert_eq!(report.format, "tlog");
    let d: Vec<_> = report.dropped.iter().filter(|d| d.kind == DropKind::UnknownMessage).collect();
    assert_eq!(d.len(), 1, "{:?}", report.dropped);
    assert_eq!((d[0].topic.as_deref(), d[0].count), (Some("message id 16000"), 1));
    assert!(report.notes().iter().any(|l| l.contains("1 frames of message id 16000 skipped")));
    let t0 = t0_us as f64 * 1e-6;
    let mut rows = 0;
    for e in reader {
        let Ok(RecordEvent::Sample { sample, .. }) = e else { continue };
        let t = sample.t_s - t0;
        assert!((-1e-6..=3.98 + 1e-6).contains(&t), "t {t}");
        assert!((sample.phi_rad.unwrap() - roll(t)).abs() < 1e-4, "φ at {t}");
        assert!((sample.p_rad_s.unwrap() - 0.1 * w * (w * t).cos()).abs() < 1e-3, "p at {t}");
        assert!((sample.vt_mps - vt(t)).abs() < 1e-4, "V at {t}");
        assert!((sample.alpha_rad - 0.05).abs() < 1e-7);
        rows += 1;
    }
    assert!((n - 1..=n).contains(&rows), "{rows} rows");
}
