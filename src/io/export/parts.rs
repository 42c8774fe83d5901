//! The steps and optional blocks of an [`OutputPlan`] as every rendering lists them: what each one
//! is called and its numbers, named and in order, spelled once for the three languages. A language
//! module only arranges them (a C initialiser, a Python tuple, a MATLAB struct or row).
use super::num;
use super::plan::{InputStep, OutputPlan, OutputStep, Spool};

/// One number of a step or block: its name in the runtimes (the fields of the C parameter and step
/// structs, of the MATLAB step structs) and its text ([`num`]; counts as integers).
pub(super) type Field = (&'static str, String);

/// One step of an input or output stage.
pub(super) struct Step {
    /// The step's kind as the runtimes name it: `delay`, `ambient`, `sensor`.
    pub kind: &'static str,
    pub fields: Vec<Field>,
}

/// An optional block: its key, and its numbers when the model has it.
pub(super) struct Block {
    pub key: &'static str,
    pub fields: Option<Vec<Field>>,
}

impl Block {
    /// The numbers alone, in order (`None` without the block).
    pub fn values(&self) -> Option<Vec<&str>> {
        self.fields.as_ref().map(|fields| fields.iter().map(|(_, value)| value.as_str()).collect())
    }
}

pub(super) fn input_step(step: &InputStep) -> Step {
    match step {
        InputStep::Delay(d) => {
            Step { kind: "delay", fields: vec![("whole", d.whole.to_string()), ("frac", num(d.frac))] }
        }
        InputStep::AmbientInput => Step { kind: "ambient", fields: Vec::new() },
    }
}

pub(super) fn output_step(step: &OutputStep) -> Step {
    match step {
        OutputStep::AmbientOutput { theta_exp, delta_exp } => Step {
            kind: "ambient",
            fields: vec![("theta_exp", num(*theta_exp)), ("delta_exp", num(*delta_exp))],
        },
        OutputStep::Sensor(s) => Step {
            kind: "sensor",
            fields: vec![("freq_hz", num(s.freq_hz)), ("zeta", num(s.zeta)), ("lag_s", num(s.lag_s))],
        },
    }
}

/// The blocks the static map and the calibration read (kink, calibration), which every rendering
/// lists before the input steps.
pub(super) fn map_blocks(o: &OutputPlan) -> [Block; 2] {
    [
        Block {
            key: "kink",
            fields: o
                .kink
                .as_ref()
                .map(|k| vec![("knot_v", num(k.knot_v)), ("slope_change", num(k.slope_change))]),
        },
        Block {
            key: "calibration",
            fields: o
                .calibration
                .map(|c| vec![("hold_s", num(c.hold_s)), ("calibration_dc_gain", num(c.dc_gain))]),
        },
    ]
}

/// The blocks acting on `v` (the soak after the linear block, or on the output's power after the
/// map when its `soak_power_exponent` k is positive; the rate limit on the split block's
/// spool state with whether it reads the limit through the map's slope), which every rendering lists
/// after the linear block.
pub(super) fn v_blocks(o: &OutputPlan) -> [Block; 2] {
    [
        Block {
            key: "soak",
            fields: o.soak.as_ref().map(|s| {
                vec![
                    ("soak_gain", num(s.gain)),
                    ("soak_tau_s", num(s.tau_s)),
                    ("soak_power_exponent", num(s.power_exponent)),
                ]
            }),
        },
        Block {
            key: "rate_limit",
            fields: o.rate_limit.as_ref().map(|r| {
                vec![
                    ("rise_per_s", num(r.rise_per_s)),
                    ("fall_per_s", num(r.fall_per_s)),
                    ("limit_through_map", u8::from(o.rate_limit_through_map).to_string()),
                ]
            }),
        },
    ]
}

/// The output read off the shaft speed (`core::effects::ReadOffSpeed`), which every rendering lists
/// after the output steps: the speed's scaling, the polynomial's coefficients and the output's own
/// inlet-correction exponents (used when the speed's model is corrected: `y/(θ^a δ^b) = P(N/√θ)`).
pub(super) fn read_off(o: &OutputPlan) -> Block {
    Block {
        key: "read_off",
        fields: o.read_off.as_ref().map(|r| {
            vec![
                ("read_off_center", num(r.speed_center)),
                ("read_off_scale", num(r.speed_scale)),
                ("read_off_c0", num(r.c0)),
                ("read_off_c1", num(r.c1)),
                ("read_off_c2", num(r.c2)),
                ("read_off_c3", num(r.c3)),
                ("read_off_c4", num(r.c4)),
                ("read_off_theta_exp", num(r.theta_exp)),
                ("read_off_delta_exp", num(r.delta_exp)),
            ]
        }),
    }
}

/// The time-constant schedule of a split linear block.
pub(super) fn schedule(s: &Spool) -> Block {
    Block {
        key: "schedule",
        fields: s.schedule.as_ref().map(|sc| {
            vec![
                ("log_ratio", num(sc.log_ratio)),
                ("state_log_ratio", num(sc.state_log_ratio)),
                ("ref_input", num(sc.ref_input)),
                ("input_span", num(sc.input_span)),
                ("load_exponent", num(sc.load_exponent)),
            ]
        }),
    }
}
