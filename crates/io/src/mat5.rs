//! MATLAB level-5 `.mat` reader for real numeric arrays (MathWorks, "MAT-File Format",
//! ch. 1): a 128-byte header whose bytes 126–127 are `IM` (little-endian) or `MI`
//! (big-endian), then data elements of an 8-byte tag (type, byte count; or the "small data
//! element" form, count in the upper 16 bits and up to 4 data bytes in the tag) and their
//! data, padded to 8 bytes except `miCOMPRESSED` (15), a zlib stream holding one element.
//! A variable is a `miMATRIX` (14): array flags (class, complex bit), dimensions, name, real
//! part (any numeric storage type: MATLAB stores doubles that fit as `miUINT8`, …), imaginary
//! part.
//!
//! Every declared size is checked before anything is allocated or inflated for it: a
//! sub-element must fit in its variable, the dimensions' product must equal the real part's
//! byte count over its type's size, and a compressed variable may not declare more bytes
//! than its compressed data can inflate to (deflate expands at most 1032:1). A record decodes
//! at most [`MAX_DECODED_BYTES`] (512 MiB): its values as `f64` are checked against it from
//! the declared dimensions, and what its compressed variables inflate (names and dimensions
//! included) is counted against it before each read, so a 2 MB zlib bomb is refused before
//! it fills gigabytes. Variables of other classes (char, cell, struct, sparse, object) are
//! skipped.
//!
//! Why not the `matfile` crate (0.5): it prints a raw debug struct to stderr on a corrupt
//! zlib stream, answers any corrupt file with "An error occurred while parsing the file",
//! and inflates and allocates whatever the file declares before checking it.

use flate2::read::ZlibDecoder;
use std::io::Read;

/// Most bytes a `.mat` record may decode: its values as `f64`, and separately what its
/// compressed variables inflate to. Well under the 1 GiB the aligned table may hold, as the
/// values are copied once more into the table's columns.
const MAX_DECODED_BYTES: usize = 512 << 20;
/// Most dimensions a variable may declare.
const MAX_DIMS: usize = 32;
/// Longest variable name read (MATLAB's limit is 63 characters).
const MAX_NAME: usize = 4096;
/// Deflate's largest expansion: 1032 output bytes per input byte, plus the stream's slack.
const MAX_INFLATION: usize = 1032;

/// One real numeric variable: name, dimensions, values in column-major order.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MatArray {
    pub(crate) name: String,
    pub(crate) dims: Vec<usize>,
    pub(crate) values: Vec<f64>,
}

/// Bytes of one element of storage type `ty` (`miINT8` … `miUINT64`), `None` for others.
fn type_size(ty: u32) -> Option<usize> {
    Some(match ty {
        1 | 2 => 1,   // miINT8, miUINT8
        3 | 4 => 2,   // miINT16, miUINT16
        5..=7 => 4,   // miINT32, miUINT32, miSINGLE
        9 => 8,       // miDOUBLE
        12 | 13 => 8, // miINT64, miUINT64
        _ => return None,
    })
}

/// Appends the values of `b` (whole elements of storage type `ty`) to `out`.
fn convert(ty: u32, b: &[u8], big: bool, out: &mut Vec<f64>) {
    macro_rules! push {
        ($t:ty, $n:expr) => {
            out.extend(b.chunks_exact($n).map(|c| {
                let a: [u8; $n] = c.try_into().unwrap_or([0; $n]);
                (if big { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
            }))
        };
    }
    match ty {
        1 => push!(i8, 1),
        2 => push!(u8, 1),
        3 => push!(i16, 2),
        4 => push!(u16, 2),
        5 => push!(i32, 4),
        6 => push!(u32, 4),
        7 => push!(f32, 4),
        9 => push!(f64, 8),
        _ => {}
    }
}

/// What a record may still decode, of [`MAX_DECODED_BYTES`] (`cap`, lower in unit tests).
#[derive(Debug, Clone, Copy)]
struct Budget {
    /// Values, as `f64` of 8 bytes each.
    values: usize,
    /// Bytes the compressed variables may still inflate to.
    inflated: usize,
    cap: usize,
}

impl Budget {
    fn new(cap: usize) -> Self {
        Self { values: cap / 8, inflated: cap, cap }
    }
}

/// A reader of one variable's sub-elements.
struct Body<'a, R> {
    r: R,
    big: bool,
    /// Bytes of the variable not yet read.
    left: usize,
    budget: &'a mut Budget,
    /// Whether `r` inflates (its bytes count against [`Budget::inflated`]).
    compressed: bool,
}

impl<R: Read> Body<'_, R> {
    fn bytes(&mut self, n: usize, what: &str) -> Result<Vec<u8>, String> {
        if n > self.left {
            return Err(format!(
                "{what} declares {n} bytes but only {} are left in the variable",
                self.left
            ));
        }
        if self.compressed {
            self.inflate(n, what)?;
        }
        let mut v = Vec::new();
        (&mut self.r).take(n as u64).read_to_end(&mut v).map_err(|e| corrupt(&e, what))?;
        if v.len() < n {
            return Err(format!("{what}: the data ends after {} of its {n} bytes", v.len()));
        }
        self.left -= n;
        Ok(v)
    }

    /// Counts `n` more bytes to inflate against [`Budget::inflated`], before reading them.
    fn inflate(&mut self, n: usize, what: &str) -> Result<(), String> {
        self.budget.inflated = self.budget.inflated.checked_sub(n).ok_or_else(|| {
            format!(
                "{what}: inflating its {n} bytes would take the record's decompressed data past \
                 {} bytes ({} MiB), the most a record may decode",
                self.budget.cap,
                self.budget.cap >> 20
            )
        })?;
        Ok(())
    }

    fn word(&self, b: &[u8]) -> u32 {
        let a: [u8; 4] = b[..4].try_into().unwrap_or([0; 4]);
        if self.big { u32::from_be_bytes(a) } else { u32::from_le_bytes(a) }
    }

    /// A sub-element's tag: `(type, byte count, data of a small element)`.
    fn tag(&mut self, what: &str) -> Result<(u32, usize, Option<Vec<u8>>), String> {
        let t = self.bytes(8, what)?;
        let w0 = self.word(&t);
        let small = if self.big { w0 & 0xffff } else { w0 >> 16 };
        if small != 0 {
            let ty = if self.big { w0 >> 16 } else { w0 & 0xffff };
            let n = small as usize;
            if n > 4 {
                return Err(format!("{what}: a small element declares {n} bytes (at most 4)"));
            }
            return Ok((ty, n, Some(t[4..4 + n].to_vec())));
        }
        Ok((w0, self.word(&t[4..]) as usize, None))
    }

    /// A whole sub-element of at most `max` bytes: `(type, data)`, padding skipped.
    fn element(&mut self, what: &str, max: usize) -> Result<(u32, Vec<u8>), String> {
        let (ty, n, small) = self.tag(what)?;
        if let Some(d) = small {
            return Ok((ty, d));
        }
        if n > max {
            return Err(format!("{what} declares {n} bytes (at most {max})"));
        }
        let d = self.bytes(n, what)?;
        self.pad(n, what)?;
        Ok((ty, d))
    }

    fn pad(&mut self, n: usize, what: &str) -> Result<(), String> {
        let p = n.div_ceil(8) * 8 - n;
        self.bytes(p.min(self.left), what).map(|_| ())
    }
}

fn corrupt(e: &std::io::Error, what: &str) -> String {
    format!("{what}: the compressed data is corrupt ({e})")
}

/// Reads one `miMATRIX` body of `n` bytes from `r` (inflating if `compressed`); `None` for a
/// class that is not a real numeric array. `budget` is what the record may still decode.
fn matrix<R: Read>(
    r: R,
    n: usize,
    big: bool,
    budget: &mut Budget,
    compressed: bool,
) -> Result<Option<MatArray>, String> {
    let mut b = Body { r, big, left: n, budget, compressed };
    let (ty, flags) = b.element("its array flags", 16)?;
    if ty != 6 || flags.len() != 8 {
        return Err(format!("array flags of type {ty} and {} bytes (miUINT32, 8)", flags.len()));
    }
    let w = b.word(&flags);
    let class = w & 0xff;
    let complex = w & 0x800 != 0;
    if !(6..=15).contains(&class) {
        return Ok(None);
    }
    let (ty, d) = b.element("its dimensions", 4 * MAX_DIMS)?;
    if ty != 5 || d.len() < 8 || d.len() % 4 != 0 {
        return Err(format!("dimensions of type {ty} and {} bytes (miINT32, 2 or more)", d.len()));
    }
    let dims: Vec<i64> = d.chunks_exact(4).map(|c| i64::from(b.word(c) as i32)).collect();
    let (ty, name) = b.element("its name", MAX_NAME)?;
    let name = String::from_utf8_lossy(&name).trim_end_matches('\0').to_string();
    let named = |m: String| format!("variable `{name}`: {m}");
    if ty != 1 && ty != 2 {
        return Err(named(format!("name of type {ty} (miINT8)")));
    }
    let shape = dims.iter().map(i64::to_string).collect::<Vec<_>>().join("×");
    if dims.iter().any(|&d| d < 0) {
        return Err(named(format!("negative dimension in {shape}")));
    }
    let cap = b.budget.cap;
    let count = dims
        .iter()
        .try_fold(1usize, |p, &d| p.checked_mul(d as usize))
        .filter(|&c| c <= b.budget.values)
        .ok_or_else(|| {
            named(format!(
                "declared {shape}: more than the {} values ({cap} bytes, {} MiB, as f64) a \
                 record may decode ({} left)",
                cap / 8,
                cap >> 20,
                b.budget.values
            ))
        })?;
    if class == 14 || class == 15 {
        return Err(named("64-bit integer data is not read (not exact in f64)".into()));
    }
    if complex {
        return Err(named("complex data is not read".into()));
    }
    let (ty, bytes, small) = b.tag("its real part").map_err(named)?;
    let size = type_size(ty).ok_or_else(|| named(format!("real part of storage type {ty}")))?;
    if ty == 12 || ty == 13 {
        return Err(named("64-bit integer data is not read (not exact in f64)".into()));
    }
    if count.checked_mul(size) != Some(bytes) {
        return Err(named(format!(
            "declared {shape} ({count} values) but its real part holds {bytes} bytes of \
             {size}-byte values: a corrupt file"
        )));
    }
    if compressed && small.is_none() && bytes > b.budget.inflated {
        return Err(named(format!(
            "its real part declares {bytes} bytes to inflate, past the {cap} bytes ({} MiB) a \
             record may decode ({} left)",
            cap >> 20,
            b.budget.inflated
        )));
    }
    let mut values = Vec::new();
    if let Some(d) = small {
        convert(ty, &d, big, &mut values);
    } else {
        // In chunks: the values grow with the data actually read, never ahead of it.
        let mut left = bytes;
        while left > 0 {
            let k = left.min(1 << 16);
            let chunk = b.bytes(k, "its real part").map_err(named)?;
            convert(ty, &chunk, big, &mut values);
            left -= k;
        }
    }
    b.budget.values -= values.len();
    let dims = dims.into_iter().map(|d| d as usize).collect();
    Ok(Some(MatArray { name, dims, values }))
}

/// The real numeric variables of a level-5 file (module doc), in file order. The header and
/// the top-level element sizes must have been checked (`crate::log::check_mat_elements`).
///
/// # Errors
/// What is wrong, naming the variable (by name, else by number and byte offset).
pub(crate) fn read_arrays(bytes: &[u8]) -> Result<Vec<MatArray>, String> {
    read_arrays_capped(bytes, MAX_DECODED_BYTES)
}

/// [`read_arrays`] decoding at most `cap` bytes (module doc).
fn read_arrays_capped(bytes: &[u8], cap: usize) -> Result<Vec<MatArray>, String> {
    let big = bytes.get(126..128) == Some(b"MI");
    let word = |at: usize| {
        let w: [u8; 4] = bytes[at..at + 4].try_into().unwrap_or([0; 4]);
        if big { u32::from_be_bytes(w) } else { u32::from_le_bytes(w) }
    };
    let mut out: Vec<MatArray> = Vec::new();
    let mut budget = Budget::new(cap);
    let mut at = 128usize;
    let mut k = 0;
    while at + 8 <= bytes.len() {
        let (ty, n) = (word(at), word(at + 4) as usize);
        let body = &bytes[(at + 8).min(bytes.len())..(at + 8).saturating_add(n).min(bytes.len())];
        k += 1;
        let which = |m: String| {
            if m.starts_with("variable `") {
                format!("{m} (element at byte {at})")
            } else {
                format!("variable {k} (element at byte {at}): {m}")
            }
        };
        let array = match ty {
            14 => matrix(body, body.len(), big, &mut budget, false).map_err(which)?,
            15 => compressed(body, big, &mut budget).map_err(which)?,
            _ => None,
        };
        out.extend(array);
        at = at.saturating_add(8).saturating_add(if ty == 15 { n } else { n.div_ceil(8) * 8 });
    }
    Ok(out)
}

/// A `miCOMPRESSED` element: the zlib stream's one element, inflated only as far as its
/// checked sizes allow.
fn compressed(body: &[u8], big: bool, budget: &mut Budget) -> Result<Option<MatArray>, String> {
    let mut z = ZlibDecoder::new(body);
    let mut tag = [0u8; 8];
    let inflated = &mut budget.inflated;
    *inflated = inflated.checked_sub(8).ok_or_else(|| {
        format!("its tag would take the record's decompressed data past {} bytes", budget.cap)
    })?;
    z.read_exact(&mut tag).map_err(|e| corrupt(&e, "its tag"))?;
    let w = |b: &[u8]| {
        let a: [u8; 4] = b.try_into().unwrap_or([0; 4]);
        if big { u32::from_be_bytes(a) } else { u32::from_le_bytes(a) }
    };
    let (ty, n) = (w(&tag[..4]), w(&tag[4..]) as usize);
    if ty != 14 {
        return Ok(None);
    }
    let most = body.len().saturating_mul(MAX_INFLATION).saturating_add(64);
    if n > most {
        return Err(format!(
            "declares {n} bytes, more than its {} compressed bytes can inflate to",
            body.len()
        ));
    }
    matrix(z, n, big, budget, true)
}

/// Builders of level-5 files shared with the integration tests.
#[cfg(test)]
#[path = "../tests/all/common/logs.rs"]
mod test_files;

#[cfg(test)]
mod tests {
    use super::*;
    use test_files::{mat_compressed, mat_file, mat_matrix};

    /// Bytes a compressed 1 × `n` double variable named `name` inflates to as read: the
    /// element's tag, then flags, dimensions, name (padded to 8) and real part, each tagged.
    fn inflated(name: &str, n: usize) -> usize {
        8 + 16 + 16 + 8 + name.len().div_ceil(8) * 8 + 8 + 8 * n
    }

    #[test]
    fn errors_the_decoded_bytes_of_a_record_are_counted_across_its_variables() {
        let cap = 4096;
        // Values: 512 as f64 in all; the second plain variable asks for 300 with 212 left.
        let v = |name: &str| mat_matrix(name, &[300, 1], &[1.0; 300]);
        let e = read_arrays_capped(&mat_file(&[v("a"), v("b")]), cap).unwrap_err();
        assert!(e.starts_with("variable `b`: declared 300×1: more than the 512 values"), "{e}");
        assert!(e.contains("(4096 bytes, 0 MiB, as f64) a record may decode (212 left)"), "{e}");
        // Inflated bytes, declared: a long name leaves too few for the next real part.
        let long = "l".repeat(3000);
        let f = mat_file(&[
            mat_compressed(&mat_matrix(&long, &[1, 1], &[1.0])),
            mat_compressed(&mat_matrix("b", &[150, 1], &[2.0; 150])),
        ]);
        let left = cap - inflated(&long, 1) - (inflated("b", 150) - 8 * 150);
        let e = read_arrays_capped(&f, cap).unwrap_err();
        assert!(
            e.starts_with(&format!(
                "variable `b`: its real part declares 1200 bytes to inflate, past the 4096 \
                 bytes (0 MiB) a record may decode ({left} left)"
            )),
            "{e}"
        );
    }

    #[test]
    fn errors_inflated_names_are_counted_as_they_stream() {
        // Variables of one value and a 1500-byte name: the third's name would pass the cap,
        // though no dimension declares more than a value.
        let cap = 4096;
        let name = |k: usize| format!("{k}{}", "n".repeat(1499));
        let vars: Vec<Vec<u8>> =
            (0..3).map(|k| mat_compressed(&mat_matrix(&name(k), &[1, 1], &[1.0]))).collect();
        assert!(2 * inflated(&name(0), 1) + 8 + 16 + 16 + 8 + 1500 > cap);
        let at = 128 + vars[0].len() + vars[1].len();
        let e = read_arrays_capped(&mat_file(&vars), cap).unwrap_err();
        assert_eq!(
            e,
            format!(
                "variable 3 (element at byte {at}): its name: inflating its 1500 bytes would \
                 take the record's decompressed data past 4096 bytes (0 MiB), the most a \
                 record may decode"
            )
        );
        // Two of them fit and read.
        let a = read_arrays_capped(&mat_file(&vars[..2]), cap).unwrap();
        assert_eq!(a.len(), 2);
        assert_eq!(a[1].values, [1.0]);
    }
}
