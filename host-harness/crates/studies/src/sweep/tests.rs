//! The sweep's unit tests.

use super::{axis::*, template::*, grid::*};


#[test]
fn linear_and_log_values_hit_both_ends() {
    let a = Axis::parse("motion.speed=0.01:0.3:30", false).unwrap();
    let v = a.values();
    assert_eq!(v.len(), 30);
    assert_eq!((v[0], v[29]), (0.01, 0.3));
    let l = Axis::parse("target.stiffness=log:1e3:1e5:3", false).unwrap();
    let v = l.values();
    assert_eq!(v[0], 1e3);
    assert!((v[1] - 1e4).abs() < 1e-6);
    assert_eq!(v[2], 1e5);
    assert_eq!(Axis::parse("target.stiffness=1e3:1e5:3", true).unwrap().spacing, Spacing::Log);
}

#[test]
fn edit_distance() {
    assert_eq!(distance("speed", "sped"), 1);
    assert_eq!(distance("", "abc"), 3);
    assert_eq!(close_matches("motion.sped", &["motion.speed".into(), "motion.decel".into(), "tool.mass".into()]), vec!["motion.speed".to_string()]);
}

/// A point's spliced text is the text the edited document prints, for every shipped scene
/// and a number of every kind (float, integer kept whole, integer made fractional, an array
/// element), so the fast path validates exactly what the slow one did.
#[test]
fn spliced_text_is_the_edited_documents_text() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes");
    let mut checked = 0;
    for e in std::fs::read_dir(&dir).unwrap().flatten() {
        let path = e.path();
        if path.extension().is_none_or(|x| x != "toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let Ok(t) = Template::from_text(&text, "x.toml") else { continue };
        assert!(t.text.is_some(), "{}: the document does not print back its text", path.display());
        let keys = t.numeric_keys();
        for key in &keys {
            for x in [0.25, 3.0, 1e-7, 12345.678] {
                let plan = t.splice_plan(&[key.as_str()]).unwrap_or_else(|| panic!("{}: {key}", path.display()));
                let mut doc = t.doc.clone();
                assert!(set(&mut doc, key, x));
                assert_eq!(t.spliced(&plan, &[x]), doc.to_string(), "{}: {key} = {x}", path.display());
                checked += 1;
            }
        }
        if keys.len() >= 2 {
            let (a, b) = (keys[keys.len() - 1].as_str(), keys[0].as_str());
            let plan = t.splice_plan(&[a, b]).unwrap();
            let mut doc = t.doc.clone();
            assert!(set(&mut doc, a, 0.5) && set(&mut doc, b, 7.0));
            assert_eq!(t.spliced(&plan, &[0.5, 7.0]), doc.to_string(), "{}: {a}, {b}", path.display());
        }
    }
    assert!(checked > 1000, "{checked}");
}

#[test]
fn grid_is_row_major() {
    assert_eq!(grid_index(&[2, 3], 0), vec![0, 0]);
    assert_eq!(grid_index(&[2, 3], 2), vec![0, 2]);
    assert_eq!(grid_index(&[2, 3], 3), vec![1, 0]);
}

/// Issue 27: the streamed sweep writes the same bytes as the in-memory one, with refused points
/// (and a first point refused, so rows wait for the header) and on 1 and 2 threads; blocks keep
/// grid order.
#[test]
fn streamed_rows_are_the_in_memory_csv_byte_for_byte() {
    let text = std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes/table1_rigid_tool.toml")).unwrap();
    let t = Template::from_text(&text, "table1_rigid_tool.toml").unwrap();
    // tool.mass from -0.1 (refused) up: the first points are refused rows.
    let axes = || vec![Axis::parse("tool.mass=-0.1:1:300", false).unwrap()];
    let whole = Sweep::keep_going(&t, axes()).unwrap().run(Progress::Hidden);
    assert!(whole.refused() > 0 && whole.points[0].status == Status::Refused);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let mut out = Vec::new();
        let mut w = super::table::RowWriter::new(&mut out, &axes());
        let st = super::stream::stream(&t, axes(), false, Progress::Hidden, Some(&pool), &mut |p| w.push(p)).unwrap().unwrap();
        w.finish().unwrap();
        drop(w);
        assert_eq!((st.done, st.total, st.refused), (300, 300, whole.refused()));
        assert_eq!(String::from_utf8(out).unwrap(), whole.csv(), "{threads} threads");
    }
    // --strict: refused before any point runs.
    let e = super::stream::stream(&t, axes(), true, Progress::Hidden, None, &mut |_| panic!("a point ran")).unwrap_err();
    assert!(e.0.contains("points refused; the first:"), "{e}");
}
