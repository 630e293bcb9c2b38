//! Output files against what the file system holds: nodes that are not regular files stay
//! what they were, inputs named by another path are not overwritten, two outputs in one file
//! are refused, and a write leaves the bytes and nothing else.

use super::*;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aeroident-outfile-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    fs::create_dir_all(&d).unwrap();
    d
}

#[cfg(unix)]
fn is_char_device(p: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    fs::metadata(p).unwrap().file_type().is_char_device()
}

#[cfg(unix)]
#[test]
fn a_device_node_is_refused_and_left_as_it_is() {
    let null = Path::new("/dev/null");
    let e = check_outputs(&[("--out", null)], &[]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "--out `/dev/null` is a character device, not a regular file: it is not replaced; give a file path"
    );
    let e = write_file("--out", null, b"x").unwrap_err();
    assert!(matches!(e, OutputFileError::NotRegular { kind: "a character device", .. }), "{e}");
    assert!(is_char_device(null));
}

#[cfg(unix)]
#[test]
fn a_fifo_and_a_directory_are_refused_and_left_as_they_are() {
    use std::os::unix::fs::FileTypeExt;
    let d = scratch("fifo");
    let fifo = d.join("pipe");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let e = write_file("--json", &fifo, b"{}").unwrap_err();
    assert!(e.to_string().contains("is a FIFO (named pipe), not a regular file"), "{e}");
    assert!(fs::metadata(&fifo).unwrap().file_type().is_fifo());
    let e = check_outputs(&[("--html", &d)], &[]).unwrap_err();
    assert!(e.to_string().contains("is a directory"), "{e}");
    // A link to a device is the device.
    let link = d.join("null-link");
    std::os::unix::fs::symlink("/dev/null", &link).unwrap();
    assert!(matches!(
        write_file("--out", &link, b"x"),
        Err(OutputFileError::NotRegular { kind: "a character device", .. })
    ));
    assert!(is_char_device(Path::new("/dev/null")));
    fs::remove_dir_all(&d).unwrap();
}

#[test]
fn an_input_named_by_another_path_is_not_overwritten() {
    let d = scratch("input");
    fs::create_dir_all(d.join("sub")).unwrap();
    let log = d.join("x.csv");
    fs::write(&log, "t,q\n0,1\n").unwrap();
    let other = d.join("sub").join("..").join("x.csv");
    let e = check_outputs(&[("--json", &other)], &[("the log", &log)]).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "--json `{}` is this run's the log `{}`: it is not overwritten; give another file",
            other.display(),
            log.display()
        )
    );
    #[cfg(unix)]
    {
        let hard = d.join("hard.csv");
        fs::hard_link(&log, &hard).unwrap();
        let e = check_outputs(&[("--out", &hard)], &[("--summary", &log)]).unwrap_err();
        assert!(matches!(e, OutputFileError::Input { .. }), "{e}");
    }
    assert_eq!(fs::read_to_string(&log).unwrap(), "t,q\n0,1\n");
    // Another file beside it is fine.
    check_outputs(&[("--json", &d.join("x.json"))], &[("the log", &log)]).unwrap();
    fs::remove_dir_all(&d).unwrap();
}

#[test]
fn two_outputs_in_one_file_are_refused_whether_it_exists_or_not() {
    let d = scratch("same");
    let a = d.join("f");
    let b = d.join("sub-missing").join("..").join("f");
    fs::create_dir_all(d.join("sub-missing")).unwrap();
    let e = check_outputs(&[("--json", &a), ("--html", &b)], &[]).unwrap_err();
    assert!(matches!(e, OutputFileError::Same { .. }), "{e}");
    assert!(e.to_string().starts_with("--json `"), "{e}");
    fs::write(&a, "old").unwrap();
    assert!(check_outputs(&[("--json", &a), ("--html", &b)], &[]).is_err());
    check_outputs(&[("--json", &a), ("--html", &d.join("g"))], &[]).unwrap();
    fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_write_leaves_the_bytes_and_no_temporary_file() {
    let d = scratch("write");
    let f = d.join("out.xml");
    fs::write(&f, "old, longer than the new").unwrap();
    write_file("--out", &f, b"new").unwrap();
    assert_eq!(fs::read_to_string(&f).unwrap(), "new");
    let names: Vec<String> = fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into())
        .collect();
    assert_eq!(names, vec!["out.xml".to_string()]);
    // A renderer that fails leaves no file and names the target.
    let png = d.join("plot.png");
    let e = write_file_with("--out", &png, |tmp: &Path| {
        assert_eq!(tmp.extension().unwrap(), "png");
        fs::write(tmp, "partial").unwrap();
        Err("the renderer failed")
    })
    .unwrap_err();
    assert_eq!(e.to_string(), format!("writing `{}`: the renderer failed", png.display()));
    let names: Vec<String> = fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into())
        .collect();
    assert_eq!(names, vec!["out.xml".to_string()]);
    fs::remove_dir_all(&d).unwrap();
}

#[cfg(unix)]
#[test]
fn a_link_to_a_file_is_followed_and_kept() {
    let d = scratch("link");
    let real = d.join("real.json");
    fs::write(&real, "old").unwrap();
    let link = d.join("link.json");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    write_file("--json", &link, b"new").unwrap();
    assert!(fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert_eq!(fs::read_to_string(&real).unwrap(), "new");
    fs::remove_dir_all(&d).unwrap();
}
