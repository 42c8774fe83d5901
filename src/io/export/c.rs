//! The C99 rendering of a [`Plan`]: the model's numbers as `static const` parameter structs, a
//! runtime stepping the same recursions as `core::effects` one sample at a time, `init`/`step`
//! functions per output, and (unless `JETID_NO_MAIN`) a CSV-to-CSV main.
use super::plan::{Filter, InputStep, Linear, OutputPlan, OutputStep, Plan};
use super::{header, list, num};

pub(super) fn render(plan: &Plan) -> String {
    let mut text = String::from("/*\n");
    for line in header(plan, "C99") {
        text.push_str(&format!(" * {line}\n"));
    }
    text.push_str(USAGE);
    text.push_str(&format!(
        "\n#define JETID_DT {}\n#define JETID_DELAY_LINE {}\n#define JETID_FILTER_LEN {}\n#define JETID_INPUT \"{}\"\n",
        num(plan.dt_secs),
        plan.max_delay_line(),
        plan.max_filter_len(),
        plan.input
    ));
    text.push_str(RUNTIME);
    text.push_str("\n/* ---- The model: one parameter set, state type, init and step per output. ---- */\n");
    for out in &plan.outputs {
        text.push_str(&output(out));
    }
    text.push_str(&outputs_table(plan));
    text.push_str(MAIN);
    text
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
    let id = &o.ident;
    let p = format!("jetid_{id}");
    let mut text = format!("\n/* Output '{}' [{}]. */\n", o.name, o.unit);
    text.push_str(&filter_arrays(&format!("{p}_tf"), &o.tf));
    text.push_str(&format!("static const double {p}_coeffs[] = {};\n", list(&o.map.coeffs_scaled, "{", "}")));
    let mut fields = vec![
        format!(".name = \"{}\"", o.name),
        format!(".tf = {}", filter_init(&format!("{p}_tf"), &o.tf)),
        format!(".offset = {}", num(o.offset)),
        format!(".v_center = {}", num(o.map.v_center)),
        format!(".v_scale = {}", num(o.map.v_scale)),
        format!(".n_coeffs = {}", o.map.coeffs_scaled.len()),
        format!(".coeffs = {p}_coeffs"),
    ];
    if let Some(k) = &o.kink {
        fields.push(format!(
            ".has_kink = 1, .knot_v = {}, .slope_change = {}",
            num(k.knot_v),
            num(k.slope_change)
        ));
    }
    if let Some(c) = &o.calibration {
        fields.push(format!(
            ".has_calibration = 1, .hold_s = {}, .calibration_dc_gain = {}",
            num(c.hold_s),
            num(c.dc_gain)
        ));
    }
    let steps: Vec<String> = o
        .input_steps
        .iter()
        .map(|s| match s {
            InputStep::Delay(d) => format!("{{JETID_STEP_DELAY, {}, {}}}", d.whole, num(d.frac)),
            InputStep::AmbientInput => "{JETID_STEP_AMBIENT, 0, 0.0}".to_owned(),
        })
        .collect();
    if !steps.is_empty() {
        fields.push(format!(".n_input_steps = {}, .input_steps = {{{}}}", steps.len(), steps.join(", ")));
    }
    if let Linear::Split(s) = &o.linear {
        if let Some(rest) = &s.rest {
            text.push_str(&filter_arrays(&format!("{p}_rest"), rest));
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
        if let Some(sc) = &s.schedule {
            fields.push(format!(
                ".has_schedule = 1, .log_ratio = {}, .state_log_ratio = {}, .ref_input = {}, .input_span = {}",
                num(sc.log_ratio),
                num(sc.state_log_ratio),
                num(sc.ref_input),
                num(sc.input_span)
            ));
        }
    }
    if let Some(s) = &o.soak {
        fields.push(format!(".has_soak = 1, .soak_gain = {}, .soak_tau_s = {}", num(s.gain), num(s.tau_s)));
    }
    if let Some(r) = &o.rate_limit {
        fields.push(format!(
            ".has_rate_limit = 1, .rise_per_s = {}, .fall_per_s = {}",
            num(r.rise_per_s),
            num(r.fall_per_s)
        ));
    }
    let steps: Vec<String> = o
        .output_steps
        .iter()
        .map(|s| match s {
            OutputStep::AmbientOutput { theta_exp, delta_exp } => {
                format!("{{JETID_STEP_AMBIENT, {}, {}, 0.0, 0.0, 0.0}}", num(*theta_exp), num(*delta_exp))
            }
            OutputStep::Sensor(s) => {
                format!(
                    "{{JETID_STEP_SENSOR, 0.0, 0.0, {}, {}, {}}}",
                    num(s.freq_hz),
                    num(s.zeta),
                    num(s.lag_s)
                )
            }
        })
        .collect();
    if !steps.is_empty() {
        fields.push(format!(".n_output_steps = {}, .output_steps = {{{}}}", steps.len(), steps.join(", ")));
    }
    text.push_str(&format!(
        "static const jetid_params {p}_params = {{\n    {}\n}};\n",
        fields.join(",\n    ")
    ));
    text.push_str(&format!(
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
        if o.needs_ambient() { "read: the output is corrected for them" } else { "ignored by this output" }
    ));
    text
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
 * Run:   ./model IN.csv OUT.csv [--calibrate]
 *   reads time_s, the input column (and ambient_temp_c, ambient_pressure_kpa when an output is
 *   corrected for inlet conditions) and writes time_s, the input and one column per output, as
 *   `jetid predict --model MODEL --input IN.csv --out OUT.csv` does. With --calibrate the measured
 *   output columns are read too, for calibration_drift's per-run offset, as
 *   `jetid predict ... --map output=NAME` does.
 * Embed: compile with -DJETID_NO_MAIN; per output NAME, jetid_NAME_state, jetid_NAME_init() and
 *   jetid_NAME_step() (one sample in, one sample out). calibration_drift's offset comes from the
 *   run's own steady holds of the measured output, so it needs the whole run in advance:
 *   jetid_NAME_calibration_offset() computes it before stepping (the main does so with --calibrate).
 * Needs libm only.
 */
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
"#;

const RUNTIME: &str = include_str!("c/runtime.c");

const MAIN: &str = include_str!("c/main.c");
