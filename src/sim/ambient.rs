//! Inlet conditions through a run: a standard day, or the linear drift of `ambient_correction`.
use super::effects::AmbientDrift;

/// ISA sea-level temperature, K.
pub const T_STD_K: f64 = 288.15;
/// ISA sea-level pressure, kPa.
pub const P_STD_KPA: f64 = 101.325;
/// The recorded day when `ambient_correction` is off.
pub const STANDARD_DAY: Ambient = Ambient { temp_c: 15.0, pressure_kpa: P_STD_KPA, rh_pct: 50.0 };

const KELVIN_FROM_CELSIUS: f64 = 273.15;

/// Inlet conditions at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ambient {
    pub temp_c: f64,
    pub pressure_kpa: f64,
    pub rh_pct: f64,
}

impl Ambient {
    /// θ = T / 288.15 K.
    pub fn theta(&self) -> f64 {
        (self.temp_c + KELVIN_FROM_CELSIUS) / T_STD_K
    }

    /// δ = p / 101.325 kPa.
    pub fn delta(&self) -> f64 {
        self.pressure_kpa / P_STD_KPA
    }
}

/// The day a run is recorded on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Day {
    drift: Option<AmbientDrift>,
    duration_secs: f64,
}

impl Day {
    /// A day over a run of `duration_secs`; `None` is the constant [`STANDARD_DAY`].
    pub fn new(drift: Option<AmbientDrift>, duration_secs: f64) -> Self {
        Self { drift, duration_secs: duration_secs.max(f64::EPSILON) }
    }

    /// Whether the engine responds to the inlet conditions (runs on corrected quantities).
    pub fn engine_corrected(&self) -> bool {
        self.drift.is_some()
    }

    /// Conditions at `t_secs`: temperature and pressure linear in time; the absolute humidity stays
    /// that of the start, so the relative humidity falls as the air warms.
    pub fn at(&self, t_secs: f64) -> Ambient {
        let Some(d) = self.drift else {
            return STANDARD_DAY;
        };
        let s = (t_secs / self.duration_secs).clamp(0.0, 1.0);
        let temp_c = d.t_start_c + (d.t_end_c - d.t_start_c) * s;
        let pressure_kpa = d.p_start_kpa + (d.p_end_kpa - d.p_start_kpa) * s;
        let vapour_hpa = d.rh_start_pct / 100.0 * saturation_vapour_pressure_hpa(d.t_start_c);
        let rh_pct = (100.0 * vapour_hpa / saturation_vapour_pressure_hpa(temp_c)).clamp(0.0, 100.0);
        Ambient { temp_c, pressure_kpa, rh_pct }
    }
}

/// Magnus formula over water (WMO), hPa.
fn saturation_vapour_pressure_hpa(temp_c: f64) -> f64 {
    6.112 * (17.62 * temp_c / (243.12 + temp_c)).exp()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn standard_day_is_neutral() {
        let day = Day::new(None, 100.0);
        let a = day.at(50.0);
        assert!((a.theta() - 1.0).abs() < 1e-12 && (a.delta() - 1.0).abs() < 1e-12);
        assert!(!day.engine_corrected());
    }

    #[test]
    fn warming_day_drifts_and_dries() {
        let drift = AmbientDrift {
            t_start_c: 18.0,
            t_end_c: 38.0,
            p_start_kpa: 101.3,
            p_end_kpa: 100.8,
            rh_start_pct: 55.0,
        };
        let day = Day::new(Some(drift), 200.0);
        let (a0, a1) = (day.at(0.0), day.at(200.0));
        assert!((a0.temp_c - 18.0).abs() < 1e-12 && (a1.temp_c - 38.0).abs() < 1e-12);
        assert!((a0.rh_pct - 55.0).abs() < 1e-9);
        assert!(a1.rh_pct < 0.5 * a0.rh_pct, "rh {} -> {}", a0.rh_pct, a1.rh_pct);
        assert!(a1.theta() > a0.theta() && a1.delta() < a0.delta());
    }
}
