//! The held-out role in the app: read from and saved to a project, scored beside the validation
//! runs, never used by the live error or the diagnosis; and a resampled run on another grid is put
//! on the identification run's grid rather than left unscored.
#![cfg(feature = "gui")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::sample;
use jetid::ui::{App, Command, Role, Session};

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
    let roles: Vec<Role> = app.session.runs.iter().map(|r| r.role).collect();
    assert_eq!(roles, [Role::Identification, Role::Validation, Role::HeldOut, Role::HeldOut]);
    let view = app.cache.live_view("shaft_speed_rpm").expect("speed is identified");
    let live = view.live.as_ref().expect("a model");
    let scored: Vec<(String, Role)> = live.runs.iter().map(|r| (r.name.clone(), r.role)).collect();
    assert!(
        scored.contains(&("validation_fast".to_owned(), Role::HeldOut)),
        "re-gridded and scored: {scored:?}"
    );
    assert!(scored.contains(&("chirp".to_owned(), Role::HeldOut)), "{scored:?}");
    // The live error is the validation run's alone.
    let validation = live.runs.iter().find(|r| r.role == Role::Validation).unwrap();
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
