//! The spool's power balance read through the static map: the time-constant factor a spool section
//! runs with when its schedule is the physical one rather than an exponential in the operating
//! point.
use super::StaticMapOrder;
use crate::core::identification::static_map::StaticMap;

/// The spool's power balance `J ω ω̇ = P_t − P_c`, in the section's own coordinate `x` (the unit-gain
/// state of the split linear block, in input units: the steady input of the state's operating
/// point). With `N = f(v)` the static map (its kink included) at `v = gain·x + offset`, and the
/// turbine power at the operating point of `x` written `P(x) = (f_s(v)/f_s(v_ref))^k`, where `f_s`
/// is the map's smooth polynomial (without the kink) and `k` the compressor's load exponent, the
/// balance reads `Ṅ = K (P(r) − P(x)) / n(x)`, so `ẋ = K (P(r) − P(x)) / (n(x) f′(v) gain)`.
///
/// Why the smooth polynomial for the power and the whole map for `N`: a bleed valve or any load
/// that switches on above a speed puts a kink into the map `f` (more power absorbed, less speed
/// for the same fuel) while the turbine power the fuel gives stays smooth; then the spool's local
/// time constant `n f′/(K P′)` drops by the same ratio as the map's slope does at the kink, which
/// is what such an engine does. Without a kink, `f = f_s` and the section is exactly the
/// simulator-form balance `Ṅ ∝ (n_r^k − n^k)/n`: local time constant `∝ N^(2−k)`, and over a large
/// step the rate of the power surplus, not of a linear lag.
///
/// [`PowerBalance::factor`] is the effective time constant `(r − x)/ẋ` over the one at the
/// reference operating point (`x = r = ref_x`), so the linear block's spool pole keeps its meaning:
/// the time constant at the reference point.
#[derive(Clone, Debug, PartialEq)]
pub struct PowerBalance {
    pub gain: f64,
    pub offset: f64,
    pub map: StaticMap,
    pub kink: Option<StaticMapOrder>,
    /// Load exponent `k` (compressor power ∝ N^k; 3 for τ ∝ 1/N).
    pub exponent: f64,
    /// The reference operating point, in the section's coordinate.
    pub ref_x: f64,
    /// The smooth map and the whole map at the reference point, and `(r − x)/ẋ` there; `None`
    /// where the map gives no positive speed (the factor is then 1).
    reference: Option<(f64, f64, f64)>,
}

/// Bounds of the factor: a time constant 20 times shorter or longer than at the reference point
/// (the same span the exponential schedule allows, `MAX_LOG_RATIO = 3`).
const FACTOR_BOUNDS: (f64, f64) = (0.05, 20.0);

impl PowerBalance {
    pub fn new(
        gain: f64,
        offset: f64,
        map: StaticMap,
        kink: Option<StaticMapOrder>,
        exponent: f64,
        ref_x: f64,
    ) -> Self {
        let mut b = Self { gain, offset, map, kink, exponent, ref_x, reference: None };
        let v_ref = b.v(ref_x);
        let (smooth_ref, speed_ref) = (b.smooth(v_ref), b.speed(v_ref));
        if smooth_ref > 0.0 && speed_ref > 0.0 {
            b.reference =
                b.time_constant(ref_x, ref_x, smooth_ref, speed_ref).map(|tau| (smooth_ref, speed_ref, tau));
        }
        b
    }

    fn v(&self, x: f64) -> f64 {
        self.gain * x + self.offset
    }

    fn speed(&self, v: f64) -> f64 {
        self.smooth(v) + self.kink_value(v)
    }

    /// The map's smooth polynomial, without the kink: what the turbine power is read through.
    fn smooth(&self, v: f64) -> f64 {
        self.map.eval(v)
    }

    fn kink_value(&self, v: f64) -> f64 {
        self.kink.as_ref().map_or(0.0, |k| k.eval(v))
    }

    fn kink_slope(&self, v: f64) -> f64 {
        self.kink.as_ref().map_or(0.0, |k| if v > k.knot_v { k.slope_change } else { 0.0 })
    }

    /// `(r − x)/ẋ` up to the constant `K`, or `None` where the map gives no positive speed. The
    /// map and its slope at `x` are evaluated once (this runs on every sample of a simulation).
    fn time_constant(&self, x: f64, r: f64, smooth_ref: f64, speed_ref: f64) -> Option<f64> {
        let v = self.v(x);
        let (smooth, smooth_slope) = (self.smooth(v), self.map.slope(v));
        let n = (smooth + self.kink_value(v)) / speed_ref;
        let dn_dx = (smooth_slope + self.kink_slope(v)) * self.gain / speed_ref;
        if n.is_nan() || n <= 0.0 {
            return None;
        }
        // The turbine power at the operating point, relative to the reference point's.
        let power = |smooth: f64| (smooth / smooth_ref).max(1e-6);
        let (s_x, p_r) = (power(smooth), power(self.smooth(self.v(r))).powf(self.exponent));
        let p_x = s_x.powf(self.exponent);
        // Equal powers (r = x among them): the balance's slope at x.
        let dp_dx = if (p_r - p_x).abs() > 1e-9 * p_x.abs().max(1e-9) {
            (p_r - p_x) / (r - x)
        } else {
            self.exponent * s_x.powf(self.exponent - 1.0) * smooth_slope * self.gain / smooth_ref
        };
        let tau = n * dn_dx / dp_dx;
        (tau.is_finite() && tau > 0.0).then_some(tau)
    }

    /// The spool's time constant at state `x` heading for `r`, over the one at the reference point.
    pub fn factor(&self, x: f64, r: f64) -> f64 {
        let Some((smooth_ref, speed_ref, at_ref)) = self.reference else { return 1.0 };
        match self.time_constant(x, r, smooth_ref, speed_ref) {
            Some(tau) => (tau / at_ref).clamp(FACTOR_BOUNDS.0, FACTOR_BOUNDS.1),
            None => 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::core::identification::static_map::Beyond;

    /// A running line N = 20 000 + 1 500 v + 10 v² (rpm), its map in x = (v − 50)/40.
    fn running_line() -> StaticMap {
        let (c, s) = (50.0, 40.0);
        let n = |v: f64| 20_000.0 + 1_500.0 * v + 10.0 * v * v;
        // N as a polynomial of x: v = c + s x.
        let coeffs = vec![n(c), (1_500.0 + 20.0 * c) * s, 10.0 * s * s];
        StaticMap { v_center: c, v_scale: s, coeffs_scaled: coeffs, beyond: Beyond::EndTrend }
    }

    /// Without a kink the section is the simulator's balance Ṅ = K (n_r^k − n^k)/n, whatever the
    /// gain and offset that lead from the section's state to the map.
    #[test]
    fn without_a_kink_it_is_the_simulators_balance() {
        let map = running_line();
        let (gain, offset, k, ref_x) = (2.0, 10.0, 3.0, 25.0);
        let b = PowerBalance::new(gain, offset, map.clone(), None, k, ref_x);
        let n = |x: f64| map.eval(gain * x + offset);
        // (r − x)/ẋ with ẋ = Ṅ/(dN/dx), Ṅ ∝ (N_r^k − N^k)/N.
        let tau = |x: f64, r: f64| {
            let dn_dx = map.slope(gain * x + offset) * gain;
            (r - x) * n(x) * dn_dx / (n(r).powf(k) - n(x).powf(k))
        };
        // Locally τ = N dN/dx / (k N^(k−1) dN/dx) = N^(2−k)/k.
        let at_ref = n(ref_x).powf(2.0 - k) / k;
        for (x, r) in [(10.0, 40.0), (40.0, 10.0), (20.0, 21.0), (35.0, 5.0)] {
            let expected = tau(x, r) / at_ref;
            assert!(
                (b.factor(x, r) / expected - 1.0).abs() < 1e-9,
                "{x} → {r}: {} vs {expected}",
                b.factor(x, r)
            );
        }
        assert!((b.factor(ref_x, ref_x) - 1.0).abs() < 1e-12);
        // Slower at the low end: τ ∝ 1/N for k = 3.
        assert!(b.factor(5.0, 5.0) > 1.0 && b.factor(45.0, 45.0) < 1.0);
    }

    /// A load that switches on above a speed (a bleed valve) makes the map flatter there and the
    /// spool faster by the same ratio: the local time constant jumps with the map's slope.
    #[test]
    fn a_kink_changes_the_time_constant_as_it_changes_the_slope() {
        let map = running_line();
        let kink = StaticMapOrder { knot_v: 60.0, slope_change: -900.0 };
        let b = PowerBalance::new(1.0, 0.0, map.clone(), Some(kink.clone()), 3.0, 50.0);
        let (below, above) = (60.0 - 1e-6, 60.0 + 1e-6);
        let slope_ratio = (map.slope(above) + kink.slope_change) / map.slope(below);
        let ratio = b.factor(above, above) / b.factor(below, below);
        assert!((ratio / slope_ratio - 1.0).abs() < 1e-4, "{ratio} vs {slope_ratio}");
        assert!(ratio < 1.0);
    }

    /// A map that gives no positive speed at the reference point leaves the time constant alone.
    #[test]
    fn no_positive_speed_leaves_the_time_constant() {
        let mut map = running_line();
        map.coeffs_scaled = map.coeffs_scaled.iter().map(|c| -c).collect();
        let b = PowerBalance::new(1.0, 0.0, map, None, 3.0, 50.0);
        assert!((b.factor(10.0, 80.0) - 1.0).abs() < 1e-15);
    }
}
