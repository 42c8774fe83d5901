//! A residual analysis in two to four plain sentences, derived from its numbers only.
use super::ResidualAnalysis;
use super::correlation::{ChannelScan, Correlogram, InputCrossCorrelation};
use super::regimes::{Regime, RegimeTable};
use super::spectrum::ResidualSpectrum;

/// RMSE ratio between two regimes worth a sentence.
const NOTABLE_RATIO: f64 = 1.5;
/// Spectral peak over the median PSD worth a sentence (10 dB).
const NOTABLE_PROMINENCE: f64 = 10.0;
/// A cross-correlation peak worth a sentence lies this far beyond the 99 % bound (about 3.9σ, so
/// chance gives one among ~60 lags in about 0.5 % of white residuals).
const NOTABLE_BOUND_FACTOR: f64 = 1.5;
/// |r| of an unused channel worth mentioning even when too few effective samples make it
/// insignificant (both drift slowly through the run).
const NOTABLE_CHANNEL_R: f64 = 0.7;

/// Three significant figures, no exponent for everyday magnitudes.
fn fmt3(x: f64) -> String {
    match x.abs() {
        a if a >= 100.0 => format!("{x:.0}"),
        a if a >= 10.0 => format!("{x:.1}"),
        a if a >= 1.0 => format!("{x:.2}"),
        _ => format!("{x:.3}"),
    }
}

fn rmse(table: &RegimeTable, regime: Regime) -> Option<f64> {
    table.row(regime).and_then(|r| r.rmse)
}

fn overall(a: &ResidualAnalysis) -> String {
    let unit = &a.unit;
    let whole = a.regimes.row(Regime::Run);
    let (rms, bias) =
        (whole.and_then(|r| r.rmse).unwrap_or(0.0), whole.and_then(|r| r.mean_error).unwrap_or(0.0));
    let b = &a.band;
    let head =
        format!("The {} residual has RMS {} {unit} and mean {} {unit}", a.output, fmt3(rms), fmt3(bias));
    if let Some(why) = b.why_not(unit) {
        return format!("{head}; {why}.");
    }
    let estimated = match b.sigma_source {
        super::SigmaSource::Supplied => "",
        super::SigmaSource::EstimatedFromSecondDifferences => ", estimated from the run",
    };
    format!(
        "{head}; {:.1} % of the samples lie outside the ±{}σ noise band (σ = {} {unit}{estimated}), where \
         noise alone would leave {:.1} %.",
        100.0 * b.outside_fraction,
        b.band_sigmas,
        fmt3(b.sigma),
        100.0 * b.expected_outside_fraction,
    )
}

/// "X× worse" between two regimes when the ratio is notable.
fn worse(table: &RegimeTable, unit: &str, pairs: &[(Regime, Regime, &str, &str)]) -> Option<String> {
    pairs.iter().find_map(|&(a, b, name_a, name_b)| {
        let (ra, rb) = (rmse(table, a)?, rmse(table, b)?);
        let (hi, lo, hi_name, lo_name) =
            if ra >= rb { (ra, rb, name_a, name_b) } else { (rb, ra, name_b, name_a) };
        (lo > 0.0 && hi / lo >= NOTABLE_RATIO).then(|| {
            format!(
                "{hi_name} are {:.1}× worse than {lo_name} (RMSE {} vs {} {unit})",
                hi / lo,
                fmt3(hi),
                fmt3(lo)
            )
        })
    })
}

/// The error at the worst operating point against the best, when notable.
fn worst_operating_point(table: &RegimeTable, unit: &str) -> Option<String> {
    let rows: Vec<(Regime, f64)> =
        [Regime::Low, Regime::Mid, Regime::High].iter().filter_map(|&r| Some((r, rmse(table, r)?))).collect();
    let hi = rows.iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    let lo = rows.iter().min_by(|a, b| a.1.total_cmp(&b.1))?;
    (lo.1 > 0.0 && hi.1 / lo.1 >= NOTABLE_RATIO).then(|| {
        format!(
            "the error is largest at the {} (RMSE {} vs {} {unit} at the {})",
            hi.0.label(),
            fmt3(hi.1),
            fmt3(lo.1),
            lo.0.label()
        )
    })
}

fn regimes(a: &ResidualAnalysis) -> String {
    let t = &a.regimes;
    let transient = t.row(Regime::Transient);
    let (share_sq, share_n) =
        transient.map_or((0.0, 0.0), |r| (r.share_of_squared_error_pct, r.share_of_samples_pct));
    let head = if share_n <= 0.0 {
        "The measured output never moves fast enough to count as transient".to_owned()
    } else if share_n >= 100.0 {
        "Every sample is transient".to_owned()
    } else {
        format!(
            "{share_sq:.0} % of the squared error is in transients, which are {share_n:.0} % of the samples"
        )
    };
    let motion = [(Regime::Decelerating, Regime::Accelerating, "decelerations", "accelerations")];
    let detail = worse(t, &a.unit, &motion).or_else(|| worst_operating_point(t, &a.unit));
    match detail {
        Some(d) => format!("{head}; {d}."),
        None => format!("{head}."),
    }
}

fn input_sentence(x: &InputCrossCorrelation) -> Option<String> {
    (x.peak_value.abs() > NOTABLE_BOUND_FACTOR * x.correlogram.bound_99).then(|| {
        let who = match x.peak_lag_samples {
            l if l > 0 => "input leading",
            l if l < 0 => "residual leading",
            _ => "no lag",
        };
        format!(
            "The residual–{} cross-correlation peaks at {:+} samples ({} s, {who}) with r = {} \
             (99 % bound ±{}).",
            x.input,
            x.peak_lag_samples,
            fmt3(x.peak_lag_secs),
            fmt3(x.peak_value),
            fmt3(x.correlogram.bound_99),
        )
    })
}

fn channel_sentence(scan: &ChannelScan) -> Option<String> {
    let top = scan.channels.first()?;
    let (r, slow) = top.strongest();
    if !top.significant && r.abs() < NOTABLE_CHANNEL_R {
        return None;
    }
    let how = if slow { format!(" on {} s averages", fmt3(scan.slow_window_secs)) } else { String::new() };
    let n_eff = if slow { top.n_eff_slow } else { top.n_eff };
    let verdict = if top.significant {
        String::new()
    } else {
        format!(", though both drift so slowly that this run holds only ~{n_eff:.0} independent samples")
    };
    let twins = match top.collinear_with.as_slice() {
        [] => String::new(),
        [one] => format!("; {one} moves with it, so the two cannot be told apart here"),
        many => format!("; {} move with it, so they cannot be told apart here", many.join(" and ")),
    };
    Some(format!(
        "Of the {} recorded channels the model does not use, the residual tracks {} most closely \
         (r = {}{how}{verdict}){twins}.",
        scan.channels.len(),
        top.channel,
        fmt3(r),
    ))
}

fn spectrum_sentence(s: &ResidualSpectrum) -> Option<String> {
    if s.peak_prominence < NOTABLE_PROMINENCE {
        return None;
    }
    let lowest_bins = s.freq_hz.get(2).copied().unwrap_or(0.0);
    Some(if s.peak_freq_hz <= lowest_bins {
        format!(
            "The residual's power sits at the lowest frequencies (peak at {} Hz, {:.0}× the median \
             level): a slow drift, not a resonance.",
            fmt3(s.peak_freq_hz),
            s.peak_prominence
        )
    } else {
        format!(
            "The residual spectrum peaks at {} Hz ({} rad/s), {:.0}× its median level.",
            fmt3(s.peak_freq_hz),
            fmt3(s.peak_omega_rad_s),
            s.peak_prominence
        )
    })
}

fn whiteness_sentence(acf: &Correlogram) -> String {
    let lags = acf.lags_samples.len().saturating_sub(1);
    let over = acf.exceeding_lags_samples.len();
    let lag1 = acf.values.get(1).copied().unwrap_or(0.0);
    if over * 20 <= lags {
        format!(
            "The residual is close to white: {over} of {lags} autocorrelation lags exceed the 99 % bound."
        )
    } else {
        format!(
            "The residual is not white: {over} of {lags} autocorrelation lags exceed the 99 % bound \
             (lag 1: {}), so the model misses dynamics or a slow effect.",
            fmt3(lag1)
        )
    }
}

/// Input dips the output does not follow: the input sensor, not the engine (only when they are).
fn dropout_sentence(d: &super::InputDropouts) -> Option<String> {
    d.sensor_dropouts.then(|| {
        format!(
            "The input {} dips {} times for up to {:.1} s (by up to {:.0} % of its range) and returns, but the \
             output does not follow (its excursion over the dips is {:.0} % of the one the model predicts): \
             the input sensor reads dropouts the engine does not see ({:.0} % of the squared error sits \
             there); repair or gate the input channel rather than look for missing physics.",
            d.input,
            d.count,
            d.longest_secs,
            d.deepest_pct,
            // No "-0 %" for a share that rounds to nothing.
            if d.output_follows_pct.abs() < 0.5 { 0.0 } else { d.output_follows_pct },
            d.residual_share_pct
        )
    })
}

/// Two to four sentences an engine engineer can act on: overall error against the noise, where the
/// error lives by regime, then the two most telling of input timing, an unused channel, a spectral
/// peak and whiteness.
pub fn summary_sentences(a: &ResidualAnalysis) -> Vec<String> {
    let findings = [
        a.input_dropouts.as_ref().and_then(dropout_sentence),
        a.input_xcorr.as_ref().and_then(input_sentence),
        channel_sentence(&a.channels),
        spectrum_sentence(&a.spectrum),
        Some(whiteness_sentence(&a.autocorrelation)),
    ];
    [overall(a), regimes(a)].into_iter().chain(findings.into_iter().flatten().take(2)).collect()
}

/// [`summary_sentences`] as one paragraph.
pub fn summary(a: &ResidualAnalysis) -> String {
    summary_sentences(a).join(" ")
}
