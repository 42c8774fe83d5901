//! report.md: the report in words and tables, one section per part of the report (the model's
//! identification, the metrics beside the paper's Table 1, noise and Monte Carlo, residuals, the
//! operating points for control design).
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use super::ident::ident_section;
use super::{OutputReport, Report, ResidualReport};
use crate::core::compare::{Curve, ModelKind};
use crate::core::numerics::metrics::Metrics;
use crate::core::run::Quantity;
use crate::io::atomic::write_atomic;

/// A model's title from its report name (the Monte Carlo summary is kept as JSON).
fn model_title(name: &str) -> &str {
    ModelKind::from_report_name(name).map_or(name, |kind| kind.title())
}

/// "measured", or the model's title.
fn curve_title(curve: Curve) -> &'static str {
    match curve {
        Curve::Measured => "measured",
        Curve::Model(kind) => kind.title(),
    }
}

fn metrics_table(out: &mut String, report: &OutputReport) {
    let _ = writeln!(out, "| model | run | RMSPE % | MAPE % | SE | fit % | RMSE | max error |");
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|");
    for (model, runs) in &report.models {
        for (run, m) in runs {
            let _ = writeln!(
                out,
                "| {} | {run} | {:.4} | {:.4} | {:.4} | {:.2}{} | {:.4} | {:.4} |",
                model.title(),
                m.rmspe_pct,
                m.mape_pct,
                m.se,
                m.fit_pct,
                if m.fails() { " ⚠" } else { "" },
                m.rmse,
                m.max_abs_error
            );
        }
    }
    let failing = failing_models(report);
    if !failing.is_empty() {
        let _ = writeln!(
            out,
            "\n⚠ Fails (explains less than half of the output's variation): {}.",
            failing.join("; ")
        );
    }
}

/// "NNARX on 'validation': fit 31.7 % (below 50 %)" for every model that fails on a run.
pub fn failing_models(report: &OutputReport) -> Vec<String> {
    report
        .models
        .iter()
        .flat_map(|(model, runs)| {
            runs.iter().filter_map(move |(run, m)| {
                let why = report.failure_reasons.get(model).and_then(|r| r.get(run));
                m.failure().map(|f| match why {
                    Some(why) => format!("{} on '{run}': {f}: {why}", model.title()),
                    None => format!("{} on '{run}': {f}", model.title()),
                })
            })
        })
        .collect()
}

/// Mean of a metric of one model over the runs of a role (validation runs, or the chirp run).
fn role_mean(
    report: &Report,
    o: &OutputReport,
    model: ModelKind,
    chirp: bool,
    f: fn(&Metrics) -> f64,
) -> Option<f64> {
    let runs = o.models.get(&model)?;
    let vals: Vec<f64> = report
        .runs
        .iter()
        .filter(|(role, _)| if chirp { role.as_str() == "chirp" } else { role.starts_with("validation") })
        .filter_map(|(_, run)| runs.get(run).map(f))
        .collect();
    (!vals.is_empty()).then(|| vals.iter().sum::<f64>() / vals.len() as f64)
}

/// Our Table 1 (mean over the validation runs; the chirp run) beside the paper's.
fn table1_section(out: &mut String, report: &Report) {
    let _ = writeln!(
        out,
        "\n## Table 1: ours beside the paper's (RMSPE %, SE; time-domain validation / chirp)\n\n\
         Ours are measured on this project's runs, the paper's on its SR-30 bench data.\n"
    );
    let _ = writeln!(
        out,
        "| output | model | RMSPE | SE | RMSPE chirp | SE chirp | paper RMSPE | paper SE | paper RMSPE chirp | paper SE chirp |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    let cell = |v: Option<f64>| v.map_or("–".to_owned(), |v| format!("{v:.4}"));
    let mut cutoffs = Vec::new();
    for (name, o) in &report.outputs {
        // The paper's models first, then the linear block and the simple references.
        for kind in [
            ModelKind::GrayBox,
            ModelKind::HammersteinWiener,
            ModelKind::Nnarx,
            ModelKind::Linear,
            ModelKind::Arx,
            ModelKind::HammersteinArx,
            ModelKind::StaticCubic,
        ] {
            let model = kind;
            if !o.models.contains_key(&model) {
                continue;
            }
            let paper = Quantity::of(name).and_then(|p| kind.paper_table1(p));
            let (pa, pb, pc, pd) = paper.map_or((None, None, None, None), |t| {
                (Some(t.rmspe_pct), Some(t.se), Some(t.rmspe_chirp_pct), Some(t.se_chirp))
            });
            let _ = writeln!(
                out,
                "| {name} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                kind.title(),
                cell(role_mean(report, o, model, false, |m| m.rmspe_pct)),
                cell(role_mean(report, o, model, false, |m| m.se)),
                cell(role_mean(report, o, model, true, |m| m.rmspe_pct)),
                cell(role_mean(report, o, model, true, |m| m.se)),
                cell(pa),
                cell(pb),
                cell(pc),
                cell(pd)
            );
        }
        if !o.cutoff_rad_s.is_empty() {
            let cuts: Vec<String> = o
                .cutoff_rad_s
                .iter()
                .map(|(k, v)| {
                    format!(
                        "{} {}",
                        curve_title(*k),
                        v.map_or("not reached".to_owned(), |c| format!("{c:.3} rad/s"))
                    )
                })
                .collect();
            cutoffs.push(format!("−3 dB cut-off of `{name}` on the chirp: {}.", cuts.join("; ")));
        }
    }
    for c in cutoffs {
        let _ = writeln!(out, "\n{c}");
    }
}

fn noise_and_monte_carlo_section(out: &mut String, report: &Report) {
    if let Some(serde_json::Value::Object(fits)) = &report.noise_fit {
        let _ = writeln!(out, "\n## Noise fit of the steady run (maximum likelihood)\n");
        let _ = writeln!(out, "| channel | best | log-likelihoods |\n|---|---|---|");
        for (channel, fit) in fits {
            let lls: Vec<String> = fit["fits"]
                .as_array()
                .map(|a| {
                    a.iter()
                        .map(|f| {
                            format!(
                                "{} {:.3}",
                                f["distribution"]["family"].as_str().unwrap_or("?"),
                                f["log_likelihood"].as_f64().unwrap_or(f64::NAN)
                            )
                        })
                        .collect()
                })
                .unwrap_or_default();
            let _ = writeln!(
                out,
                "| {channel} | {} | {} |",
                fit["best_by_log_likelihood"].as_str().unwrap_or("?"),
                lls.join(", ")
            );
        }
    }
    if let Some(serde_json::Value::Object(mc)) = &report.monte_carlo {
        let _ = writeln!(
            out,
            "\n## Monte Carlo error propagation\n\n100 runs of 20 s at the steady run's mean input from a zero initial condition, input noise drawn from the input's best-fitting distribution; std of noisy − nominal output (paper: gray-box 6.035 rpm / 0.0136 N, HW 14.08 / 0.0352, NNARX 26.5 / 0.1064).\n"
        );
        let _ =
            writeln!(out, "| output | model | std of difference | mean of difference |\n|---|---|---|---|");
        for (output, models) in mc {
            if let serde_json::Value::Object(models) = models {
                for (model, r) in models {
                    let _ = writeln!(
                        out,
                        "| {output} | {} | {:.5} | {:.5} |",
                        model_title(model),
                        r["std_difference"].as_f64().unwrap_or(f64::NAN),
                        r["mean_difference"].as_f64().unwrap_or(f64::NAN)
                    );
                }
            }
        }
    }
}

/// "Where it fails": per scored run the plain-words summary, the error by regime and the worst
/// stretches.
fn residuals_section(out: &mut String, residuals: &[ResidualReport], unit: &str) {
    if residuals.is_empty() {
        return;
    }
    let _ = writeln!(out, "\n### Where it fails (residual = measured − final model)");
    for r in residuals {
        let applies = if r.noise_band_applies { "" } else { "; the band does not apply here" };
        let _ = writeln!(
            out,
            "\n**{}**: {} (Noise σ from the {}{applies}.)\n",
            r.run, r.summary, r.noise_sigma_source
        );
        let _ = writeln!(
            out,
            "| regime | share of samples % | RMSE {unit} | RMSPE % | bias {unit} | share of squared error % |\n|---|---|---|---|---|---|"
        );
        let opt = |v: Option<f64>| v.map_or_else(|| "–".to_owned(), |v| format!("{v:.4}"));
        for row in &r.regimes {
            let _ = writeln!(
                out,
                "| {} | {:.1} | {} | {} | {} | {:.1} |",
                row.regime.label(),
                row.share_of_samples_pct,
                opt(row.rmse),
                opt(row.rmspe_pct),
                opt(row.mean_error),
                row.share_of_squared_error_pct
            );
        }
        let stretches: Vec<String> = r
            .worst_stretches
            .iter()
            .map(|s| {
                let motion = format!("{:?}", s.motion).to_lowercase();
                format!("{:.1}–{:.1} s (RMS {:.4}, mostly {motion})", s.start_secs, s.end_secs, s.rms)
            })
            .collect();
        if !stretches.is_empty() {
            let _ = writeln!(out, "\nWorst stretches: {}.", stretches.join("; "));
        }
        if let Some(f) = &r.figure {
            let _ = writeln!(out, "\n![residuals of {}]({f})", r.run);
        }
    }
}

/// Operating points and the continuous-time equivalent, for a controller designer; u* is in
/// `input_unit`, y* in the output's and dy/du in the output's per the input's.
fn control_section(out: &mut String, o: &OutputReport, input_unit: &str) {
    if o.operating_points.is_empty() && o.continuous.is_none() {
        return;
    }
    let _ = writeln!(out, "\n### Operating points (local linear models for control design)\n");
    if let Some(c) = &o.continuous {
        let _ = writeln!(
            out,
            "Linear block as a continuous-time system (zero-order-hold equivalent, s in rad/s): {}.\n",
            continuous_text(c)
        );
    }
    if o.operating_points.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "Local model at each point: K·G(z)/G(1), K the local gain dy/du, with the effects linearised there. \
         Poles as τ (real) or ωn, ζ (pairs), from their zero-order-hold equivalents. \
         `x −a/+b`: the 95 % interval from x − a to x + b, the 2.5 and 97.5 percentiles over models drawn \
         from the parameter covariance (report.json: `*_ci95`).\n\n\
         | point | u*{u_unit} | y*{unit} | dy/du [{gain_unit}] | poles | −3 dB bandwidth (rad/s) | rise 10–90 % (s) | settling 2 % (s) | overshoot % |\n\
         |---|---|---|---|---|---|---|---|---|",
        u_unit = crate::core::run::bracketed_unit(input_unit),
        unit = crate::core::run::bracketed_unit(&o.unit),
        gain_unit = gain_unit(&o.unit, input_unit),
    );
    let opt = |x: Option<f64>, ci: Option<[f64; 2]>, digits: usize| {
        x.map_or("–".to_owned(), |v| with_interval(v, ci, digits))
    };
    for p in &o.operating_points {
        let source = match &p.source {
            crate::core::control::PointSource::Grid => "grid".to_owned(),
            crate::core::control::PointSource::SteadyRun(run) => format!("steady run `{run}`"),
        };
        let poles: Vec<String> = p.poles.iter().map(pole_with_interval).collect();
        let _ = writeln!(
            out,
            "| {source} | {:.4} | {:.4} | {} | {} | {} | {} | {} | {:.1} |",
            p.u,
            p.y,
            with_interval(p.gain, p.gain_ci95, 5),
            poles.join("; "),
            opt(p.bandwidth_rad_s, p.bandwidth_rad_s_ci95, 3),
            opt(p.step.rise_s, p.step.rise_s_ci95, 3),
            opt(p.step.settling_s, p.step.settling_s_ci95, 3),
            p.step.overshoot_pct
        );
    }
}

/// The final model's numbers with their 95 % intervals (report.json `parameter_intervals`).
fn parameters_section(out: &mut String, o: &OutputReport) {
    if o.parameter_intervals.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\n### Parameter uncertainty\n\n\
         The final model's numbers with their 95 % intervals: 2.5 and 97.5 percentiles over models drawn \
         from the covariance of its fit to the identification run (stored in model.json). *not estimated*: \
         a number the covariance does not move (set by the structure, or solved from the others inside \
         its effect's own fit), so its spread is not known here; –: fewer than 90 % of the draws have it (a drawn pole on the \
         negative real axis has no continuous-time equivalent).\n\n\
         | number | value | 95 % interval |\n|---|---|---|"
    );
    for p in &o.parameter_intervals {
        let interval = match p.ci95 {
            Some([lo, hi]) if hi <= lo => "not estimated".to_owned(),
            Some([lo, hi]) => format!("{} … {}", significant(lo), significant(hi)),
            None => "–".to_owned(),
        };
        let _ = writeln!(out, "| {} | {} | {interval} |", p.name, significant(p.value));
    }
}

/// Six significant digits, in scientific notation outside 0.001 to 10⁶.
fn significant(x: f64) -> String {
    match x.abs() {
        a if a == 0.0 || (1e-3..1e6).contains(&a) => {
            let digits = (5 - a.log10().floor().max(0.0) as i32).max(0) as usize;
            format!("{x:.digits$}")
        }
        _ => format!("{x:.5e}"),
    }
}

/// `value −a/+b`: the value and how far its 95 % interval reaches below and above it (the
/// operating points' intervals are percentiles of drawn models, not symmetric); the value alone
/// without an interval.
pub fn with_interval(value: f64, ci95: Option<[f64; 2]>, digits: usize) -> String {
    match ci95 {
        Some([lo, hi]) => {
            let sig = digits.min(3);
            format!("{value:.digits$} −{:.sig$}/+{:.sig$}", (value - lo).max(0.0), (hi - value).max(0.0))
        }
        None => format!("{value:.digits$}"),
    }
}

/// A local pole as `τ 1.820 −0.1/+0.2 s` or `ωn …, ζ …`, with its intervals where it has them.
pub fn pole_with_interval(p: &crate::core::control::LocalPole) -> String {
    match (p.tau_s, p.wn_rad_s, p.zeta) {
        (Some(tau), _, _) => format!("τ {} s", with_interval(tau, p.tau_s_ci95, 3)),
        (None, Some(wn), Some(zeta)) => {
            format!("ωn {}, ζ {}", with_interval(wn, p.wn_rad_s_ci95, 3), with_interval(zeta, p.zeta_ci95, 3))
        }
        _ => p.describe(3),
    }
}

/// The unit of a local gain dy/du: the output's per the input's ("rpm/V", "rpm/(gal/h)"); "per input
/// unit" when the input's unit is unknown.
pub fn gain_unit(output_unit: &str, input_unit: &str) -> String {
    let output_unit = if output_unit.is_empty() { "1" } else { output_unit };
    match input_unit {
        "" => format!("{output_unit} per input unit"),
        u if u.contains(['/', '·', ' ', '*']) => format!("{output_unit}/({u})"),
        u => format!("{output_unit}/{u}"),
    }
}

/// `e^(−0.2 s)·(b0 s + b1)/(s² + a1 s + a2)` with six significant digits.
pub fn continuous_text(c: &crate::core::control::ContinuousTf) -> String {
    let poly = |coeffs: &[f64]| {
        let n = coeffs.len().saturating_sub(1);
        let terms: Vec<String> = coeffs
            .iter()
            .enumerate()
            .filter(|(_, x)| **x != 0.0)
            .map(|(i, x)| match n - i {
                0 => format!("{x:.6e}"),
                1 => format!("{x:.6e}·s"),
                p => format!("{x:.6e}·s^{p}"),
            })
            .collect();
        if terms.is_empty() { "0".to_owned() } else { terms.join(" + ") }
    };
    let delay = if c.delay_secs > 0.0 { format!("e^(−{:.4}·s)·", c.delay_secs) } else { String::new() };
    format!("{delay}({}) / ({})", poly(&c.num_s), poly(&c.den_s))
}

/// The error after each step of the effects, when there were any.
fn error_history_line(out: &mut String, o: &OutputReport) {
    if !o.error_history.is_empty() {
        let _ = writeln!(
            out,
            "\nError history: {}",
            o.error_history
                .iter()
                .map(|h| format!("{} {:.4} %", h.step, h.rmspe_pct))
                .collect::<Vec<_>>()
                .join(" → ")
        );
    }
}

/// The diagnosis of the final model, best first, when there is one.
fn diagnosis_table(out: &mut String, o: &OutputReport) {
    if !o.diagnosis.is_empty() {
        let _ = writeln!(
            out,
            "\n### Diagnosis\n\nStructural refinements and physical effects are judged alike, by their error \
             beyond the measurement noise (in units of the noise, 'beyond noise'; the ranking follows it): \
             an effect counts only when it beats the current model, its evidence agrees and the data \
             prefer it to the best refinement. Each trial is judged on the validation runs and, where the \
             identification data have enough segments, on the segment responses a cross-validation held \
             out (the 'held-out' column).\n\n\
             | effect | kind | significant | RMSPE before % | after % | beyond noise after | held-out after % | p | evidence | witnesses |\n\
             |---|---|---|---|---|---|---|---|---|---|"
        );
        for d in &o.diagnosis {
            let held_out = d.held_out_rmspe_pct.map_or_else(|| "–".to_owned(), |h| format!("{h:.4}"));
            let p = d.p_value.map_or_else(|| "–".to_owned(), crate::core::diagnose::p_text);
            let beyond = d.beyond_noise_after.map_or_else(|| "–".to_owned(), |b| format!("{b:.2} σ"));
            let _ = writeln!(
                out,
                "| {} | {} | {} | {:.4} | {:.4} | {beyond} | {held_out} | {p} | {} | {} |",
                d.effect,
                d.kind,
                d.significant,
                d.rmspe_before_pct,
                d.rmspe_after_pct,
                d.evidence,
                d.significance
            );
        }
    }
}

/// The Markdown report: the same numbers as report.json, as tables a person reads.
pub fn render_markdown(report: &Report) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# jetid report — {}\n", report.project);
    let _ = writeln!(out, "Input: `{}`. Runs:\n", report.input);
    for (role, run) in &report.runs {
        let _ = writeln!(out, "- {role}: `{run}`");
    }
    for (name, o) in &report.outputs {
        let _ = writeln!(out, "\n## Output `{name}`{}\n", crate::core::run::bracketed_unit(&o.unit));
        ident_section(&mut out, &o.identified, &o.unit);
        let _ = writeln!(
            out,
            "\n### Validation (each model simulated from the input alone; initial state {}: {})\n",
            o.initial_state, o.initial_state_meaning
        );
        metrics_table(&mut out, o);
        if let Some(sentence) = &o.steady_states {
            let _ = writeln!(out, "\n**Steady states across runs:** {sentence}.");
        }
        if let Some(choice) = &o.preparation {
            let _ = writeln!(out, "\n**Preparation:** {}.", choice.sentence(name));
        }
        error_history_line(&mut out, o);
        diagnosis_table(&mut out, o);
        control_section(&mut out, o, &report.input_unit);
        parameters_section(&mut out, o);
        residuals_section(&mut out, &o.residuals, &o.unit);
    }
    table1_section(&mut out, report);
    noise_and_monte_carlo_section(&mut out, report);
    if !report.figures.is_empty() {
        let _ = writeln!(out, "\n## Figures\n");
        for f in &report.figures {
            let _ = writeln!(out, "![{f}]({f})\n");
        }
    }
    if !report.diagnostics.is_empty() {
        let _ = writeln!(out, "\n## Notes\n");
        for d in &report.diagnostics {
            let _ = writeln!(out, "- {d}");
        }
    }
    let timings: Vec<String> = report.timings_ms.iter().map(|(k, v)| format!("{k} {v:.1} ms")).collect();
    let _ = writeln!(out, "\nTimings: {}.", timings.join(", "));
    out
}

pub fn write_report_md(path: &Path, report: &Report) -> Result<()> {
    write_atomic(path, render_markdown(report).as_bytes())
}
