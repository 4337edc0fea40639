//! The bad-input corpus (`tests/bad-inputs/`, written by its `make_corpus.py`) through the
//! `radia` binary: every file must give a non-zero exit (not a panic, not an abort) and one
//! line on stderr naming the file, and the line and column where there is one (the
//! location listed in `EXPECTED`), and must leave the output file as it was.
//!
//! The test lives beside the binary (as `cli.rs` does) so that cargo builds the very binary
//! it runs, in the same profile.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/bad-inputs")
}

/// Address-space cap (KiB) for each run: a regression that allocates without checking then
/// fails inside the test instead of swapping the shared machine to a halt.
const MEMORY_CAP_KIB: u64 = 8 << 20;
const TIME_LIMIT: Duration = Duration::from_secs(60);

/// The binary under `sh -c 'ulimit -v ...'`, started in `dir`.
fn radia_capped(dir: &Path, args: &[&str]) -> Command {
    let mut cmd = Command::new("sh");
    cmd.current_dir(dir)
        .arg("-c")
        .arg(format!("ulimit -v {MEMORY_CAP_KIB} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_radia"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    cmd
}

/// Waits for `child` at most TIME_LIMIT (then kills it): (status, stdout, stderr).
fn wait_with_limit(mut child: Child, what: &str) -> (ExitStatus, String, String) {
    use std::io::Read;
    let (mut so, mut se) = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let out_thread = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = so.read_to_string(&mut s);
        s
    });
    let err_thread = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = se.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > TIME_LIMIT {
            let _ = child.kill();
            panic!("{what}: still running after {TIME_LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    (
        status,
        out_thread.join().unwrap(),
        err_thread.join().unwrap(),
    )
}

/// (scene file, expected location) pairs of EXPECTED.
fn expected() -> Vec<(String, String)> {
    let text = std::fs::read_to_string(corpus_dir().join("EXPECTED")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let (name, location) = l.split_once(' ').expect("NAME LOCATION");
            (name.to_string(), location.trim().to_string())
        })
        .collect()
}

const SENTINEL: &[u8] = b"an image from an earlier render";

/// Runs one bad scene; returns a description of what went wrong, if anything.
fn check(name: &str, location: &str, out_dir: &Path) -> Option<String> {
    let out = out_dir.join("out.exr");
    std::fs::write(&out, SENTINEL).unwrap();
    let child = radia_capped(
        &corpus_dir(),
        &[
            "render",
            "-q",
            "--threads",
            "1",
            name,
            "-o",
            out.to_str().unwrap(),
        ],
    )
    .spawn()
    .unwrap();
    let (status, _stdout, stderr) = wait_with_limit(child, name);
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    let problem = match status.code() {
        None => Some(format!("killed by a signal ({status})")),
        Some(0) => Some("exit status 0".into()),
        Some(101) => Some("panicked".into()),
        Some(_) if lines.len() != 1 => Some(format!("{} lines on stderr", lines.len())),
        Some(_) if !lines[0].starts_with("radia: error: ") => Some("not an error line".into()),
        Some(_) if !lines[0].contains(location) => Some(format!("does not name {location}")),
        Some(_) => None,
    };
    let untouched = std::fs::read(&out).ok().as_deref() == Some(SENTINEL);
    let others: Vec<_> = std::fs::read_dir(out_dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n != "out.exr")
        .collect();
    let problem = problem
        .or_else(|| (!untouched).then(|| "the output file was overwritten".into()))
        .or_else(|| (!others.is_empty()).then(|| format!("files were left: {others:?}")));
    problem.map(|p| format!("{name}: {p}\n    stderr: {}", stderr.trim()))
}

#[test]
fn every_bad_input_gives_one_error_line_and_no_image() {
    let cases = expected();
    assert!(cases.len() >= 40, "only {} cases", cases.len());
    // Every scene file in the folder is a case, and every case is a file.
    let mut files: Vec<String> = std::fs::read_dir(corpus_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| [".xml", ".gltf", ".glb"].iter().any(|x| n.ends_with(x)))
        .collect();
    files.sort();
    let mut names: Vec<String> = cases.iter().map(|(n, _)| n.clone()).collect();
    names.sort();
    assert_eq!(
        files, names,
        "EXPECTED and the files disagree: rerun make_corpus.py"
    );

    let out_dir = std::env::temp_dir().join(format!("radia-bad-inputs-{}", std::process::id()));
    std::fs::create_dir_all(&out_dir).unwrap();
    let failures: Vec<String> = cases
        .iter()
        .filter_map(|(name, location)| check(name, location, &out_dir))
        .collect();
    let _ = std::fs::remove_dir_all(&out_dir);
    assert!(
        failures.is_empty(),
        "{} of {} bad inputs were not refused cleanly:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// An absurd --resolution on a good scene is refused before anything is allocated.
#[test]
fn absurd_resolution_override_is_refused_with_the_figure() {
    let child = radia_capped(
        &corpus_dir(),
        &[
            "render",
            "-q",
            "../../scenes/furnace.xml",
            "--resolution",
            "4000000000x4000000000",
            "-o",
            "/nonexistent/out.exr",
        ],
    )
    .spawn()
    .unwrap();
    let (status, _, stderr) = wait_with_limit(child, "--resolution");
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("--resolution 4000000000x4000000000: a 4000000000x4000000000 film needs 721.6 EiB of memory"),
        "{stderr}"
    );
}
