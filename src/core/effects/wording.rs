//! Time differences in the evidence sentences. A difference is measured as "measured minus model",
//! so a negative one is a lead, and the sentence says so rather than printing a minus sign after
//! "lags" or "after".

/// Differences that round to zero at the two decimals shown read as "after" and "lags".
const SHOWN_RESOLUTION_SECS: f64 = 0.005;

/// "0.06 s after", or "0.06 s before" when `secs` is negative.
pub(super) fn after_or_before(secs: f64) -> String {
    if secs <= -SHOWN_RESOLUTION_SECS {
        format!("{:.2} s before", -secs)
    } else {
        format!("{:.2} s after", secs.abs())
    }
}

/// "lags" and the amount, or "leads" and the amount when `secs` is negative.
pub(super) fn lags_or_leads(secs: f64) -> (&'static str, String) {
    if secs <= -SHOWN_RESOLUTION_SECS {
        ("leads", format!("{:.2} s", -secs))
    } else {
        ("lags", format!("{:.2} s", secs.abs()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_negative_difference_reads_as_before_and_leads() {
        assert_eq!(after_or_before(0.07), "0.07 s after");
        assert_eq!(after_or_before(-0.06), "0.06 s before");
        assert_eq!(after_or_before(-0.001), "0.00 s after", "no '-0.00'");
        assert_eq!(lags_or_leads(0.12), ("lags", "0.12 s".to_owned()));
        assert_eq!(lags_or_leads(-0.07), ("leads", "0.07 s".to_owned()));
    }
}
