//! What the log reader leaves out reaches `summary.json` (`reader`) and `report.html`, counted
//! per kind and topic with where it began: the real PX4 log with one `sensor_combined`
//! timestamp set to `u64::MAX`, through the binary.

use crate::common;
use common::workspace;
use std::process::Command;

/// Byte offsets of the ULog `D` messages of format `name` (instance 0) and of their
/// timestamp field, found by walking the messages (PX4 "ULog File Format": 16-byte header,
/// then `u16 size, u8 type, payload`; `A` = multi_id, msg_id, name; `D` = msg_id, data).
fn data_messages(b: &[u8], name: &str) -> Vec<usize> {
    let mut at = 16;
    let mut id = None;
    let mut out = Vec::new();
    while at + 3 <= b.len() {
        let size = usize::from(u16::from_le_bytes([b[at], b[at + 1]]));
        let p = &b[(at + 3).min(b.len())..(at + 3 + size).min(b.len())];
        match b[at + 2] {
            // The timestamp must be the first field for the offset below.
            b'F' if p.starts_with(format!("{name}:").as_bytes()) => {
                assert!(p.starts_with(format!("{name}:uint64_t timestamp;").as_bytes()));
            }
            b'A' if p.len() > 3 && p[0] == 0 && &p[3..] == name.as_bytes() => {
                id = Some([p[1], p[2]]);
            }
            b'D' if id.is_some_and(|i| p[..2] == i) => out.push(at + 3 + 2),
            _ => {}
        }
        at += 3 + size;
    }
    out
}

#[test]
fn val_one_absurd_timestamp_is_counted_in_summary_and_report() {
    let Some(data) = common::shared("px4_ardupilot/f16capstone_log_52_2021-5-22-12-42-56.ulg")
    else {
        return;
    };
    let mut bytes = std::fs::read(&data).unwrap();
    let ts = data_messages(&bytes, "sensor_combined");
    let k = ts.len() / 2;
    bytes[ts[k]..ts[k] + 8].copy_from_slice(&u64::MAX.to_le_bytes());
    let dir = std::env::temp_dir().join(format!("aeroident-reader-report-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("absurd.ulg");
    std::fs::write(&log, &bytes).unwrap();
    let out = dir.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .arg("replay")
        .arg(&log)
        .arg("--map")
        .arg(workspace().join("mappings/px4-fixedwing.toml"))
        .args(["--estimator", "rls", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let reader = v["reader"].as_array().unwrap();
    assert_eq!(reader.len(), 1);
    assert_eq!(reader[0]["format"], "ulog");
    let drops = reader[0]["dropped"].as_array().unwrap();
    let d = drops
        .iter()
        .find(|d| d["kind"] == "timestamp_order" && d["topic"] == "sensor_combined")
        .unwrap_or_else(|| panic!("{drops:?}"));
    // One sample, the one changed: its index and the message after it (the first timestamp
    // that did not increase).
    assert_eq!(d["count"], 1);
    assert_eq!(d["first_sample"], k as u64);
    assert_eq!(d["first_byte"], (ts[k + 1] - 5) as u64);
    assert_eq!(d["of"], ts.len() as u64);
    // The unmodified log's replay reads 2999 aligned rows: one sample costs none of them.
    assert_eq!(v["samples_read"], 2999);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("left out by the reader"), "settings row");
    assert!(html.contains("topic `sensor_combined`: 1 of"), "the drop is a warning of the report");
    let _ = std::fs::remove_dir_all(&dir);
}
