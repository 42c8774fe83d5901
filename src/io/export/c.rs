//! The C99 rendering of a [`Plan`]: the model's numbers as `static const` parameter structs, a
//! runtime stepping the same recursions as `core::effects` one sample at a time, `init`/`step`
//! functions per output, and (unless `JETID_NO_MAIN`) a CSV-to-CSV main.
use super::parts::{self, Block, Step};
use super::plan::{Filter, Linear, OutputPlan, Plan, Spool};
use super::{header, list, num};
use crate::core::identification::static_map::Beyond;

pub(super) fn render(plan: &Plan) -> String {
    let mut text = String::from("/*\n");
    for line in header(plan, "C99") {
        text.push_str(&format!(" * {line}\n"));
    }
    text.push_str(USAGE);
    text.push_str(&format!(
        "\n#define JETID_DT {}\n#define JETID_DELAY_LINE {}\n#define JETID_FILTER_LEN {}\n#define JETID_INPUT \"{}\"\n\
         /* The model file, as `jetid predict` names it in messages. */\n#define JETID_MODEL_FILE {}\n",
        num(plan.dt_secs),
        plan.max_delay_line(),
        plan.max_filter_len(),
        plan.input,
        string(&plan.source)
    ));
    text.push_str(RUNTIME);
    text.push_str("\n/* ---- The model: one parameter set, state type, init and step per output. ---- */\n");
    for out in &plan.outputs {
        text.push_str(&output(out));
    }
    text.push_str(&outputs_table(plan));
    text.push_str(READ_RUN);
    text.push_str(MAIN);
    text
}

/// A C string literal of any text: quotes, backslashes and bytes outside printable ASCII escaped
/// (octal, three digits, so that no digit after one is read into it).
fn string(text: &str) -> String {
    let mut out = String::from("\"");
    for b in text.bytes() {
        match b {
            b'"' | b'\\' => {
                out.push('\\');
                out.push(char::from(b));
            }
            // '?' escaped too: "??" starts a trigraph.
            b' '..=b'~' if b != b'?' => out.push(char::from(b)),
            _ => out.push_str(&format!("\\{b:03o}")),
        }
    }
    out.push('"');
    out
}

/// The arrays and the parameter struct of one filter, named `prefix_num`/`prefix_den`.
fn filter_arrays(prefix: &str, f: &Filter) -> String {
    format!(
        "static const double {prefix}_num[] = {};\nstatic const double {prefix}_den[] = {};\n",
        list(&f.num_zinv, "{", "}"),
        list(&f.den_zinv, "{", "}")
    )
}

fn filter_init(prefix: &str, f: &Filter) -> String {
    format!(
        "{{{}, {prefix}_num, {}, {prefix}_den, {}}}",
        f.num_zinv.len(),
        f.den_zinv.len(),
        num(f.steady_gain)
    )
}

fn output(o: &OutputPlan) -> String {
    let p = format!("jetid_{}", o.ident);
    let mut text = format!("\n/* Output '{}' [{}]. */\n", o.name, o.unit);
    text.push_str(&filter_arrays(&format!("{p}_tf"), &o.tf));
    text.push_str(&format!("static const double {p}_coeffs[] = {};\n", list(&o.map.coeffs_scaled, "{", "}")));
    let mut fields = base_fields(o, &p);
    fields.extend(parts::map_blocks(o).iter().filter_map(block_field));
    fields.extend(steps_field("input", &INPUT_SLOTS, o.input_steps.iter().map(parts::input_step)));
    if let Linear::Split(s) = &o.linear {
        if let Some(rest) = &s.rest {
            text.push_str(&filter_arrays(&format!("{p}_rest"), rest));
        }
        fields.extend(split_fields(&p, s));
    }
    fields.extend(parts::v_blocks(o).iter().filter_map(block_field));
    fields.extend(steps_field("output", &OUTPUT_SLOTS, o.output_steps.iter().map(parts::output_step)));
    fields.extend(block_field(&parts::read_off(o)));
    text.push_str(&format!(
        "static const jetid_params {p}_params = {{\n    {}\n}};\n",
        fields.join(",\n    ")
    ));
    text.push_str(&entry_points(&p, o.needs_ambient()));
    text
}

/// The fields of `jetid_params` every output has: its name, linear block, offset and static map
/// (`p` is the output's prefix, `jetid_IDENT`).
fn base_fields(o: &OutputPlan, p: &str) -> Vec<String> {
    vec![
        format!(".name = \"{}\"", o.name),
        format!(".tf = {}", filter_init(&format!("{p}_tf"), &o.tf)),
        format!(".offset = {}", num(o.offset)),
        format!(".v_center = {}", num(o.map.v_center)),
        format!(".v_scale = {}", num(o.map.v_scale)),
        format!(".end_trend = {}", i32::from(o.map.beyond == Beyond::EndTrend)),
        format!(".n_coeffs = {}", o.map.coeffs_scaled.len()),
        format!(".coeffs = {p}_coeffs"),
    ]
}

/// An optional block as `.has_KEY = 1, .field = …`; nothing without it.
fn block_field(block: &Block) -> Option<String> {
    let fields = block.fields.as_ref()?;
    let values: Vec<String> = fields.iter().map(|(name, value)| format!(".{name} = {value}")).collect();
    Some(format!(".has_{} = 1, {}", block.key, values.join(", ")))
}

/// The fields of `jetid_input_step` and `jetid_output_step` after `kind`, with the value a step
/// that has no such number gets.
const INPUT_SLOTS: [(&str, &str); 2] = [("whole", "0"), ("frac", "0.0")];
const OUTPUT_SLOTS: [(&str, &str); 5] =
    [("theta_exp", "0.0"), ("delta_exp", "0.0"), ("freq_hz", "0.0"), ("zeta", "0.0"), ("lag_s", "0.0")];

/// One step as a struct initialiser: its kind's constant, then every slot in order.
fn step_init(step: &Step, slots: &[(&str, &str)]) -> String {
    let mut items = vec![format!("JETID_STEP_{}", step.kind.to_ascii_uppercase())];
    items.extend(slots.iter().map(|(slot, zero)| {
        let value = step.fields.iter().find(|(name, _)| name == slot).map(|(_, value)| value.as_str());
        value.unwrap_or(zero).to_owned()
    }));
    format!("{{{}}}", items.join(", "))
}

/// `.n_WHICH_steps = n, .WHICH_steps = {…}`; nothing without steps.
fn steps_field(which: &str, slots: &[(&str, &str)], steps: impl Iterator<Item = Step>) -> Option<String> {
    let steps: Vec<String> = steps.map(|s| step_init(&s, slots)).collect();
    (!steps.is_empty())
        .then(|| format!(".n_{which}_steps = {}, .{which}_steps = {{{}}}", steps.len(), steps.join(", ")))
}

/// The fields of a split linear block: the remainder filter, the spool root and its schedule.
fn split_fields(p: &str, s: &Spool) -> Vec<String> {
    let mut fields = Vec::new();
    if let Some(rest) = &s.rest {
        fields.push(format!(".has_rest = 1, .rest = {}", filter_init(&format!("{p}_rest"), rest)));
    }
    fields.push(format!(
        ".split = 1, .dead_time = {}, .ln_root_re = {}, .ln_root_im = {}, .pair = {}, .gain = {}, .decel = {}",
        s.dead_time,
        num(s.ln_root.0),
        num(s.ln_root.1),
        i32::from(s.pair),
        num(s.gain),
        num(s.decel)
    ));
    fields.extend(block_field(&parts::schedule(s)));
    fields
}

/// The output's state type and its `init`, `step` and `calibration_offset` functions.
fn entry_points(p: &str, needs_ambient: bool) -> String {
    format!(
        "typedef jetid_state {p}_state;\n\
         /* Start a run: dt is the run's sample time, calibration_offset the input offset of\n \
         * calibration_drift ({p}_calibration_offset; 0 without it). */\n\
         void {p}_init({p}_state *s, double dt, double calibration_offset)\n\
         {{\n    jetid_init(s, &{p}_params, dt, calibration_offset);\n}}\n\
         /* The next output sample from the next input sample; temp_c and pressure_kpa are the inlet\n \
         * conditions ({}). */\n\
         double {p}_step({p}_state *s, double u, double temp_c, double pressure_kpa)\n\
         {{\n    return jetid_step(s, u, temp_c, pressure_kpa);\n}}\n\
         /* calibration_drift's offset for a whole run (0 without the effect or without holds). */\n\
         double {p}_calibration_offset(const double *u, const double *temp_c, const double *pressure_kpa,\n\
         \x20                                const double *y_measured, size_t n, double dt)\n\
         {{\n    return jetid_calibration_offset(&{p}_params, u, temp_c, pressure_kpa, y_measured, n, dt);\n}}\n",
        if needs_ambient { "read: the output is corrected for them" } else { "ignored by this output" }
    )
}

fn outputs_table(plan: &Plan) -> String {
    let params: Vec<String> = plan.outputs.iter().map(|o| format!("&jetid_{}_params", o.ident)).collect();
    format!(
        "\n#ifndef JETID_NO_MAIN\n#define JETID_N_OUTPUTS {}\nstatic const jetid_params *const jetid_outputs[JETID_N_OUTPUTS] = {{{}}};\n#endif\n",
        plan.outputs.len(),
        params.join(", ")
    )
}

const USAGE: &str = r#" *
 * Build: cc -O2 -std=c99 -Wall -Werror THIS_FILE -lm -o model
 * Run:   ./model IN.csv OUT.csv [--calibrate] [--map ROLE=COLUMN]... [--sample-time S]
 *                [--window START:END] [--quality COLUMN] [--invalid CHANNEL=V1,V2]... [--resample]
 *   writes what `jetid predict --model MODEL --input IN.csv --out OUT.csv` (with the same options)
 *   writes: time_s, the input and one column per output. IN.csv is read as jetid reads a run, and a
 *   file jetid refuses is refused with jetid's message (exit status 1):
 *   --map ROLE=COLUMN      the column of a role: time, input, output, aux (repeatable); by default
 *                          time_s and fuel_flow_gph, and every other numeric column as auxiliary
 *   --sample-time S        the sample time of a file without a time column
 *   --window START:END     keep samples START..END (0-based, END excluded), or seconds: 12.5s:80s
 *                          (`auto` is jetid's alone)
 *   --quality COLUMN       a 0/1 column; samples marked 0 are interpolated (trimmed at the ends)
 *   --invalid CH=V1,V2     values channel CH logs for "no reading": interpolated (repeatable)
 *   --resample             merge repeated time stamps and resample an irregular time axis onto the
 *                          median step, instead of refusing it
 *   --calibrate            read the measured outputs for calibration_drift's per-run offset, as
 *                          `jetid predict ... --map output=NAME` does
 * Embed: compile with -DJETID_NO_MAIN; per output NAME, jetid_NAME_state, jetid_NAME_init() and
 *   jetid_NAME_step() (one sample in, one sample out). calibration_drift's offset comes from the
 *   run's own steady holds of the measured output, so it needs the whole run in advance:
 *   jetid_NAME_calibration_offset() computes it before stepping (the main does so with --calibrate).
 * Needs libm only.
 */
#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
"#;

const RUNTIME: &str = include_str!("c/runtime.c");

const READ_RUN: &str = include_str!("c/read_run.c");

const MAIN: &str = include_str!("c/main.c");

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::effects::SensorDynamics;
    use crate::io::export::plan::{Delay, InputStep, OutputStep};

    /// A number without a slot in the C step struct would be dropped from the initialiser.
    #[test]
    fn every_number_of_every_step_has_a_slot() {
        let inputs = [InputStep::Delay(Delay { whole: 3, frac: 0.25 }), InputStep::AmbientInput];
        let outputs = [
            OutputStep::AmbientOutput { theta_exp: 0.5, delta_exp: 1.0 },
            OutputStep::Sensor(SensorDynamics { freq_hz: 2.0, zeta: 0.7, lag_s: 0.1 }),
        ];
        let steps = inputs.iter().map(|s| (parts::input_step(s), &INPUT_SLOTS[..]));
        for (step, slots) in steps.chain(outputs.iter().map(|s| (parts::output_step(s), &OUTPUT_SLOTS[..]))) {
            for (name, _) in &step.fields {
                assert!(slots.iter().any(|(slot, _)| slot == name), "{}: {name} has no slot", step.kind);
            }
        }
        assert_eq!(step_init(&parts::input_step(&inputs[0]), &INPUT_SLOTS), "{JETID_STEP_DELAY, 3, 0.25}");
        assert_eq!(
            step_init(&parts::output_step(&outputs[1]), &OUTPUT_SLOTS),
            "{JETID_STEP_SENSOR, 0.0, 0.0, 2.0, 0.7, 0.1}"
        );
    }
}
