//! Which physical effect a run shows that its engine's reference lacks: the diagnosis of the
//! model-building workflow (`core::diagnose`), run on one fleet run against the reference.
//!
//! **Fitted on one part of the run, judged on the other.** The diagnosis needs data to fit each
//! trial on and runs to judge it on that the fit never saw. A fleet run is one log, so it is split in
//! two at the step boundary nearest its middle: the trials (the reference refitted, then each effect
//! of the catalog and each structural refinement added to it) are fitted on the first part, with the
//! cross-validation over its steps when it has enough of them, and judged on the second. The test is
//! the diagnosis's own: the same significance level, the same smallest reduction, the same evidence
//! from the residuals; nothing here decides which effect a run has. Since every trial starts from the
//! reference refitted on the run, a trial is credited only with what its block adds beyond what the
//! health deltas already move (gain, time constants, map): a drifted meter is not read as an effect.
//! Only physics is reported; the reference's structure is the engine's and stays as it is.
//!
//! **Not on a supply fault.** The samples from the first stretch where the input sits at its limit
//! while the output falls short of the reference (the flag's "fuel supply") are left out: no effect of
//! the catalog models a supply that fails, and the flag already names it.
//!
//! **Which runs.** The diagnosis refits fifteen trials per output, about a hundred times a run's
//! scoring, so it runs on the runs that show something to explain: those flagged, and those whose
//! error is above its engine's normal band (the band's upper limit, without the flag's margin; see
//! [`screened`]). A run inside its band on every output fits as well as its engine's healthy runs,
//! which leaves a missing effect too little of the error to be found on one run.
use anyhow::{Context, Result};

use crate::core::control::bands::parameter_intervals;
use crate::core::diagnose::{DiagnosisKind, diagnose};
use crate::core::effects::ExtendedModel;
use crate::core::identification::fits::fit_segments_for;
use crate::core::identification::segment::Segment;
use crate::core::identification::settings::OutputSettings;
use crate::core::run::Run;
use crate::workflow::runs::{segments, steps_from};
use crate::workflow::uncertainty::parameter_covariance;

use super::EngineResult;
use super::finding::{Finding, RunDiagnosis};
use super::flags::{EngineBands, quantity_word};
use super::manifest::FleetRun;
use super::reference::Reference;
use super::score::{INITIAL, RunScore, read_run};

/// Fewest steps each part of a split run must hold: the first part's segment models need two (see
/// `fit_segments`), and a judge run with fewer than two set-point changes says little about
/// dynamics.
const MIN_STEPS_PER_PART: usize = 2;

/// The runs (indices in the engine's trend order) the diagnosis runs on: flagged, or with an error
/// above the engine's band on some output.
pub fn screened(bands: &EngineBands, scores: &[RunScore]) -> Vec<usize> {
    (0..scores.len())
        .filter(|&i| {
            let run = &scores[i];
            !bands.all_reasons(i, run).is_empty()
                || run.outputs.iter().any(|o| bands.rmse_band(&o.output).is_some_and(|b| o.rmse > b.high()))
        })
        .collect()
}

/// The diagnosis of `run` against `reference` on every output the run holds; `score` is the run's
/// score (its starved stretches are left out).
pub fn diagnose_run(run: &FleetRun, reference: &Reference, score: &RunScore) -> Result<RunDiagnosis> {
    // Read again rather than kept from the scoring: a fleet holds no run's samples in memory, and
    // only the few screened runs are read twice.
    let data = read_run(run, reference, &mut Vec::new())?;
    let end = score.starved.iter().map(|s| s.start).min().unwrap_or(data.len());
    Ok(diagnose_samples(&data, end, reference))
}

/// The diagnosis of the run `data` (read on the reference's sample time) up to sample `end`.
pub fn diagnose_samples(data: &Run, end: usize, reference: &Reference) -> RunDiagnosis {
    let mut out = RunDiagnosis::default();
    let end = end.min(data.len());
    let Some((first, second)) = split(&data.slice(0..end)) else {
        out.notes.push(format!(
            "run '{}': not diagnosed: fewer than {} steps on each side of its middle{}",
            data.name,
            MIN_STEPS_PER_PART,
            if end < data.len() { " before its input reaches its limit" } else { "" }
        ));
        return out;
    };
    // The first part's steps, found once for every output.
    let channel = steps_from(&first, &[], None);
    let parts = segments(&first, &[], None, channel.channel()).map_err(anyhow::Error::from);
    for model in &reference.models {
        if data.output(&model.output).is_none() {
            continue;
        }
        let found = match &parts {
            Ok(parts) => findings_of(model, &first, parts, &second),
            Err(e) => Err(anyhow::anyhow!("{e:#}")),
        };
        match found {
            Ok(found) => {
                out.diagnosed.push(model.output.clone());
                out.findings.extend(found);
            }
            Err(e) => out.notes.push(format!(
                "run '{}': {} not diagnosed: {e:#}",
                data.name,
                quantity_word(&model.output)
            )),
        }
    }
    out
}

/// The run cut at the step boundary nearest its middle, when each part holds enough steps.
fn split(run: &Run) -> Option<(Run, Run)> {
    let channel = steps_from(run, &[], None);
    let found = segments(run, &[], None, channel.channel()).ok()?;
    let middle = run.len() / 2;
    let k = (MIN_STEPS_PER_PART..=found.len().checked_sub(MIN_STEPS_PER_PART)?)
        .min_by_key(|&k| found[k].start.abs_diff(middle))?;
    let cut = found[k].start;
    let mut first = run.slice(0..cut);
    let mut second = run.slice(cut..run.len());
    first.name = format!("{} (first part)", run.name);
    second.name = format!("{} (second part)", run.name);
    Some((first, second))
}

/// The first significant physics of one output's diagnosis (the effect its loop would add), with
/// its parameters' intervals and the other significant physics, which explain less of the same
/// residual.
fn findings_of(
    model: &ExtendedModel,
    first: &Run,
    parts: &[Segment],
    second: &Run,
) -> Result<Option<Finding>> {
    let settings = OutputSettings { initial_state: INITIAL, ..OutputSettings::for_output(&model.output) };
    let fits = fit_segments_for(first, &model.output, parts, &settings)?;
    let report = diagnose(model, first, &fits, &[second], &settings)?;
    let mut significant = report
        .entries
        .iter()
        .filter(|d| d.significant && d.kind == DiagnosisKind::Physics)
        .filter_map(|d| Some((d, d.effect.as_effect()?)));
    let Some((entry, effect)) = significant.next() else { return Ok(None) };
    let params = parameter_covariance(&fits, &entry.model, first, &settings)
        .and_then(|c| parameter_intervals(&entry.model, &c))
        .map(|all| all.into_iter().filter(|p| p.name.starts_with(&format!("{effect}."))).collect())
        .unwrap_or_default();
    Ok(Some(Finding {
        output: model.output.clone(),
        effect,
        p_value: entry.test.p_value,
        beyond_noise_before: entry.beyond_noise_before,
        beyond_noise_after: entry.beyond_noise_after,
        evidence: entry.evidence.clone(),
        params,
        also: significant.map(|(d, id)| (id, d.beyond_noise_after)).collect(),
    }))
}

/// Diagnose the screened runs of every engine, one after another (each diagnosis fits its trials on
/// both threads), each result stored with its run's score; `progress` hears the fraction of them
/// done before each and stops the work when it answers `false` (`Ok(false)`).
pub fn diagnose_screened(
    results: &mut [EngineResult<'_>],
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<bool> {
    let jobs: Vec<(usize, usize)> = results
        .iter()
        .enumerate()
        .flat_map(|(e, r)| screened(&r.bands, &r.scores).into_iter().map(move |i| (e, i)))
        .collect();
    for (done, &(e, i)) in jobs.iter().enumerate() {
        if !progress(done as f64 / jobs.len() as f64) {
            return Ok(false);
        }
        let r = &results[e];
        let (run, engine) = (&r.engine.runs[i], &r.engine.name);
        let diagnosis = diagnose_run(run, &r.reference, &r.scores[i])
            .with_context(|| format!("diagnosing engine '{engine}', run '{}'", run.name))?;
        results[e].scores[i].diagnosis = Some(diagnosis);
    }
    Ok(progress(1.0))
}
