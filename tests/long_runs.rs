//! Long logs: the identification run cut to the part its model is fitted on (and said so), the
//! simulator's repeated designs, and a batch stopped by Ctrl+C leaving nothing behind.
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use jetid::workflow::long_runs::FIT_SAMPLES;

use crate::common::{jetid, sample};

/// A simulated identification design repeated `times` times end to end, written into `dir`.
fn repeated_run(dir: &Path, times: u32) -> std::path::PathBuf {
    let path = dir.join(format!("long_x{times}.csv"));
    let times = times.to_string();
    let o = jetid(&[
        "simulate",
        "--test",
        "ident",
        "--repeat",
        &times,
        "--seed",
        "5",
        "--out",
        path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    path
}

fn project_with_ident(dir: &Path, ident: &Path) -> jetid::io::project::Project {
    let text = format!("name = \"long\"\nident = \"{}\"\noutputs = [\"shaft_speed_rpm\"]\n", ident.display());
    jetid::io::project::parse_project(&text, dir, "long.toml").unwrap()
}

/// The repeated design is one continuous run: the engine runs through, each repeat starting where
/// the last one ended, with the design's samples `times` over.
#[test]
fn the_simulator_repeats_a_design_without_a_stop() {
    let dir = tempfile::tempdir().unwrap();
    let once = jetid::io::csv_run::load_run(&repeated_run(dir.path(), 1), &Default::default()).unwrap();
    let thrice = jetid::io::csv_run::load_run(&repeated_run(dir.path(), 3), &Default::default()).unwrap();
    let per_design = once.len() as f64 - 1.0;
    assert!((thrice.len() as f64 - 3.0 * per_design).abs() <= 3.0, "{} against {}", thrice.len(), once.len());
    // The second repeat does not restart from idle: where it begins, the spool is still near the top
    // step the first one ended on (a run pasted end to end would jump to the idle speed at once).
    let speed = &thrice.output("shaft_speed_rpm").unwrap().values;
    let idle = once.output("shaft_speed_rpm").unwrap().values[0];
    let at = (375.0 * 8.85_f64).ceil() as usize;
    let (before, after) = (speed[at - 1], speed[at]);
    assert!((after - before).abs() < 0.5 * (before - idle).abs(), "{before} -> {after} rpm (idle {idle})");
    let bad = jetid(&["simulate", "--test", "ident", "--repeat", "0", "--out", "x.csv"]);
    assert!(!bad.status.success());
}

/// A run longer than the fit budget is fitted on its first segments up to the budget, and the notes
/// say which and how to choose another part; a short run is fitted whole.
#[test]
fn a_long_identification_run_is_fitted_on_its_first_segments_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let long = repeated_run(dir.path(), 10);
    let full = jetid::io::csv_run::load_run(&long, &Default::default()).unwrap();
    assert!(full.len() > FIT_SAMPLES, "{} samples", full.len());
    let runs = jetid::workflow::runs::load_runs(&project_with_ident(dir.path(), &long)).unwrap();
    assert!(runs.ident.len() <= FIT_SAMPLES && runs.ident.len() > FIT_SAMPLES / 2, "{}", runs.ident.len());
    let note = runs.notes.iter().find(|n| n.contains("is long")).expect("a note on the cut");
    assert!(note.contains("window") && note.contains(&full.len().to_string()), "{note}");
    // The cut starts where the first segment does, on the run's own time axis.
    let first = runs.ident.t_secs[0];
    let k = full.t_secs.iter().position(|t| (t - first).abs() < 1e-9).unwrap();
    assert_eq!(full.input.values[k..k + runs.ident.len()], runs.ident.input.values[..]);

    let short =
        jetid::workflow::runs::load_runs(&project_with_ident(dir.path(), &sample("sr30/ident.csv"))).unwrap();
    assert!(!short.notes.iter().any(|n| n.contains("is long")));
}

/// Ctrl+C in the middle of a batch: exit status 130, no staging folder left, `--out` not created.
#[cfg(unix)]
#[test]
fn an_interrupted_batch_leaves_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_jetid"))
        .args(["--batch", "--out", out.to_str().unwrap(), "--quiet"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the staging folder (the batch is then well under way), then interrupt.
    let staged = |d: &Path| {
        std::fs::read_dir(d)
            .unwrap()
            .any(|e| e.unwrap().file_name().to_string_lossy().contains("jetid-staging"))
    };
    let begun = Instant::now();
    while !staged(dir.path()) {
        assert!(child.try_wait().unwrap().is_none(), "the batch ended before it could be interrupted");
        assert!(begun.elapsed() < Duration::from_secs(120), "no staging folder appeared");
        std::thread::sleep(Duration::from_millis(20));
    }
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let status = child.wait().unwrap();
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(!staged(dir.path()), "a staging folder was left behind");
    assert!(!out.exists(), "--out was created by an interrupted batch");
}
