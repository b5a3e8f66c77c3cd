//! Tests of output directories.

use super::*;

fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    list_entries(dir)
        .unwrap()
        .into_iter()
        .filter(|(_, k)| matches!(k, Entry::File))
        .map(|(r, _)| (r.clone(), std::fs::read(dir.join(&r)).unwrap()))
        .collect()
}

#[test]
fn new_directory_appears_only_on_commit() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("run");
    let o = OutputDir::create(&out, false).unwrap();
    std::fs::write(o.path().join("a.csv"), "1").unwrap();
    assert!(!out.exists());
    o.commit().unwrap();
    assert_eq!(std::fs::read(out.join("a.csv")).unwrap(), b"1");
    assert!(out.join(MANIFEST_FILE).exists());
    // Dropped without commit: nothing changes, no staging left.
    let o = OutputDir::create(&out, true).unwrap();
    std::fs::write(o.path().join("a.csv"), "2").unwrap();
    drop(o);
    assert_eq!(std::fs::read(out.join("a.csv")).unwrap(), b"1");
    assert_eq!(std::fs::read_dir(t.path()).unwrap().count(), 1);
}

#[test]
fn refuses_files_links_and_full_directories() {
    let t = tempfile::tempdir().unwrap();
    let f = t.path().join("file");
    std::fs::write(&f, "x").unwrap();
    let e = OutputDir::create(&f, true).unwrap_err().to_string();
    assert!(e.contains("is a file"), "{e}");
    let l = t.path().join("link");
    std::os::unix::fs::symlink(t.path(), &l).unwrap();
    let e = OutputDir::create(&l, true).unwrap_err().to_string();
    assert!(e.contains("symbolic link"), "{e}");
    let d = t.path().join("d");
    std::fs::create_dir(&d).unwrap();
    std::fs::write(d.join("measurements.csv"), "m").unwrap();
    let e = OutputDir::create(&d, false).unwrap_err().to_string();
    assert!(e.contains("a run directory (measurements.csv)"), "{e}");
    assert!(e.contains("--force"), "{e}");
}

#[test]
fn force_keeps_foreign_files_and_refuses_to_replace_them() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path().join("d");
    std::fs::create_dir(&d).unwrap();
    std::fs::write(d.join("measurements.csv"), "measured").unwrap();
    std::fs::write(d.join("notes.txt"), "mine").unwrap();
    let before = tree(&d);
    let o = OutputDir::create(&d, true).unwrap();
    std::fs::write(o.path().join("measurements.csv"), "simulated").unwrap();
    let e = o.commit().unwrap_err().to_string();
    assert!(e.contains("measurements.csv would be replaced"), "{e}");
    assert_eq!(tree(&d), before);
    // Writing other names keeps both foreign files.
    let o = OutputDir::create(&d, true).unwrap();
    std::fs::write(o.path().join("report.json"), "{}").unwrap();
    o.commit().unwrap();
    let after = tree(&d);
    assert_eq!(after["measurements.csv"], b"measured");
    assert_eq!(after["notes.txt"], b"mine");
    assert_eq!(after["report.json"], b"{}");
}

#[test]
fn force_replaces_own_files_drops_stale_ones_and_extends_logs() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path().join("d");
    let o = OutputDir::create(&d, false).unwrap();
    std::fs::write(o.path().join("truth.json"), "t").unwrap();
    std::fs::write(o.path().join("m.csv"), "1").unwrap();
    std::fs::write(o.path().join("raw.bin"), "ab").unwrap();
    o.commit().unwrap();
    let mut o = OutputDir::create(&d, true).unwrap();
    o.appends("raw.bin");
    std::fs::write(o.path().join("m.csv"), "2").unwrap();
    std::fs::write(o.path().join("raw.bin"), "abc").unwrap();
    o.commit().unwrap();
    let after = tree(&d);
    assert_eq!(after["m.csv"], b"2");
    assert_eq!(after["raw.bin"], b"abc");
    assert!(!after.contains_key("truth.json"));
    // A raw log that does not extend the old one is refused.
    let mut o = OutputDir::create(&d, true).unwrap();
    o.appends("raw.bin");
    std::fs::write(o.path().join("raw.bin"), "xyz").unwrap();
    let e = o.commit().unwrap_err().to_string();
    assert!(e.contains("append-only"), "{e}");
    assert_eq!(tree(&d), after);
    // A command that does not write the log keeps it.
    let o = OutputDir::create(&d, true).unwrap();
    std::fs::write(o.path().join("m.csv"), "3").unwrap();
    o.commit().unwrap();
    assert_eq!(tree(&d)["raw.bin"], b"abc");
}

#[test]
fn symlinks_inside_out_are_moved_not_followed() {
    let t = tempfile::tempdir().unwrap();
    let outside = t.path().join("outside.csv");
    std::fs::write(&outside, "precious").unwrap();
    let d = t.path().join("d");
    std::fs::create_dir(&d).unwrap();
    std::os::unix::fs::symlink(&outside, d.join("measurements.csv")).unwrap();
    let o = OutputDir::create(&d, true).unwrap();
    std::fs::write(o.path().join("measurements.csv"), "new").unwrap();
    assert!(o.commit().is_err());
    let o = OutputDir::create(&d, true).unwrap();
    std::fs::write(o.path().join("other.csv"), "new").unwrap();
    o.commit().unwrap();
    assert_eq!(std::fs::read(&outside).unwrap(), b"precious");
    assert!(d
        .join("measurements.csv")
        .symlink_metadata()
        .unwrap()
        .file_type()
        .is_symlink());
}

#[test]
fn a_file_that_appears_in_a_new_out_is_never_replaced() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("run");
    std::fs::create_dir(&out).unwrap();
    let o = OutputDir::create(&out, false).unwrap();
    std::fs::write(o.path().join("measurements.csv"), "simulated").unwrap();
    // Another writer puts a file into the empty --out meanwhile.
    std::fs::write(out.join("imported.csv"), "theirs").unwrap();
    let e = o.commit().unwrap_err().to_string();
    assert!(e.contains("appeared") && e.contains("imported.csv"), "{e}");
    assert_eq!(std::fs::read(out.join("imported.csv")).unwrap(), b"theirs");
    assert!(!out.join("measurements.csv").exists());
    let left: Vec<_> = std::fs::read_dir(t.path()).unwrap().collect();
    assert_eq!(left.len(), 1, "no staging, backup or lock left");
}

#[test]
fn a_file_that_appears_in_a_forced_out_is_never_deleted() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("run");
    let o = OutputDir::create(&out, false).unwrap();
    std::fs::write(o.path().join("a.csv"), "1").unwrap();
    o.commit().unwrap();
    let o = OutputDir::create(&out, true).unwrap();
    std::fs::write(o.path().join("a.csv"), "2").unwrap();
    // Written after the merge's snapshot would be taken, before commit.
    std::fs::write(out.join("late.txt"), "theirs").unwrap();
    o.commit().unwrap();
    // late.txt existed at the merge (it ran at commit): kept.
    assert_eq!(std::fs::read(out.join("late.txt")).unwrap(), b"theirs");
    assert_eq!(std::fs::read(out.join("a.csv")).unwrap(), b"2");
}

#[test]
fn a_second_command_on_the_same_out_is_refused_while_the_first_runs() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("run");
    let first = OutputDir::create(&out, false).unwrap();
    let lock = lock_path(&out);
    assert!(lock.exists());
    // flock locks belong to the open file: a second open is refused.
    let e = OutputDir::create(&out, false).unwrap_err().to_string();
    assert!(
        e.contains("another Plinth command") && e.contains("process"),
        "{e}"
    );
    std::fs::write(first.path().join("a.csv"), "1").unwrap();
    first.commit().unwrap();
    assert!(!lock.exists(), "the lock file is removed");
    let second = OutputDir::create(&out, true).unwrap();
    drop(second);
    assert_eq!(std::fs::read_dir(t.path()).unwrap().count(), 1);
}

#[test]
fn out_dot_and_read_only_outputs_are_clear_errors_that_leave_nothing() {
    use std::os::unix::fs::PermissionsExt;
    let t = tempfile::tempdir().unwrap();
    let cwd = std::env::current_dir().unwrap();
    let e = OutputDir::create(&cwd, true).unwrap_err().to_string();
    assert!(e.contains("current directory"), "{e}");
    let e = OutputDir::create(Path::new("."), false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("current directory"), "{e}");
    // `a/..` resolves to the parent, a real name.
    let sub = t.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    let o = OutputDir::create(&sub.join("x/../y"), false).unwrap();
    std::fs::write(o.path().join("a.csv"), "1").unwrap();
    assert_eq!(o.commit().unwrap(), sub.canonicalize().unwrap().join("y"));
    // Read-only --out with --force: refused before anything is written.
    let ro = t.path().join("ro");
    let o = OutputDir::create(&ro, false).unwrap();
    std::fs::write(o.path().join("a.csv"), "1").unwrap();
    o.commit().unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    let r = OutputDir::create(&ro, true);
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    let root = std::fs::metadata("/proc/self").is_ok_and(|_| {
        std::fs::read_to_string("/proc/self/status").is_ok_and(|s| {
            s.lines()
                .any(|l| l.starts_with("Uid:") && l.split_whitespace().nth(1) == Some("0"))
        })
    });
    if !root {
        let e = r.unwrap_err().to_string();
        assert!(e.contains("read-only"), "{e}");
    }
    let names: BTreeSet<String> = std::fs::read_dir(t.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["ro", "sub"].map(String::from).into());
}

#[test]
fn a_commit_killed_after_its_swap_is_completed_by_the_next_command() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("run");
    let o = OutputDir::create(&out, false).unwrap();
    std::fs::write(o.path().join("a.csv"), "1").unwrap();
    o.commit().unwrap();
    std::fs::write(out.join("mine.txt"), "user").unwrap();
    // What a kill after the second rename leaves: the merged new
    // directory in place and the old one aside.
    let dead = 4_000_000u32; // above pid_max: never running
    let backup = sibling(&out, "plinth-old", dead);
    let copy = |from: &Path, to: &Path| {
        std::fs::create_dir(to).unwrap();
        for e in std::fs::read_dir(from).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    };
    copy(&out, &backup);
    std::fs::write(out.join("a.csv"), "2").unwrap();
    let notes = clean_leftovers(&out);
    assert!(notes[0].contains("already merged"), "{notes:?}");
    assert!(!backup.exists());
    // A backup holding something the new directory lacks is kept.
    copy(&out, &backup);
    std::fs::write(backup.join("only-here.txt"), "x").unwrap();
    let notes = clean_leftovers(&out);
    assert!(notes[0].contains("only-here.txt"), "{notes:?}");
    assert!(backup.join("only-here.txt").exists());
}

#[test]
fn a_commit_killed_while_removing_the_previous_directory_leaves_nothing_behind() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("run");
    for n in ["1", "2"] {
        let o = OutputDir::create(&out, true).unwrap();
        std::fs::write(o.path().join("a.csv"), n).unwrap();
        o.commit().unwrap();
    }
    // A completed commit leaves no backup nor trash.
    let siblings = |dir: &Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".run."))
            .collect()
    };
    assert!(siblings(t.path()).is_empty(), "{:?}", siblings(t.path()));
    // What a kill in the middle of the removal leaves: the renamed backup,
    // its manifest already removed, a file differing from the new one.
    let dead = 4_000_000u32; // above pid_max: never running
    let trash = sibling(&out, "plinth-trash", dead);
    std::fs::create_dir(&trash).unwrap();
    std::fs::write(trash.join("a.csv"), "1").unwrap();
    let notes = clean_leftovers(&out);
    assert!(notes[0].contains("had replaced"), "{notes:?}");
    assert!(!trash.exists());
    assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "2");
}
