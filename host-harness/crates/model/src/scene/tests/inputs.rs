//! The doors a scene opens to other files (issue 27): its URDF read through the one reader
//! (regular files only, a cap), and a `robot.joints` list longer than the chain refused by name
//! (it panicked: index out of bounds).

use super::*;
use std::path::PathBuf;

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes")
}

fn two_link() -> String {
    std::fs::read_to_string(scenes().join("robot_two_link.toml")).unwrap()
}

/// Parses `text` as if it were a file in `dir` (so `urdf` resolves there).
fn parse_in(dir: &Path, text: &str) -> Result<Scene, SceneError> {
    parse(text, &dir.join("scene.toml").display().to_string())
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("flinch-model-inputs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn joints_longer_than_the_chain_are_refused_by_name() {
    let text = two_link();
    for list in ["[0.3, 1.2, 0.5]", "[0.3, 1.2, 0.5, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]"] {
        let t = text.replace("joints = { shoulder = 0.3, elbow = 1.2 }", &format!("joints = {list}"));
        assert_ne!(t, text);
        let e = parse_in(&scenes(), &t).unwrap_err().to_string();
        assert!(e.contains("robot.joints: has ") && e.contains("the chain \"base\" -> \"tip\" has 2 moving joints (shoulder, elbow)"), "{e}");
    }
    let t = text.replace("joints = { shoulder = 0.3, elbow = 1.2 }", "joints = { shoulder = 0.3, elbow = 1.2, wrist = 0.1 }");
    let e = parse_in(&scenes(), &t).unwrap_err().to_string();
    assert!(e.contains("\"wrist\" is not a moving joint"), "{e}");
}

#[cfg(unix)]
#[test]
fn a_urdf_that_is_not_a_regular_file_is_refused_at_once() {
    let d = tmp("fifo");
    let fifo = d.join("robot.urdf");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    // Blocked forever before: nobody writes the FIFO. A watchdog fails the test instead of hanging.
    let (tx, rx) = std::sync::mpsc::channel();
    let text = two_link().replace("robots/two_link.urdf", "robot.urdf");
    let d2 = d.clone();
    std::thread::spawn(move || {
        let _ = tx.send(parse_in(&d2, &text).map(|_| ()).unwrap_err().to_string());
    });
    let e = rx.recv_timeout(std::time::Duration::from_secs(10)).expect("reading a FIFO URDF must not block");
    assert!(e.contains("robot.urdf: cannot read the URDF") && e.contains("is not a regular file (a FIFO)"), "{e}");
    for (dev, what) in [("/dev/zero", "a character device"), ("/dev/urandom", "a character device")] {
        let t = two_link().replace("robots/two_link.urdf", dev);
        let e = parse_in(&d, &t).unwrap_err().to_string();
        assert!(e.contains(what), "{e}");
    }
    let t = two_link().replace("robots/two_link.urdf", d.to_str().unwrap());
    let e = parse_in(&d, &t).unwrap_err().to_string();
    assert!(e.contains("is a directory"), "{e}");
}

#[test]
fn a_urdf_over_its_cap_is_refused_before_it_is_read() {
    let d = tmp("cap");
    let f = std::fs::File::create(d.join("big.urdf")).unwrap();
    f.set_len(3 << 30).unwrap(); // sparse: 3 GiB said, nothing on disk
    let t = two_link().replace("robots/two_link.urdf", "big.urdf");
    let e = parse_in(&d, &t).unwrap_err().to_string();
    assert!(e.contains("3221225472 bytes; a URDF is at most 16 MiB"), "{e}");
}
