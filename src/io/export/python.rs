//! The Python rendering of a [`Plan`]: the model's numbers as dicts, its linear blocks as
//! `control.TransferFunction`s, and a runtime stepping the same recursions as `core::effects`.
use super::plan::{Filter, InputStep, Linear, OutputPlan, OutputStep, Plan};
use super::{header, list, num};

pub(super) fn render(plan: &Plan) -> String {
    let mut text = String::from("#!/usr/bin/env python3\n");
    for line in header(plan, "Python") {
        text.push_str(&format!("# {line}\n"));
    }
    text.push_str(USAGE);
    text.push_str(&format!("\nDT = {}\nINPUT = {:?}\n\n", num(plan.dt_secs), plan.input));
    text.push_str(
        "# Per output: the numbers of every step of its signal path (see simulate()).\nOUTPUTS = {\n",
    );
    for out in &plan.outputs {
        text.push_str(&format!("    {:?}: {},\n", out.name, output(out)));
    }
    text.push_str("}\n\n");
    text.push_str(
        "# The linear block G(z) of each output (z^-1 coefficients padded to positive powers of z).\nTF = {\n",
    );
    for out in &plan.outputs {
        let (n, d) = out.tf.positive_powers();
        text.push_str(&format!(
            "    {:?}: control.TransferFunction({}, {}, DT),\n",
            out.name,
            list(&n, "[", "]"),
            list(&d, "[", "]")
        ));
    }
    text.push_str("}\n");
    text.push_str(RUNTIME);
    text
}

fn filter(f: &Filter) -> String {
    format!(
        "{{\"num\": {}, \"den\": {}, \"steady_gain\": {}}}",
        list(&f.num_zinv, "[", "]"),
        list(&f.den_zinv, "[", "]"),
        num(f.steady_gain)
    )
}

fn option(x: Option<String>) -> String {
    x.unwrap_or_else(|| "None".to_owned())
}

fn output(o: &OutputPlan) -> String {
    let input_steps: Vec<String> = o
        .input_steps
        .iter()
        .map(|s| match s {
            InputStep::Delay(d) => format!("(\"delay\", {}, {})", d.whole, num(d.frac)),
            InputStep::AmbientInput => "(\"ambient\",)".to_owned(),
        })
        .collect();
    let output_steps: Vec<String> = o
        .output_steps
        .iter()
        .map(|s| match s {
            OutputStep::AmbientOutput { theta_exp, delta_exp } => {
                format!("(\"ambient\", {}, {})", num(*theta_exp), num(*delta_exp))
            }
            OutputStep::Sensor(s) => {
                format!("(\"sensor\", {}, {}, {})", num(s.freq_hz), num(s.zeta), num(s.lag_s))
            }
        })
        .collect();
    let split = match &o.linear {
        Linear::Direct(_) => None,
        Linear::Split(s) => Some(format!(
            "{{\"dead_time\": {}, \"rest\": {}, \"ln_root\": ({}, {}), \"pair\": {}, \"gain\": {}, \"decel\": {}, \
             \"schedule\": {}}}",
            s.dead_time,
            option(s.rest.as_ref().map(filter)),
            num(s.ln_root.0),
            num(s.ln_root.1),
            if s.pair { "True" } else { "False" },
            num(s.gain),
            num(s.decel),
            option(s.schedule.as_ref().map(|s| format!(
                "({}, {}, {}, {})",
                num(s.log_ratio),
                num(s.state_log_ratio),
                num(s.ref_input),
                num(s.input_span)
            ))),
        )),
    };
    let fields = [
        ("tf", filter(&o.tf)),
        ("offset", num(o.offset)),
        (
            "map",
            format!(
                "({}, {}, {})",
                num(o.map.v_center),
                num(o.map.v_scale),
                list(&o.map.coeffs_scaled, "[", "]")
            ),
        ),
        ("kink", option(o.kink.as_ref().map(|k| format!("({}, {})", num(k.knot_v), num(k.slope_change))))),
        ("calibration", option(o.calibration.map(|c| format!("({}, {})", num(c.hold_s), num(c.dc_gain))))),
        ("input_steps", format!("[{}]", input_steps.join(", "))),
        ("split", option(split)),
        ("soak", option(o.soak.as_ref().map(|s| format!("({}, {})", num(s.gain), num(s.tau_s))))),
        (
            "rate_limit",
            option(o.rate_limit.as_ref().map(|r| format!("({}, {})", num(r.rise_per_s), num(r.fall_per_s)))),
        ),
        ("output_steps", format!("[{}]", output_steps.join(", "))),
        ("effect_dynamics", filter(&o.effect_dynamics)),
    ];
    let body: Vec<String> = fields.iter().map(|(k, v)| format!("\n        {k:?}: {v}")).collect();
    format!("{{{},\n    }}", body.join(","))
}

const USAGE: &str = r#"#
# Run: python3 THIS_FILE IN.csv OUT.csv [--calibrate]
#   reads time_s, the input column (and ambient_temp_c, ambient_pressure_kpa when an output is
#   corrected for inlet conditions) and writes time_s, the input and one column per output, as
#   `jetid predict --model MODEL --input IN.csv --out OUT.csv` does. With --calibrate the measured
#   output columns are read too, for calibration_drift's per-run offset, as
#   `jetid predict ... --map output=NAME` does.
# Import: simulate(u, aux, measured) -> {output: array}; operating_point(output, u_star) -> the
#   local linear model as a control.TransferFunction. Needs numpy and python-control.
import csv
import math
import sys

import control
import numpy as np
"#;

const RUNTIME: &str = include_str!("python/runtime.py");
