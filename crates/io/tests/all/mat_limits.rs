//! The `.mat` reader against corrupt dimensions, corrupt zlib streams and declared sizes no
//! file can back: a clear error naming the file and the variable, found before inflating or
//! allocating what the file declares.

use crate::common::logs;

use aeroident_io::log::read_mat;
use logs::{mat_compressed, mat_file, mat_matrix};

fn read(bytes: &[u8]) -> Result<aeroident_io::table::Table, String> {
    read_mat(bytes, "r.mat", None).map_err(|e| e.to_string())
}

#[test]
fn val_compressed_and_plain_variables_read_alike() {
    let data: Vec<f64> = (0..12).map(|i| f64::from(i) * 0.5).collect();
    let plain = mat_matrix("rec", &[4, 3], &data);
    for f in [mat_file(std::slice::from_ref(&plain)), mat_file(&[mat_compressed(&plain)])] {
        let t = read(&f).unwrap();
        assert_eq!(t.names, ["1", "2", "3"]);
        assert_eq!(t.columns[2], data[8..12]);
    }
}

#[test]
fn errors_corrupt_dimensions_name_the_variable_and_the_declared_shape() {
    let data = [1.0; 12];
    for wrap in [false, true] {
        let m = mat_matrix("rec", &[4, 300_000], &data);
        let f = mat_file(&[if wrap { mat_compressed(&m) } else { m }]);
        let e = read(&f).unwrap_err();
        assert!(e.starts_with("r.mat: variable `rec`: declared 4×300000"), "{e}");
        assert!(e.contains("its real part holds 96 bytes"), "{e}");
        let m = mat_matrix("rec", &[-4, 3], &data);
        let e = read(&mat_file(&[if wrap { mat_compressed(&m) } else { m }])).unwrap_err();
        assert!(e.contains("variable `rec`: negative dimension in -4×3"), "{e}");
    }
    // A product past the cap (65535⁴ values): refused from the dimensions alone.
    let m = mat_matrix("big", &[65535, 65535, 65535, 65535], &data);
    let e = read(&mat_file(&[mat_compressed(&m)])).unwrap_err();
    assert!(e.contains("variable `big`: declared 65535×65535×65535×65535: more than"), "{e}");
}

#[test]
fn errors_a_corrupt_zlib_stream_is_named_without_debug_output() {
    let m = mat_matrix("rec", &[4, 3], &[2.0; 12]);
    let mut c = mat_compressed(&m);
    let n = c.len();
    for b in &mut c[8 + 2..n - 4] {
        *b ^= 0x5a;
    }
    let e = read(&mat_file(&[c])).unwrap_err();
    assert!(e.starts_with("r.mat: variable 1 (element at byte 128): "), "{e}");
    assert!(e.contains("compressed data is corrupt") || e.contains("the data ends"), "{e}");
}

#[test]
fn errors_a_small_file_declaring_gigabytes_fails_before_inflating_them() {
    // 2 GB of zeros declared, ~1 MB of zlib: the real part's size is what the dimensions say,
    // so the declared byte count of the whole variable cannot be backed by the stream.
    let mut inner = mat_matrix("z", &[16384, 16384], &[]);
    // The variable claims 2 GiB of data (the miDOUBLE tag's count and the element's).
    let real_tag = inner.len() - 8;
    inner[real_tag + 4..real_tag + 8].copy_from_slice(&(16384u32 * 16384 * 8).to_le_bytes());
    let total = (inner.len() - 8) as u64 + 16384 * 16384 * 8;
    inner[4..8].copy_from_slice(&(total as u32).to_le_bytes());
    inner.resize(inner.len() + 8 * 1024 * 1024, 0); // 8 MB of real zeros compress to ~8 kB
    let compressed = mat_compressed(&inner);
    let f = mat_file(std::slice::from_ref(&compressed));
    let e = read(&f).unwrap_err();
    // The declared-size check's own words, with the declared count and the stream's length
    // (the element less its 8-byte tag): the refusal came before inflating, not from running
    // out of data or memory after it.
    let want = format!(
        "r.mat: variable 1 (element at byte 128): declares {total} bytes, more than its {} compressed bytes can inflate to",
        compressed.len() - 8
    );
    assert_eq!(e, want);
}

/// A zlib stream (RFC 1950/1951) of `head` followed by `repeats` × `chunk` zero bytes, made
/// without compressing the zeros `repeats` times: `chunk` zeros deflated once by a fresh
/// compressor and flushed to a byte boundary only refer back to zeros, so the same bytes
/// repeated inflate to zeros again. An empty final block and the Adler-32 close it.
fn zero_bomb(head: &[u8], chunk: usize, repeats: usize) -> Vec<u8> {
    use std::io::Write;
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    z.write_all(head).unwrap();
    z.flush().unwrap();
    let mut out = z.get_ref().clone();
    let mut d = flate2::write::DeflateEncoder::new(Vec::new(), flate2::Compression::best());
    d.write_all(&vec![0u8; chunk]).unwrap();
    d.flush().unwrap();
    for _ in 0..repeats {
        out.extend_from_slice(d.get_ref());
    }
    out.extend([0x03, 0x00]); // final fixed-Huffman block holding only end-of-block
    // Adler-32: zeros leave the byte sum `a` alone and add it to `b` once per byte.
    let m = 65_521u64;
    let (mut a, mut b) = (1u64, 0u64);
    for &x in head {
        a = (a + u64::from(x)) % m;
        b = (b + a) % m;
    }
    b = (b + (chunk as u64 * repeats as u64 % m) * a) % m;
    out.extend(((b << 16 | a) as u32).to_be_bytes());
    out
}

/// `stream` as a miCOMPRESSED element.
fn compressed_element(stream: &[u8]) -> Vec<u8> {
    let mut out = 15u32.to_le_bytes().to_vec();
    out.extend(u32::try_from(stream.len()).unwrap().to_le_bytes());
    out.extend_from_slice(stream);
    out
}

/// The head of a double `rows` × `cols` variable `name` whose real part declares `zeros`
/// bytes (all of which follow the head in a zero bomb).
fn zero_matrix_head(name: &str, rows: i32, cols: i32, zeros: usize) -> Vec<u8> {
    let mut m = mat_matrix(name, &[rows, cols], &[]);
    let real_tag = m.len() - 8;
    m[real_tag + 4..real_tag + 8].copy_from_slice(&u32::try_from(zeros).unwrap().to_le_bytes());
    let total = m.len() - 8 + zeros;
    m[4..8].copy_from_slice(&u32::try_from(total).unwrap().to_le_bytes());
    m
}

#[test]
fn val_the_zero_bomb_builder_inflates_to_what_it_declares() {
    let head = zero_matrix_head("z", 3000, 2, 3 * 16_000);
    let stream = zero_bomb(&head, 16_000, 3);
    let mut all = Vec::new();
    std::io::Read::read_to_end(&mut flate2::read::ZlibDecoder::new(&stream[..]), &mut all).unwrap();
    assert_eq!(all.len(), head.len() + 3 * 16_000);
    assert_eq!(all[..head.len()], head);
    assert!(all[head.len()..].iter().all(|&x| x == 0));
    let t = read(&mat_file(&[compressed_element(&stream)])).unwrap();
    assert_eq!(t.names, ["1", "2"]);
    assert_eq!(t.columns, [vec![0.0; 3000], vec![0.0; 3000]]);
}

#[test]
fn errors_a_zlib_bomb_of_gigabytes_is_refused_from_its_dimensions_before_inflating() {
    // The probe's file: ~1.9 MB of zlib inflating to a 12e6 × 20 double matrix (1.92 GB),
    // within the 1032:1 deflate can expand and the 2²⁸ values once allowed.
    let zeros = 12_000_000 * 20 * 8;
    let head = zero_matrix_head("bomb", 12_000_000, 20, zeros);
    let stream = zero_bomb(&head, zeros / 2000, 2000);
    assert!(stream.len() * 1032 > zeros && stream.len() < 2_000_000, "{}", stream.len());
    let e = read(&mat_file(&[compressed_element(&stream)])).unwrap_err();
    assert!(e.starts_with("r.mat: variable `bomb`: declared 12000000×20: more than"), "{e}");
    assert!(e.contains("536870912 bytes, 512 MiB, as f64) a record may decode"), "{e}");
}
