//! Builders of small synthetic ULog and DataFlash files for the reader tests (PX4 "ULog File
//! Format"; ArduPilot `LogStructure.h`), independent of the readers under test.
#![allow(dead_code)]

/// A ULog file being written: header, then messages `u16 size, u8 type, payload`.
pub struct Ulog(pub Vec<u8>);

impl Ulog {
    /// Header (magic, version 1, start time 1 s) and a flag-bits message with no flags.
    pub fn new() -> Self {
        let mut b = vec![0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01];
        b.extend_from_slice(&1_000_000u64.to_le_bytes());
        let mut u = Ulog(b);
        u.msg(b'B', &[0u8; 40]);
        u
    }

    pub fn msg(&mut self, kind: u8, payload: &[u8]) -> &mut Self {
        self.0.extend_from_slice(&u16::try_from(payload.len()).unwrap().to_le_bytes());
        self.0.push(kind);
        self.0.extend_from_slice(payload);
        self
    }

    /// `F` message: `name:type field;…`.
    pub fn format(&mut self, text: &str) -> &mut Self {
        self.msg(b'F', text.as_bytes())
    }

    /// `A` message: instance `multi`, `msg_id` `id`, format `name`.
    pub fn subscribe(&mut self, multi: u8, id: u16, name: &str) -> &mut Self {
        let mut p = vec![multi];
        p.extend_from_slice(&id.to_le_bytes());
        p.extend_from_slice(name.as_bytes());
        self.msg(b'A', &p)
    }

    /// `D` message of `id`: timestamp then the `f32` fields in order.
    pub fn data_f32(&mut self, id: u16, t_us: u64, fields: &[f32]) -> &mut Self {
        let mut p = id.to_le_bytes().to_vec();
        p.extend_from_slice(&t_us.to_le_bytes());
        for f in fields {
            p.extend_from_slice(&f.to_le_bytes());
        }
        self.msg(b'D', &p)
    }
}

/// A DataFlash file being written: `A3 95 type payload` messages.
pub struct Dataflash(pub Vec<u8>);

impl Dataflash {
    /// Starts with the `FMT` of `FMT`.
    pub fn new() -> Self {
        let mut d = Dataflash(Vec::new());
        d.fmt(128, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns");
        d
    }

    /// An `FMT` message defining type `id`, message length `len` (header included).
    pub fn fmt(&mut self, id: u8, len: u8, name: &str, chars: &str, cols: &str) -> &mut Self {
        self.0.extend_from_slice(&[0xA3, 0x95, 128, id, len]);
        for (s, w) in [(name, 4), (chars, 16), (cols, 64)] {
            let mut v = s.as_bytes().to_vec();
            v.resize(w, 0);
            self.0.extend_from_slice(&v);
        }
        self
    }

    /// A message of type `id` with `payload`.
    pub fn msg(&mut self, id: u8, payload: &[u8]) -> &mut Self {
        self.0.extend_from_slice(&[0xA3, 0x95, id]);
        self.0.extend_from_slice(payload);
        self
    }
}

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
