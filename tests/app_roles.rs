//! The held-out role in the app: read from and saved to a project, scored beside the validation
//! runs, never used by the live error or the diagnosis; and a resampled run on another grid is put
//! on the identification run's grid rather than left unscored.
#![cfg(feature = "gui")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::sample;
use jetid::core::run::RunRole;
use jetid::ui::{App, Command, Session};

/// The sr30 validation run written with every time stamp 0.9 times its own: another sample time.
fn faster_copy(dir: &std::path::Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(sample("sr30/validation.csv")).unwrap();
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    for line in lines {
        let (t, rest) = line.split_once(',').unwrap();
        out += &format!("{},{rest}\n", t.parse::<f64>().unwrap() * 0.9);
    }
    let path = dir.join("validation_fast.csv");
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn held_out_runs_are_scored_saved_and_never_chosen_on() {
    let dir = tempfile::tempdir().unwrap();
    let fast = faster_copy(dir.path());
    let runs = sample("sr30");
    let project = dir.path().join("project.toml");
    std::fs::write(
        &project,
        format!(
            "ident = {:?}\nvalidate = [{:?}]\nheld_out = [{:?}, {{ path = {:?}, resample = true }}]\n",
            runs.join("ident.csv"),
            runs.join("validation.csv"),
            runs.join("chirp.csv"),
            fast,
        ),
    )
    .unwrap();
    let mut app = App::new(Session::default());
    app.apply(Command::OpenProject(project.clone()));
    assert!(app.view.errors.is_empty(), "{:?}", app.view.errors);
    app.settle();
    let roles: Vec<RunRole> = app.session.runs.iter().map(|r| r.role).collect();
    assert_eq!(roles, [RunRole::Identification, RunRole::Validation, RunRole::HeldOut, RunRole::HeldOut]);
    let view = app.cache.live_view("shaft_speed_rpm").expect("speed is identified");
    let live = view.live.as_ref().expect("a model");
    let scored: Vec<(String, RunRole)> = live.runs.iter().map(|r| (r.name.clone(), r.role)).collect();
    assert!(
        scored.contains(&("validation_fast".to_owned(), RunRole::HeldOut)),
        "re-gridded and scored: {scored:?}"
    );
    assert!(scored.contains(&("chirp".to_owned(), RunRole::HeldOut)), "{scored:?}");
    // The live error is the validation run's alone.
    let validation = live.runs.iter().find(|r| r.role == RunRole::Validation).unwrap();
    assert_eq!(live.mean_validation_rmspe(), Some(validation.gray_box.metrics.rmspe_pct));
    // The diagnosis is scored on the validation run only.
    let input = app.cache.output("shaft_speed_rpm").unwrap().diagnosis_input().unwrap();
    assert_eq!(input.validation.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(), ["validation"]);
    // Saved back as held_out.
    let (text, _) = jetid::ui::project_io::project_text(&app.session, &project).unwrap();
    let saved: toml::Value = toml::from_str(&text).unwrap();
    assert_eq!(saved["held_out"].as_array().map(Vec::len), Some(2), "{text}");
    assert_eq!(saved["validate"].as_array().map(Vec::len), Some(1), "{text}");
}

#[test]
fn several_identification_runs_are_joined_as_the_batch_joins_them_and_saved() {
    let dir = tempfile::tempdir().unwrap();
    let runs = sample("sr30");
    let project = dir.path().join("project.toml");
    std::fs::write(
        &project,
        format!(
            "ident = [{:?}, {:?}]\nvalidate = [{:?}]\n",
            runs.join("ident.csv"),
            runs.join("validation.csv"),
            runs.join("chirp.csv"),
        ),
    )
    .unwrap();
    let mut app = App::new(Session::default());
    app.apply(Command::OpenProject(project.clone()));
    assert!(app.view.errors.is_empty(), "{:?}", app.view.errors);
    app.settle();
    let lens: Vec<usize> =
        app.session.runs.iter().filter(|r| r.role == RunRole::Identification).map(|r| r.run.len()).collect();
    let ident = app.cache.ident.as_ref().expect("identified");
    assert_eq!(ident.run.len(), lens.iter().sum::<usize>(), "both runs, end to end");
    let segments = ident.segments.as_ref().unwrap();
    assert!(segments.iter().all(|s| s.end <= lens[0] || s.start >= lens[0]), "no segment crosses the join");
    // The Data view draws each run's own segments: the second run starts at the junction.
    let ident_indices: Vec<usize> = (0..app.session.runs.len())
        .filter(|&i| app.session.runs[i].role == RunRole::Identification)
        .collect();
    assert_eq!(ident.part_start(ident_indices[0]), Some(0));
    assert_eq!(ident.part_start(ident_indices[1]), Some(lens[0]));
    let notes = &app.cache.output("shaft_speed_rpm").unwrap().notes;
    assert!(notes.iter().any(|n| n.contains("joined end to end")), "{notes:?}");
    let (text, _) = jetid::ui::project_io::project_text(&app.session, &project).unwrap();
    let saved: toml::Value = toml::from_str(&text).unwrap();
    assert_eq!(saved["ident"].as_array().map(Vec::len), Some(2), "{text}");
}
