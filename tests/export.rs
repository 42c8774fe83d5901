//! `jetid export` end to end: the Python and C programs it writes reproduce `jetid predict` on a run
//! the model was not fitted on, for the plain model and for a model with each effect; the MATLAB
//! file holds the model's transfer functions; and the errors a user can cause.
//!
//! The programs are run with the real `python3` (numpy and python-control) and `cc`. Without them
//! the comparisons are skipped with a message, unless `JETID_REQUIRE_EXPORT_TOOLS=1` (CI), where a
//! missing tool fails the test.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use crate::common::{build_model, have_cc, have_python, jetid, python3};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use jetid::core::effects::{AmbientCorrection, EffectBlock, ExtendedModel, ReadOffSpeed};
use jetid::io::model_file::read_model;

fn ok(o: &Output, what: &str) -> String {
    assert!(
        o.status.success(),
        "{what} failed: {}\n{}",
        String::from_utf8_lossy(&o.stderr),
        String::from_utf8_lossy(&o.stdout)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A run file's header and columns.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(|h| h.trim().to_owned()).collect();
    let mut columns = vec![Vec::new(); header.len()];
    for line in lines.filter(|l| !l.trim().is_empty()) {
        for (column, cell) in columns.iter_mut().zip(line.split(',')) {
            column.push(
                cell.trim().parse::<f64>().unwrap_or_else(|e| panic!("{}: {cell}: {e}", path.display())),
            );
        }
    }
    (header, columns)
}

/// Largest relative difference of `actual` from `expected`, after checking that both have the same
/// columns and samples and that every sample agrees to 1e-6 relative (1e-9 absolute floor).
fn agree(expected: &Path, actual: &Path) -> f64 {
    let (h_e, c_e) = read_csv(expected);
    let (h_a, c_a) = read_csv(actual);
    assert_eq!(h_e, h_a, "columns of {} and {}", expected.display(), actual.display());
    let mut worst = 0.0f64;
    for ((name, e), a) in h_e.iter().zip(&c_e).zip(&c_a) {
        assert_eq!(e.len(), a.len(), "{name}: samples");
        assert!(e.len() > 100, "{name}: a run of {} samples", e.len());
        for (k, (x, y)) in e.iter().zip(a).enumerate() {
            let diff = (x - y).abs();
            assert!(
                diff <= 1e-6 * x.abs() + 1e-9,
                "{}: {name}[{k}] = {y}, jetid predict says {x}",
                actual.display()
            );
            worst = worst.max(diff / x.abs().max(1e-300));
        }
    }
    worst
}

/// A model fitted on a simulated identification run (with `effect` in the engine when the
/// simulator has it, and added to the model), and a run of another seed it was not fitted on. The
/// model is the one `jetid --batch` writes, built here by the batch's steps ([`build_model`]): the
/// exports need the model alone, not the batch's baselines and figures.
fn fit(dir: &Path, effect: Option<&str>, output: Option<&str>) -> (PathBuf, PathBuf) {
    let (ident, val, other) = simulated_runs(dir, effect);
    let fitted = dir.join("fit");
    std::fs::create_dir_all(&fitted).unwrap();
    let mut text = format!("ident = {:?}\nvalidate = [{:?}]\n", s(&ident), s(&val));
    text += &output.map(|o| format!("outputs = [{o:?}]\n")).unwrap_or_default();
    text += &effect.map(|e| format!("add_effects = [{e:?}]\n")).unwrap_or_default();
    let model = build_model(&text, &fitted);
    check_effects(&model, effect);
    (model, other)
}

/// [`fit`] through `jetid --batch` itself, for the tests that read its report (`fit/report.json`).
fn fit_with_report(dir: &Path, effect: Option<&str>, output: Option<&str>) -> (PathBuf, PathBuf) {
    let (ident, val, other) = simulated_runs(dir, effect);
    let fitted = dir.join("fit");
    let mut args =
        vec!["--batch", "--ident", s(&ident), "--validate", s(&val), "--out", s(&fitted), "--quiet"];
    args.extend(output.map(|o| ["--output", o]).iter().flatten());
    args.extend(effect.map(|e| ["--add-effect", e]).iter().flatten());
    ok(&jetid(&args), "jetid --batch");
    let model = fitted.join("model.json");
    check_effects(&model, effect);
    (model, other)
}

/// Simulated identification, validation and other-seed runs (with `effect` in the engine when the
/// simulator has it), written to `dir`.
fn simulated_runs(dir: &Path, effect: Option<&str>) -> (PathBuf, PathBuf, PathBuf) {
    let sim_effect: Vec<&str> = effect
        .filter(|e| jetid::sim::effects::EFFECT_IDS.iter().any(|id| id.name() == *e))
        .map(|e| vec!["--effect", e])
        .unwrap_or_default();
    let simulate = |test: &str, seed: &str, out: &Path| {
        let mut args = vec!["simulate", "--test", test, "--seed", seed, "--out", s(out)];
        args.extend(&sim_effect);
        ok(&jetid(&args), "jetid simulate");
    };
    let (ident, val, other) = (dir.join("ident.csv"), dir.join("val.csv"), dir.join("other.csv"));
    simulate("ident", "3", &ident);
    simulate("validation", "4", &val);
    simulate("validation", "11", &other);
    (ident, val, other)
}

/// Every output of the model file `model` holds `effect` and nothing else.
fn check_effects(model: &Path, effect: Option<&str>) {
    for out in &read_model(model).unwrap().outputs {
        let applied: Vec<&str> = out.effects.iter().map(|e| e.id.name()).collect();
        assert_eq!(applied, effect.into_iter().collect::<Vec<_>>(), "{}: {}", model.display(), out.name);
    }
}

/// Export `model` to Python and C, run both on `run` (with `extra` arguments) and compare with
/// `jetid predict` (with `predict_extra`). Returns the largest relative differences (Python, C),
/// `None` for a tool that is missing.
fn reproduce(
    dir: &Path,
    model: &Path,
    run: &Path,
    extra: &[&str],
    predict_extra: &[&str],
) -> (Option<f64>, Option<f64>) {
    let tag = model.parent().and_then(Path::file_name).map(|n| n.to_string_lossy().into_owned()).unwrap();
    let expected = dir.join(format!("{tag}_predict.csv"));
    let mut args = vec!["predict", "--model", s(model), "--input", s(run), "--out", s(&expected)];
    args.extend_from_slice(predict_extra);
    ok(&jetid(&args), "jetid predict");

    let python = have_python().then(|| {
        let program = dir.join(format!("{tag}_model.py"));
        ok(
            &jetid(&["export", "--model", s(model), "--format", "python", "--out", s(&program)]),
            "export python",
        );
        let out = dir.join(format!("{tag}_python.csv"));
        let o = python3().arg(&program).arg(run).arg(&out).args(extra).output().unwrap();
        ok(&o, "the exported Python program");
        agree(&expected, &out)
    });
    let c = have_cc().then(|| {
        let source = dir.join(format!("{tag}_model.c"));
        ok(&jetid(&["export", "--model", s(model), "--format", "c", "--out", s(&source)]), "export c");
        let binary = dir.join(format!("{tag}_model"));
        let strict = ["-std=c99", "-Wall", "-Werror"];
        let o = Command::new("cc")
            .arg("-O2")
            .args(strict)
            .arg(&source)
            .arg("-o")
            .arg(&binary)
            .arg("-lm")
            .output()
            .unwrap();
        ok(&o, "cc on the exported C program");
        // Without its main, as a library: the same source was just compiled and optimised whole, so
        // what is left to check is that the rest stands alone, warnings as errors (a helper only
        // main used would be unused). Unoptimised: `-fsyntax-only` would skip the unused-function
        // check, and -O2's optimisation would repeat the compile above.
        let o = Command::new("cc")
            .arg("-O0")
            .args(strict)
            .args(["-DJETID_NO_MAIN", "-c"])
            .arg(&source)
            .arg("-o")
            .arg(dir.join(format!("{tag}_model.o")))
            .output()
            .unwrap();
        ok(&o, "cc -DJETID_NO_MAIN on the exported C program");
        let out = dir.join(format!("{tag}_c.csv"));
        ok(&Command::new(&binary).arg(run).arg(&out).args(extra).output().unwrap(), "the exported C program");
        agree(&expected, &out)
    });
    let octave = (extra.is_empty() && predict_extra.is_empty())
        .then(|| octave_reproduces(dir, model, run, &expected, &tag))
        .flatten();
    eprintln!(
        "{}: largest relative difference from jetid predict: Python {python:?}, C {c:?}, MATLAB {octave:?}",
        model.display()
    );
    (python, c)
}

/// The MATLAB export run by GNU Octave on `run`, against `expected`, when Octave is installed (CI
/// does not install it: the MATLAB file is then checked as text by `matlab_file_holds_…`).
fn octave_reproduces(dir: &Path, model: &Path, run: &Path, expected: &Path, tag: &str) -> Option<f64> {
    if !Command::new("octave").arg("--version").output().is_ok_and(|o| o.status.success()) {
        eprintln!("SKIPPED: octave is not installed, so the MATLAB file is not run");
        return None;
    }
    let name: String =
        format!("m_{tag}").chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    let program = dir.join(format!("{name}.m"));
    ok(&jetid(&["export", "--model", s(model), "--format", "matlab", "--out", s(&program)]), "export matlab");
    let out = dir.join(format!("{tag}_octave.csv"));
    let call = format!("{name}('csv', '{}', '{}')", s(run), s(&out));
    ok(
        &Command::new("octave").current_dir(dir).args(["--quiet", "--eval", &call]).output().unwrap(),
        "octave",
    );
    Some(agree(expected, &out))
}

fn exports_reproduce_predict(effect: Option<&str>, output: Option<&str>) {
    let dir = tempfile::tempdir().unwrap();
    let (model, run) = fit(dir.path(), effect, output);
    reproduce(dir.path(), &model, &run, &[], &[]);
}

#[test]
fn plain_model_with_two_outputs() {
    exports_reproduce_predict(None, None);
}

#[test]
fn thermal_soak() {
    exports_reproduce_predict(Some("thermal_soak"), Some("shaft_speed_rpm"));
}

/// Thrust's soak acts on a power of thrust that is not the speed's cube (`powf` in every runtime).
#[test]
fn thermal_soak_on_thrust() {
    exports_reproduce_predict(Some("thermal_soak"), Some("thrust_n"));
}

#[test]
fn ambient_correction() {
    exports_reproduce_predict(Some("ambient_correction"), Some("thrust_n"));
}

#[test]
fn asymmetric_dynamics() {
    exports_reproduce_predict(Some("asymmetric_dynamics"), Some("shaft_speed_rpm"));
}

#[test]
fn scheduled_time_constant() {
    exports_reproduce_predict(Some("scheduled_time_constant"), Some("shaft_speed_rpm"));
}

/// The scheduled time constant in the power balance's form (`spool_schedule = "power_balance"`),
/// read through a map with a kink, beside asymmetric dynamics: every runtime runs the balance, the
/// kink's jump of the time constant and the slower falls included, as `jetid predict` does.
#[test]
fn scheduled_time_constant_as_the_power_balance_through_a_kinked_map() {
    let dir = tempfile::tempdir().unwrap();
    let (model, run) = power_balance_model(dir.path());
    reproduce(dir.path(), &model, &run, &[], &[]);
}

/// A speed model fitted by `jetid --batch` on a project that asks for the power balance, on runs of
/// family engine 7 with asymmetric dynamics (whose spool the balance describes: it is kept, not
/// refitted in the exponential form), with a kink in its map: `fit/model.json` (with
/// `fit/report.json`) and a run of another seed.
fn power_balance_model(dir: &Path) -> (PathBuf, PathBuf) {
    let simulate = |test: &str, seed: &str, out: &Path| {
        let args =
            ["simulate", "--test", test, "--seed", seed, "--engine", "7", "--effect", "asymmetric_dynamics"];
        ok(&jetid(&[&args[..], &["--out", s(out)]].concat()), "jetid simulate");
    };
    let (ident, val, other) = (dir.join("ident.csv"), dir.join("val.csv"), dir.join("other.csv"));
    simulate("ident", "3", &ident);
    simulate("validation", "4", &val);
    simulate("validation", "11", &other);
    let project = dir.join("power_balance.toml");
    let blocks = ["asymmetric_dynamics", "scheduled_time_constant", "static_map_order"];
    let text = format!(
        "ident = {:?}\nvalidate = [{:?}]\noutputs = [\"shaft_speed_rpm\"]\nadd_effects = {blocks:?}\n\
         [output.shaft_speed_rpm]\nspool_schedule = \"power_balance\"\n",
        s(&ident),
        s(&val)
    );
    std::fs::write(&project, text).unwrap();
    let fitted = dir.join("fit");
    ok(&jetid(&["--batch", s(&project), "--out", s(&fitted), "--quiet"]), "jetid --batch");
    let model = fitted.join("model.json");
    let file = read_model(&model).unwrap();
    let speed = &file.outputs[0];
    let mut ids: Vec<&str> = speed.effects.iter().map(|e| e.id.name()).collect();
    ids.sort_unstable();
    assert_eq!(ids, blocks, "{}", model.display());
    let schedule = speed.effects.iter().find(|e| e.id.name() == "scheduled_time_constant").unwrap();
    let k = schedule.params["load_exponent"];
    assert!((1.0..=5.0).contains(&k), "the power balance's load exponent {k}");
    (model, other)
}

#[test]
fn rate_limit() {
    exports_reproduce_predict(Some("rate_limit"), Some("shaft_speed_rpm"));
}

#[test]
fn sensor_dynamics() {
    exports_reproduce_predict(Some("sensor_dynamics"), Some("thrust_n"));
}

#[test]
fn static_map_order_and_the_local_linear_model() {
    let dir = tempfile::tempdir().unwrap();
    let (model, run) = fit(dir.path(), Some("static_map_order"), Some("shaft_speed_rpm"));
    reproduce(dir.path(), &model, &run, &[], &[]);
    if !have_python() {
        return;
    }
    // operating_point(output, u*) is K·G(z)/G(1), K = f'(v*)·G(1) with the kink's slope above its knot.
    let read = read_model(&model).unwrap();
    let out = &read.outputs[0];
    let knot = out.effects[0].params["knot_v"];
    let slope_change = out.effects[0].params["slope_change"];
    let g1 = out.wiener.linear.tf.dc_gain().unwrap();
    let offset = out.wiener.linear.offset;
    let program = dir.path().join("jetid_model.py");
    ok(
        &jetid(&["export", "--model", s(&model), "--format", "python", "--out", s(&program)]),
        "export python",
    );
    // One Python for both points (each start imports python-control): a line per point.
    let v_stars = [knot - 1000.0, knot + 1000.0];
    let u_stars: Vec<f64> = v_stars.iter().map(|v| (v - offset) / g1).collect();
    let script = format!(
        "import sys; sys.path.insert(0, {dir:?}); import jetid_model as m\n\
         for u in {u_stars:?}:\n    g = m.operating_point({name:?}, u)\n    \
         print(repr(float(g.dcgain())), repr(float(abs(g.poles() - m.TF[{name:?}].poles()).max())))",
        dir = s(dir.path()),
        name = out.name,
    );
    let printed = ok(&python3().args(["-c", &script]).output().unwrap(), "operating_point");
    let mut lines = printed.lines();
    for v_star in v_stars {
        let expected = (out.wiener.map.slope(v_star) + if v_star > knot { slope_change } else { 0.0 }) * g1;
        let line = lines.next().unwrap_or_else(|| panic!("no line for v* = {v_star}: {printed}"));
        let numbers: Vec<f64> = line.split_whitespace().map(|x| x.parse().unwrap()).collect();
        assert!(
            (numbers[0] - expected).abs() <= 1e-9 * expected.abs(),
            "K at v* = {v_star}: {} vs {expected}",
            numbers[0]
        );
        assert!(numbers[1] < 1e-12, "the local model has G's poles: {line}");
    }
}

/// An output read off the shaft speed's model (`read_off_speed`, offered by the spool sharing): the
/// speed's whole path, with a rate limit read through its map, then the quartic in the speed, in
/// every runtime; and the local gain of the exported operating point carries the quartic's slope.
#[test]
fn read_off_speed_through_a_rate_limited_speed_model() {
    read_off_reproduces_predict("rate_limit", None);
}

/// Read off a speed model corrected for the inlet conditions: in corrected quantities, the speed's
/// correction undone and the output's own (`F/δ`) applied, in every runtime.
#[test]
fn read_off_speed_through_a_corrected_speed_model() {
    let thrust = AmbientCorrection { output_theta_exp: 0.0, output_delta_exp: 1.0 };
    read_off_reproduces_predict("ambient_correction", Some(&thrust));
}

/// A speed model with `effect`, and thrust read off it (its own correction `correction`, when the
/// speed's model is corrected): the exports reproduce `jetid predict`, and Python's operating point
/// has the local gain through the quartic's slope.
fn read_off_reproduces_predict(effect: &str, correction: Option<&AmbientCorrection>) {
    let dir = tempfile::tempdir().unwrap();
    let (model, run) = fit(dir.path(), Some(effect), Some("shaft_speed_rpm"));
    let mut file = read_model(&model).unwrap();
    let (header, columns) = read_csv(&dir.path().join("ident.csv"));
    let column = |name: &str| &columns[header.iter().position(|h| h == name).unwrap()];
    let block = ReadOffSpeed::fit(column("shaft_speed_rpm"), column("thrust_n"), correction).unwrap();
    let mut thrust = file.outputs[0].clone();
    (thrust.name, thrust.unit, thrust.covariance) = ("thrust_n".into(), "N".into(), None);
    thrust.effects.push(EffectBlock::ReadOffSpeed(block.clone()).record());
    file.outputs.push(thrust.clone());
    let read_off_dir = dir.path().join("read_off");
    std::fs::create_dir_all(&read_off_dir).unwrap();
    let read_off_model = read_off_dir.join("model.json");
    jetid::io::model_file::write_model(&read_off_model, &file).unwrap();
    reproduce(dir.path(), &read_off_model, &run, &[], &[]);
    if !have_python() {
        return;
    }
    let extended = ExtendedModel::from_records("thrust_n", thrust.wiener.clone(), &thrust.effects).unwrap();
    let (g1, offset) = (thrust.wiener.linear.tf.dc_gain().unwrap(), thrust.wiener.linear.offset);
    let u_star = 3.0;
    let v_star = g1 * u_star + offset;
    let expected = thrust.wiener.map.slope(v_star) * block.slope(extended.map_with_kink(v_star)) * g1;
    let program = dir.path().join("jetid_read_off.py");
    ok(
        &jetid(&["export", "--model", s(&read_off_model), "--format", "python", "--out", s(&program)]),
        "export python",
    );
    let script = format!(
        "import sys; sys.path.insert(0, {dir:?}); import jetid_read_off as m\n\
         print(repr(float(m.operating_point('thrust_n', {u_star}).dcgain())))",
        dir = s(dir.path()),
    );
    let printed = ok(&python3().args(["-c", &script]).output().unwrap(), "operating_point");
    let k: f64 = printed.trim().parse().unwrap();
    assert!(expected > 0.0 && (k - expected).abs() <= 1e-9 * expected, "K = {k}, expected {expected}");
}

#[test]
fn transport_delay_fitted_and_several_samples_long() {
    let dir = tempfile::tempdir().unwrap();
    let (model, run) = fit(dir.path(), Some("transport_delay"), Some("thrust_n"));
    reproduce(dir.path(), &model, &run, &[], &[]);
    // The fitted delay can be a fraction of a sample; a delay three samples longer runs the delay line.
    let mut longer = read_model(&model).unwrap();
    let delay = longer.outputs[0].effects[0].params.get_mut("delay_samples").unwrap();
    *delay += 3.0;
    let longer_dir = dir.path().join("longer");
    std::fs::create_dir_all(&longer_dir).unwrap();
    let longer_model = longer_dir.join("model.json");
    jetid::io::model_file::write_model(&longer_model, &longer).unwrap();
    reproduce(dir.path(), &longer_model, &run, &[], &[]);
}

#[test]
fn calibration_drift_from_the_runs_own_holds() {
    let dir = tempfile::tempdir().unwrap();
    let (model, run) = fit(dir.path(), Some("calibration_drift"), Some("thrust_n"));
    reproduce(dir.path(), &model, &run, &[], &[]);
    // A run logged with another calibration, noiseless so that its holds are found: with the
    // measured output read (`--calibrate`, `--map output=thrust_n`) the offset moves the prediction.
    let (noisy, truth) = (dir.path().join("drifted.csv"), dir.path().join("drifted_truth.csv"));
    ok(
        &jetid(&[
            "simulate",
            "--test",
            "ident",
            "--seed",
            "9",
            "--effect",
            "calibration_drift:offset_gph=0.5",
            "--out",
            s(&noisy),
            "--truth-out",
            s(&truth),
        ]),
        "jetid simulate",
    );
    let (py, c) = reproduce(dir.path(), &model, &truth, &["--calibrate"], &["--map", "output=thrust_n"]);
    let calibrated = dir.path().join("fit_predict.csv");
    let plain = dir.path().join("uncalibrated.csv");
    ok(&jetid(&["predict", "--model", s(&model), "--input", s(&truth), "--out", s(&plain)]), "jetid predict");
    let (_, a) = read_csv(&calibrated);
    let (_, b) = read_csv(&plain);
    let moved = a[2].iter().zip(&b[2]).map(|(x, y)| (x - y).abs() / x.abs()).fold(0.0, f64::max);
    assert!(moved > 1e-3, "the calibration offset must change the prediction ({moved})");
    assert!(py.is_none_or(|e| e <= 1e-6) && c.is_none_or(|e| e <= 1e-6));
}

#[test]
fn matlab_file_holds_the_transfer_functions_and_a_simulation() {
    let dir = tempfile::tempdir().unwrap();
    let (model, _) = fit(dir.path(), Some("thermal_soak"), None);
    let file = dir.path().join("engine_model.m");
    ok(&jetid(&["export", "--model", s(&model), "--format", "matlab", "--out", s(&file)]), "export matlab");
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.starts_with("function varargout = engine_model(command, varargin)"), "{}", &text[..80]);
    assert!(text.contains("tf(o.tf_num_z, o.tf_den_z, m.dt)"));
    assert!(text.contains("function out = simulate_all(m, u, aux, measured, dt)"));
    let read = read_model(&model).unwrap();
    let row = |xs: &[f64]| xs.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", ");
    assert!(text.contains(&format!("m.dt = {:?};", read.dt_secs)));
    for out in &read.outputs {
        let tf = &out.wiener.linear.tf;
        let at = text.find(&format!("o.name = '{}';", out.name)).unwrap_or_else(|| panic!("{}", out.name));
        let section = &text[at..];
        assert!(section.contains(&format!("o.tf.num = [{}];", row(&tf.num_zinv))), "{}", out.name);
        assert!(section.contains(&format!("o.tf.den = [{}];", row(&tf.den_zinv))), "{}", out.name);
        assert!(section.contains(&format!("o.coeffs = [{}];", row(&out.wiener.map.coeffs_scaled))));
        let soak = &out.effects[0].params;
        let exponent = soak["power_exponent"];
        assert!(
            section.contains(&format!("o.soak = [{:?}, {:?}, {exponent:?}];", soak["gain"], soak["tau_s"])),
            "{}",
            out.name
        );
    }
    // Where Octave is installed, every `exports_reproduce_predict` runs the MATLAB file too
    // (`octave_reproduces`); here it is read as text, which needs no Octave.
}

/// `jetid` fails with status 1, no panic, and a message holding every `needle`.
fn fails_with(args: &[&str], needles: &[&str]) {
    let o = jetid(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for needle in needles {
        assert!(err.contains(needle), "{args:?}: '{needle}' not in: {err}");
    }
}

#[test]
fn errors_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let (model, _) = fit(dir.path(), None, Some("thrust_n"));
    let out = dir.path().join("m.py");
    fails_with(
        &["export", "--model", s(&dir.path().join("missing.json")), "--format", "python", "--out", s(&out)],
        &["missing.json"],
    );
    fails_with(
        &["export", "--model", s(&model), "--format", "fortran", "--out", s(&out)],
        &["fortran", "python", "matlab"],
    );
    // An --out inside a regular file.
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, "x").unwrap();
    fails_with(
        &["export", "--model", s(&model), "--format", "c", "--out", s(&blocker.join("sub/m.c"))],
        &["cannot create folder", "file"],
    );
    assert!(!blocker.join("sub").exists());
    fails_with(
        &["export", "--model", s(&model), "--format", "matlab", "--out", s(&dir.path().join("2nd-model.m"))],
        &["2nd-model", "MATLAB identifier"],
    );

    // What the generated code cannot represent: a name that cannot be a CSV header cell, an
    // unstable linear block, an effect the linear block has no spool for.
    let edited = |name: &str, edit: &dyn Fn(&mut jetid::io::model_file::ModelFile)| {
        let mut m = read_model(&model).unwrap();
        edit(&mut m);
        let path = dir.path().join(name);
        jetid::io::model_file::write_model(&path, &m).unwrap();
        path
    };
    let quoted = edited("quoted.json", &|m| m.outputs[0].name = "thrust, \"net\"".into());
    fails_with(
        &["export", "--model", s(&quoted), "--format", "python", "--out", s(&out)],
        &["thrust, \\\"net\\\"", "cannot be exported"],
    );
    let unstable = edited("unstable.json", &|m| {
        let tf = &mut m.outputs[0].wiener.linear.tf;
        tf.den_zinv = vec![1.0, -1.5];
        tf.num_zinv = vec![0.0, 1.0];
    });
    fails_with(
        &["export", "--model", s(&unstable), "--format", "c", "--out", s(&out)],
        &["thrust_n", "unstable"],
    );
    let no_spool = edited("no_spool.json", &|m| {
        let tf = &mut m.outputs[0].wiener.linear.tf;
        tf.den_zinv = vec![1.0, 0.5];
        tf.num_zinv = vec![0.0, 1.5];
        m.outputs[0].effects.push(jetid::io::model_file::EffectRecord {
            id: "asymmetric_dynamics".parse().unwrap(),
            params: [("decel_factor".to_owned(), 2.0)].into_iter().collect(),
        });
    });
    fails_with(
        &["export", "--model", s(&no_spool), "--format", "python", "--out", s(&out)],
        &["thrust_n", "asymmetric_dynamics", "real pole"],
    );
    // A covariance that does not describe the model: one parameter short, or not symmetric.
    let short = edited("short_cov.json", &|m| {
        let c = m.outputs[0].covariance.as_mut().unwrap();
        c.names.pop();
        c.values.pop();
    });
    fails_with(
        &["export", "--model", s(&short), "--format", "python", "--out", s(&out)],
        &["thrust_n", "parameter covariance", "parameters"],
    );
    let skew = edited("skew_cov.json", &|m| {
        let c = m.outputs[0].covariance.as_mut().unwrap();
        c.matrix[0][1] = c.matrix[1][0] + (c.matrix[0][0] * c.matrix[1][1]).sqrt();
    });
    fails_with(
        &["export", "--model", s(&skew), "--format", "c", "--out", s(&out)],
        &["thrust_n", "not a covariance"],
    );
    assert!(!out.exists(), "nothing is written on an error");
}

/// The exported `sample_models` draws from the model file's covariance: the sample covariance of
/// 2,000 drawn parameter vectors is within 10 % of the stated one (each entry against the product of
/// the two standard deviations: with 2,000 draws an entry's own sampling spread is about 2-3 % of
/// that), the model at the stated values is the file's linear block, and `operating_point_ci95`
/// agrees with the report's `gain_ci95` at the grid's middle point.
#[test]
fn the_python_sample_models_follow_the_covariance() {
    if !have_python() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (model, _) = fit_with_report(dir.path(), None, Some("shaft_speed_rpm"));
    let stated =
        read_model(&model).unwrap().outputs[0].covariance.clone().expect("the batch stores a covariance");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("fit/report.json")).unwrap()).unwrap();
    let mid = &report["outputs"]["shaft_speed_rpm"]["operating_points"][4];
    let (u, ci): (f64, Vec<f64>) =
        (mid["u"].as_f64().unwrap(), serde_json::from_value(mid["gain_ci95"].clone()).unwrap());
    let program = dir.path().join("jetid_model.py");
    ok(
        &jetid(&["export", "--model", s(&model), "--format", "python", "--out", s(&program)]),
        "export python",
    );
    let script = format!(
        "import sys, numpy as np; sys.path.insert(0, {dir:?}); import jetid_model as m\n\
         o = 'shaft_speed_rpm'\n\
         draws = m.sample_models(o, 2000, 7)\n\
         theta = np.array([d['theta'] for d in draws])\n\
         S = np.cov(theta.T)\n\
         print(' '.join(repr(float(x)) for x in S.ravel()))\n\
         g = m.model_at(o, m.COVARIANCE[o]['values'])['tf']\n\
         t = m.TF[o]\n\
         print(max(abs(complex(g(np.exp(1j * w * m.DT)) - t(np.exp(1j * w * m.DT)))) / abs(complex(t(1.0))) for w in (0.01, 0.3, 2.0)))\n\
         print(' '.join(repr(x) for x in m.operating_point_ci95(o, {u:?})['gain']))",
        dir = s(dir.path()),
    );
    let printed = ok(&python3().args(["-c", &script]).output().unwrap(), "sample_models");
    let lines: Vec<Vec<f64>> =
        printed.lines().map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect()).collect();
    let n = stated.values.len();
    assert_eq!(lines[0].len(), n * n);
    for i in 0..n {
        for j in 0..n {
            let scale = (stated.matrix[i][i] * stated.matrix[j][j]).sqrt();
            let got = lines[0][i * n + j];
            assert!(
                (got - stated.matrix[i][j]).abs() <= 0.1 * scale,
                "{} × {}: sample covariance {got} against the stated {}",
                stated.names[i],
                stated.names[j],
                stated.matrix[i][j]
            );
        }
    }
    assert!(lines[1][0] < 1e-9, "the model at the stated values is the file's G(z): {}", lines[1][0]);
    let (lo, hi) = (lines[2][0], lines[2][1]);
    let width = ci[1] - ci[0];
    assert!(
        (lo - ci[0]).abs() <= 0.25 * width && (hi - ci[1]).abs() <= 0.25 * width,
        "Python's gain interval [{lo}, {hi}] against the report's {ci:?}"
    );
}

/// The exported `operating_point` is the local model of the report's operating points (the same
/// frequency response at every point), for a scheduled spool (in either form) and for sensor
/// dynamics.
#[test]
fn the_python_operating_points_are_the_reports() {
    if !have_python() {
        return;
    }
    for effect in ["scheduled_time_constant", "sensor_dynamics", "power_balance"] {
        let dir = tempfile::tempdir().unwrap();
        let model = match effect {
            "power_balance" => power_balance_model(dir.path()).0,
            _ => fit_with_report(dir.path(), Some(effect), Some("shaft_speed_rpm")).0,
        };
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("fit/report.json")).unwrap())
                .unwrap();
        let points = report["outputs"]["shaft_speed_rpm"]["operating_points"].as_array().unwrap().clone();
        assert!(points.len() >= 9, "{effect}: {} points", points.len());
        let program = dir.path().join("jetid_model.py");
        ok(
            &jetid(&["export", "--model", s(&model), "--format", "python", "--out", s(&program)]),
            "export python",
        );
        // One Python for the three points (each start imports python-control, two seconds): a line
        // per point and frequency.
        let omegas = [0.05, 0.5, 2.0, 8.0];
        let chosen = [&points[0], &points[4], &points[8]];
        let us: Vec<f64> = chosen.iter().map(|p| p["u"].as_f64().unwrap()).collect();
        let script = format!(
            "import sys, numpy as np; sys.path.insert(0, {dir:?}); import jetid_model as m\n\
             for u in {us:?}:\n    g = m.operating_point('shaft_speed_rpm', u)\n    \
             for w in {omegas:?}:\n        r = g(np.exp(1j * w * m.DT))\n        \
             print(repr(float(r.real)), repr(float(r.imag)))",
            dir = s(dir.path()),
        );
        let printed = ok(&python3().args(["-c", &script]).output().unwrap(), "operating_point");
        let mut lines = printed.lines();
        for (p, u) in chosen.iter().zip(&us) {
            let local: jetid::core::numerics::tf::DiscreteTf =
                serde_json::from_value(p["local"].clone()).unwrap();
            for w in omegas {
                let line = lines.next().unwrap_or_else(|| panic!("{effect}, u* = {u}: no line for ω = {w}"));
                let parts: Vec<f64> = line.split_whitespace().map(|x| x.parse().unwrap()).collect();
                let expected = local.freq_response(w);
                let got = num_complex::Complex64::new(parts[0], parts[1]);
                assert!(
                    (got - expected).norm() <= 1e-9 * expected.norm().max(1e-300),
                    "{effect}, u* = {u}, ω = {w}: {got} vs {expected}"
                );
            }
        }
    }
}
