//! Builders of small synthetic ULog and DataFlash files for the reader tests (PX4 "ULog File
//! Format"; ArduPilot `LogStructure.h`), independent of the readers under test.
#![allow(dead_code)]

#[path = "log_writers.rs"]
mod log_writers;
#[allow(unused_imports)]
pub use log_writers::{Dataflash, Ulog};

/// A minimal mapping reading `topic.v` as airspeed and `topic.a` as α from an aligned log at
/// `rate_hz`.
pub fn mapping_text(topic: &str, rate_hz: f64) -> String {
    format!(
        "nominal_dt_s = {}\n[time]\ncolumn = \"time_s\"\nunit = \"s\"\n[align]\nrate_hz = {rate_hz:?}\nmethod = \"linear\"\n[channels]\nvt = {{ column = \"{topic}.v\", unit = \"m/s\" }}\nalpha = {{ column = \"{topic}.a\", unit = \"rad\" }}\nmass = {{ value = 1.0, unit = \"kg\" }}\nS = {{ value = 1.0, unit = \"m2\" }}\nrho = {{ value = 1.0, unit = \"kg/m3\" }}\n",
        1.0 / rate_hz
    )
}

/// One miMATRIX element of a MATLAB level-5 file (MathWorks "MAT-File Format", ch. 1):
/// array flags (class double), dimensions `dims` as declared (may disagree with `data`), name,
/// real part as miDOUBLE.
pub fn mat_matrix(name: &str, dims: &[i32], data: &[f64]) -> Vec<u8> {
    let tag = |v: &mut Vec<u8>, ty: u32, n: usize| {
        v.extend(ty.to_le_bytes());
        v.extend(u32::try_from(n).unwrap().to_le_bytes());
    };
    let pad = |v: &mut Vec<u8>| v.resize(v.len().div_ceil(8) * 8, 0);
    let mut m = Vec::new();
    tag(&mut m, 6, 8);
    m.extend(6u32.to_le_bytes());
    m.extend(0u32.to_le_bytes());
    tag(&mut m, 5, 4 * dims.len());
    for d in dims {
        m.extend(d.to_le_bytes());
    }
    pad(&mut m);
    tag(&mut m, 1, name.len());
    m.extend(name.as_bytes());
    pad(&mut m);
    tag(&mut m, 9, 8 * data.len());
    for x in data {
        m.extend(x.to_le_bytes());
    }
    let mut out = Vec::new();
    tag(&mut out, 14, m.len());
    out.extend(m);
    out
}

/// The 128-byte level-5 header (little-endian), then `elements`.
pub fn mat_file(elements: &[Vec<u8>]) -> Vec<u8> {
    let mut out = format!("{:<116}", "MATLAB 5.0 MAT-file, written by a test").into_bytes();
    out.extend([0u8; 8]);
    out.extend(0x0100u16.to_le_bytes());
    out.extend(*b"IM");
    for e in elements {
        out.extend(e);
    }
    out
}

/// `element` as a miCOMPRESSED element (zlib).
pub fn mat_compressed(element: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    z.write_all(element).unwrap();
    let c = z.finish().unwrap();
    let mut out = 15u32.to_le_bytes().to_vec();
    out.extend(u32::try_from(c.len()).unwrap().to_le_bytes());
    out.extend(c);
    out
}

/// One `.tlog` record: the big-endian µs timestamp and the frame the `mavlink` crate writes.
pub fn tlog_record(
    out: &mut Vec<u8>,
    t_us: u64,
    version: mavlink::MavlinkVersion,
    msg: &mavlink::dialects::ardupilotmega::MavMessage,
) {
    out.extend(t_us.to_be_bytes());
    mavlink::write_versioned_msg(out, version, mavlink::MavHeader::default(), msg).unwrap();
}
