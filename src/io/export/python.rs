//! The Python rendering of a [`Plan`]: the model's numbers as dicts, its linear blocks as
//! `control.TransferFunction`s, and a runtime stepping the same recursions as `core::effects`.
use super::parts::{self, Block, Step};
use super::plan::{Filter, Linear, OutputPlan, Plan};
use super::{header, list, num};
use crate::core::control::covariance::Slot;
use crate::core::identification::static_map::Beyond;

pub(super) fn render(plan: &Plan) -> String {
    let mut text = String::from("#!/usr/bin/env python3\n");
    for line in header(plan, "Python") {
        text.push_str(&format!("# {line}\n"));
    }
    text.push_str(USAGE);
    text.push_str(&constants(plan));
    text.push_str(&outputs_dict(plan));
    text.push_str(&tf_coeffs_dict(plan));
    text.push_str(&covariance_dict(plan));
    text.push_str(RUNTIME);
    text.push_str(READ_RUN);
    text.push_str(MAIN);
    text
}

/// The sample time, the input's name and the model file's name.
fn constants(plan: &Plan) -> String {
    format!(
        "\nDT = {}\nINPUT = {:?}\n# The model file, as `jetid predict` names it in messages.\nMODEL_FILE = {}\n\n",
        num(plan.dt_secs),
        plan.input,
        string(&plan.source)
    )
}

/// `OUTPUTS`: per output, the numbers of every step of its signal path.
fn outputs_dict(plan: &Plan) -> String {
    let entries: String =
        plan.outputs.iter().map(|out| format!("    {:?}: {},\n", out.name, output(out))).collect();
    format!("{OUTPUTS_COMMENT}OUTPUTS = {{\n{entries}}}\n\n")
}

/// `TF_COEFFS`: each output's linear block G(z) in positive powers of z.
fn tf_coeffs_dict(plan: &Plan) -> String {
    let entries: String = plan
        .outputs
        .iter()
        .map(|out| {
            let (n, d) = out.tf.positive_powers();
            format!("    {:?}: ({}, {}),\n", out.name, list(&n, "[", "]"), list(&d, "[", "]"))
        })
        .collect();
    format!("{TF_COEFFS_COMMENT}TF_COEFFS = {{\n{entries}}}\n")
}

/// `COVARIANCE`: per output, the model file's parameter covariance and where the parameters sit
/// (`None` when the file holds none).
fn covariance_dict(plan: &Plan) -> String {
    let slots = |slots: &[Slot]| {
        let names: Vec<&str> =
            slots.iter().map(|s| if *s == Slot::Pair { "\"pair\"" } else { "\"real\"" }).collect();
        format!("[{}]", names.join(", "))
    };
    let entries: String = plan
        .outputs
        .iter()
        .map(|out| {
            let body = out.uncertainty.as_ref().map(|u| {
                let c = &u.covariance;
                let names: Vec<String> = c.names.iter().map(|n| string(n)).collect();
                let rows: Vec<String> = c.matrix.iter().map(|r| list(r, "[", "]")).collect();
                dict(&[
                    ("names", format!("[{}]", names.join(", "))),
                    ("values", list(&c.values, "[", "]")),
                    ("matrix", format!("[{}]", rows.join(", "))),
                    ("poles", slots(&u.layout.poles)),
                    ("zeros", slots(&u.layout.zeros)),
                    ("map", u.layout.map.to_string()),
                    ("steady_gain", num(u.layout.steady_gain)),
                    ("delay", u.layout.delay.to_string()),
                ])
            });
            format!("    {:?}: {},\n", out.name, option(body))
        })
        .collect();
    format!("{COVARIANCE_COMMENT}COVARIANCE = {{\n{entries}}}\n")
}

const COVARIANCE_COMMENT: &str = "\n# Per output: the covariance of the model's parameters from its fit to the identification run \
    (None when\n# the model file holds none): names, values, matrix, and where the parameters sit (poles as \
    atanh of a real\n# pole / of a pair's modulus with its angle, then zeros, the static map's coefficients, each effect's \
    free\n# parameters). See sample_models().\n";

const OUTPUTS_COMMENT: &str =
    "# Per output: the numbers of every step of its signal path (see simulate()).\n";

const TF_COEFFS_COMMENT: &str = "# The linear block G(z) of each output (z^-1 coefficients padded to positive powers of z); TF \
    holds\n# them as control.TransferFunction objects, made when TF is first used (see __getattr__).\n";

/// A Python string literal of any text (a JSON string is one).
fn string(text: &str) -> String {
    serde_json::Value::from(text).to_string()
}

fn filter(f: &Filter) -> String {
    dict(&[
        ("num", list(&f.num_zinv, "[", "]")),
        ("den", list(&f.den_zinv, "[", "]")),
        ("steady_gain", num(f.steady_gain)),
    ])
}

/// `{"key": value, …}` on one line.
fn dict(entries: &[(&str, String)]) -> String {
    let entries: Vec<String> = entries.iter().map(|(key, value)| format!("{key:?}: {value}")).collect();
    format!("{{{}}}", entries.join(", "))
}

fn option(x: Option<String>) -> String {
    x.unwrap_or_else(|| "None".to_owned())
}

fn output(o: &OutputPlan) -> String {
    let mut fields = vec![("tf", filter(&o.tf)), ("offset", num(o.offset)), ("map", static_map(o))];
    fields.extend(parts::map_blocks(o).iter().map(block_entry));
    fields.push(("input_steps", steps(o.input_steps.iter().map(parts::input_step))));
    fields.push(("split", option(split(&o.linear))));
    fields.extend(parts::v_blocks(o).iter().map(block_entry));
    fields.push(("output_steps", steps(o.output_steps.iter().map(parts::output_step))));
    fields.push(block_entry(&parts::read_off(o)));
    fields.push(("effect_dynamics", filter(&o.effect_dynamics)));
    let body: Vec<String> = fields.iter().map(|(k, v)| format!("\n        {k:?}: {v}")).collect();
    format!("{{{},\n    }}", body.join(","))
}

/// `(items)`, with the trailing comma a one-element tuple needs.
fn tuple(items: &[&str]) -> String {
    match items {
        [one] => format!("({one},)"),
        _ => format!("({})", items.join(", ")),
    }
}

/// The static map as `(v_center, v_scale, [coefficients], end_trend)`.
fn static_map(o: &OutputPlan) -> String {
    format!(
        "({}, {}, {}, {})",
        num(o.map.v_center),
        num(o.map.v_scale),
        list(&o.map.coeffs_scaled, "[", "]"),
        if o.map.beyond == Beyond::EndTrend { "True" } else { "False" }
    )
}

/// An optional block as a dict entry: its numbers as a tuple, or `None`.
fn block_entry(block: &Block) -> (&'static str, String) {
    (block.key, option(block.values().map(|values| tuple(&values))))
}

/// Steps as a list of tuples `("kind", numbers…)`.
fn steps(steps: impl Iterator<Item = Step>) -> String {
    let steps: Vec<String> = steps
        .map(|s| {
            let kind = format!("{:?}", s.kind);
            let mut items = vec![kind.as_str()];
            items.extend(s.fields.iter().map(|(_, value)| value.as_str()));
            tuple(&items)
        })
        .collect();
    format!("[{}]", steps.join(", "))
}

/// A split linear block as a dict; `None` for a direct one.
fn split(linear: &Linear) -> Option<String> {
    let Linear::Split(s) = linear else { return None };
    Some(dict(&[
        ("dead_time", s.dead_time.to_string()),
        ("rest", option(s.rest.as_ref().map(filter))),
        ("ln_root", tuple(&[&num(s.ln_root.0), &num(s.ln_root.1)])),
        ("pair", (if s.pair { "True" } else { "False" }).to_owned()),
        ("gain", num(s.gain)),
        ("decel", num(s.decel)),
        ("schedule", option(parts::schedule(s).values().map(|values| tuple(&values)))),
    ]))
}

const USAGE: &str = r#"#
# Run: python3 THIS_FILE IN.csv OUT.csv [--calibrate] [--map ROLE=COLUMN]... [--sample-time S]
#                   [--window START:END] [--quality COLUMN] [--invalid CHANNEL=V1,V2]... [--resample]
#   writes what `jetid predict --model MODEL --input IN.csv --out OUT.csv` (with the same options)
#   writes: time_s, the input and one column per output. IN.csv is read as jetid reads a run, and
#   a file jetid refuses is refused with jetid's message (exit status 1):
#   --map ROLE=COLUMN      the column of a role: time, input, output, aux (repeatable); by default
#                          time_s and fuel_flow_gph, and every other numeric column as auxiliary
#   --sample-time S        the sample time of a file without a time column
#   --window START:END     keep samples START..END (0-based, END excluded), or seconds: 12.5s:80s
#                          (`auto` is jetid's alone)
#   --quality COLUMN       a 0/1 column; samples marked 0 are interpolated (trimmed at the ends)
#   --invalid CH=V1,V2     values channel CH logs for "no reading": interpolated (repeatable)
#   --resample             merge repeated time stamps and resample an irregular time axis onto
#                          the median step, instead of refusing it
#   --calibrate            read the measured outputs for calibration_drift's per-run offset, as
#                          `jetid predict ... --map output=NAME` does
# Import: simulate(u, aux, measured) -> {output: array}; operating_point(output, u_star) -> the
#   local linear model as a control.TransferFunction; sample_models(output, n, seed) -> models drawn
#   from the parameter covariance; operating_point_ci95(output, u_star) -> the 95 % interval of the
#   local gain; load_run(path, LoadOptions()) reads a run
#   file as jetid does. Needs numpy; TF and operating_point also python-control, imported only
#   when they are used (it takes a second or two to load), so the command line starts at once.
import cmath
import math
import os
import re
import sys

import numpy as np
"#;

const RUNTIME: &str = include_str!("python/runtime.py");

const READ_RUN: &str = include_str!("python/read_run.py");

const MAIN: &str = include_str!("python/main.py");
