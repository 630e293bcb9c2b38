//! The `.mat` reader against corrupt dimensions, corrupt zlib streams and declared sizes no
//! file can back: a clear error naming the file and the variable, found before inflating or
//! allocating what the file declares.

#[path = "common/logs.rs"]
mod logs;

use aeroident_io::log::read_mat;
use logs::{mat_compressed, mat_file, mat_matrix};
use std::time::Instant;

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
    let f = mat_file(&[mat_compressed(&inner)]);
    let started = Instant::now();
    let e = read(&f).unwrap_err();
    assert!(started.elapsed().as_secs_f64() < 5.0);
    assert!(e.contains("more than its") && e.contains("compressed bytes can inflate to"), "{e}");
}
