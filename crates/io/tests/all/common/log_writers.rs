//! Writers of small synthetic ULog and DataFlash files (PX4 "ULog File Format"; ArduPilot
//! `LogStructure.h`), independent of the readers under test. Free of dependencies, so that the
//! other crates' tests include it with `#[path]` to write logs for their own stages.
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
