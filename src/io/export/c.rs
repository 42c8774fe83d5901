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

const RUNTIME: &str = r#"
#define JETID_T_STD_K 288.15
#define JETID_P_STD_KPA 101.325
#define JETID_KELVIN_FROM_CELSIUS 273.15
#define JETID_PI 3.14159265358979323846
#define JETID_STEP_DELAY 1
#define JETID_STEP_AMBIENT 2
#define JETID_STEP_SENSOR 3

/* G(z) in z^-1: num[0] + num[1] z^-1 + ... over 1 + den[1] z^-1 + ... */
typedef struct {
    int n_num;
    const double *num;
    int n_den;
    const double *den;
    double steady_gain; /* G(1), or 0 without a steady state: the start is u0, steady_gain * u0 */
} jetid_filter;

typedef struct {
    int kind;
    int whole;
    double frac;
} jetid_input_step;

typedef struct {
    int kind;
    double theta_exp, delta_exp;
    double freq_hz, zeta, lag_s;
} jetid_output_step;

/* Everything one output's model needs, in signal-path order. */
typedef struct {
    const char *name;
    jetid_filter tf;
    double offset;
    double v_center, v_scale;
    int n_coeffs;
    const double *coeffs;
    int has_kink;
    double knot_v, slope_change;
    int has_calibration;
    double hold_s, calibration_dc_gain;
    int n_input_steps;
    jetid_input_step input_steps[2];
    int split;
    int dead_time;
    int has_rest;
    jetid_filter rest;
    double ln_root_re, ln_root_im;
    int pair;
    double gain, decel;
    int has_schedule;
    double log_ratio, state_log_ratio, ref_input, input_span;
    int has_soak;
    double soak_gain, soak_tau_s;
    int n_output_steps;
    jetid_output_step output_steps[2];
} jetid_params;

typedef struct {
    double u[JETID_FILTER_LEN]; /* u[k], u[k-1], ... */
    double y[JETID_FILTER_LEN]; /* y[k-1], y[k-2], ... */
} jetid_filter_state;

typedef struct {
    double line[JETID_DELAY_LINE]; /* u[k], u[k-1], ... */
} jetid_delay_state;

typedef struct {
    int lag;
    double a, ramp, omega, h;
    int steps;
    double y_prev, x, lagged, pos, vel;
} jetid_sensor_state;

typedef struct {
    const jetid_params *p;
    double dt, calibration_offset;
    int started;
    jetid_delay_state input_delay[2];
    jetid_filter_state linear, rest;
    jetid_delay_state dead;
    double x, x_old, prev, prev_old; /* the spool: output now and before, its input before */
    double soak_a, soak_s;
    jetid_sensor_state sensor[2];
} jetid_state;

static double jetid_filter_step(const jetid_filter *f, jetid_filter_state *s, double x, int first)
{
    int j;
    double acc = 0.0;
    if (first) {
        for (j = 0; j < JETID_FILTER_LEN; j++) {
            s->u[j] = x;
            s->y[j] = f->steady_gain * x;
        }
    }
    for (j = f->n_num - 1; j > 0; j--) s->u[j] = s->u[j - 1];
    s->u[0] = x;
    for (j = 0; j < f->n_num; j++) acc += f->num[j] * s->u[j];
    for (j = 1; j < f->n_den; j++) acc -= f->den[j] * s->y[j - 1];
    for (j = f->n_den - 1; j > 0; j--) s->y[j] = s->y[j - 1];
    s->y[0] = acc;
    return acc;
}

static double jetid_delay_step(jetid_delay_state *s, int whole, double frac, double x, int first)
{
    int j;
    if (first) {
        for (j = 0; j < whole + 2; j++) s->line[j] = x;
    }
    for (j = whole + 1; j > 0; j--) s->line[j] = s->line[j - 1];
    s->line[0] = x;
    return (1.0 - frac) * s->line[whole] + frac * s->line[whole + 1];
}

static double jetid_spool_step(jetid_state *s, double u, int first)
{
    const jetid_params *p = s->p;
    double r, factor = 1.0, f, mag, re, im, next;
    u = jetid_delay_step(&s->dead, p->dead_time, 0.0, u, first);
    r = p->has_rest ? jetid_filter_step(&p->rest, &s->rest, u, first) : u;
    if (first) s->x = s->x_old = s->prev = s->prev_old = r;
    if (p->has_schedule)
        factor = exp(-(p->log_ratio * (s->prev - p->ref_input) + p->state_log_ratio * (s->x - p->ref_input)) /
                     p->input_span);
    if (s->prev < s->x) factor *= p->decel;
    f = factor > DBL_MIN ? factor : DBL_MIN;
    mag = exp(p->ln_root_re / f);
    re = mag * cos(p->ln_root_im / f);
    im = mag * sin(p->ln_root_im / f);
    if (p->pair) {
        double a1 = 2.0 * re, a2 = re * re + im * im;
        next = a1 * s->x - a2 * s->x_old + (1.0 - a1 + a2) * s->prev_old;
    } else {
        next = re * s->x + (1.0 - re) * s->prev;
    }
    s->x_old = s->x;
    s->x = next;
    s->prev_old = s->prev;
    s->prev = r;
    return p->gain * s->x;
}

static void jetid_sensor_init(jetid_sensor_state *s, const jetid_output_step *o, double dt)
{
    s->lag = o->lag_s > 1e-3;
    if (s->lag) {
        s->a = exp(-dt / o->lag_s);
        s->ramp = 1.0 - o->lag_s * (1.0 - s->a) / dt;
    }
    s->omega = 2.0 * JETID_PI * o->freq_hz;
    s->steps = (int)ceil(s->omega * dt / 0.25);
    if (s->steps < 4) s->steps = 4;
    s->h = dt / s->steps;
}

static void jetid_deriv(double omega, double zeta, double pos, double vel, double u, double *dpos, double *dvel)
{
    *dpos = vel;
    *dvel = omega * omega * (u - pos) - 2.0 * zeta * omega * vel;
}

static double jetid_sensor_step(jetid_sensor_state *s, const jetid_output_step *o, double dt, double y, int first)
{
    double lagged, w0, w1, h = s->h, z = o->zeta, w = s->omega;
    int k;
    if (first) {
        s->y_prev = s->x = s->lagged = s->pos = y;
        s->vel = 0.0;
        return s->pos;
    }
    if (s->lag) {
        s->x = s->a * s->x + (1.0 - s->a) * s->y_prev + (y - s->y_prev) * s->ramp;
        lagged = s->x;
    } else {
        lagged = y;
    }
    s->y_prev = y;
    w0 = s->lagged;
    w1 = lagged;
    for (k = 0; k < s->steps; k++) {
        double t = k * h, p1, v1, p2, v2, p3, v3, p4, v4;
        double u0 = w0 + (w1 - w0) * t / dt, u1 = w0 + (w1 - w0) * (t + 0.5 * h) / dt,
               u2 = w0 + (w1 - w0) * (t + h) / dt;
        jetid_deriv(w, z, s->pos, s->vel, u0, &p1, &v1);
        jetid_deriv(w, z, s->pos + 0.5 * h * p1, s->vel + 0.5 * h * v1, u1, &p2, &v2);
        jetid_deriv(w, z, s->pos + 0.5 * h * p2, s->vel + 0.5 * h * v2, u1, &p3, &v3);
        jetid_deriv(w, z, s->pos + h * p3, s->vel + h * v3, u2, &p4, &v4);
        s->pos += h / 6.0 * (p1 + 2.0 * p2 + 2.0 * p3 + p4);
        s->vel += h / 6.0 * (v1 + 2.0 * v2 + 2.0 * v3 + v4);
    }
    s->lagged = lagged;
    return s->pos;
}

/* f(v): the polynomial in (v - v_center)/v_scale, plus the kink of static_map_order. */
static double jetid_static_map(const jetid_params *p, double v)
{
    double x = (v - p->v_center) / p->v_scale, y = 0.0, kink = 0.0;
    int i;
    for (i = p->n_coeffs - 1; i >= 0; i--) y = y * x + p->coeffs[i];
    if (p->has_kink) kink = p->slope_change * (v - p->knot_v > 0.0 ? v - p->knot_v : 0.0);
    return y + kink;
}

static void jetid_init(jetid_state *s, const jetid_params *p, double dt, double calibration_offset)
{
    int i;
    memset(s, 0, sizeof *s);
    s->p = p;
    s->dt = dt;
    s->calibration_offset = calibration_offset;
    s->started = 0;
    if (p->has_soak) s->soak_a = exp(-dt / (p->soak_tau_s > DBL_MIN ? p->soak_tau_s : DBL_MIN));
    for (i = 0; i < p->n_output_steps; i++)
        if (p->output_steps[i].kind == JETID_STEP_SENSOR) jetid_sensor_init(&s->sensor[i], &p->output_steps[i], dt);
}

/* The input as the linear block sees it: delayed, corrected for inlet conditions. */
static double jetid_input_stage(jetid_state *s, double u, double temp_c, double pressure_kpa)
{
    const jetid_params *p = s->p;
    int i;
    for (i = 0; i < p->n_input_steps; i++) {
        const jetid_input_step *st = &p->input_steps[i];
        if (st->kind == JETID_STEP_DELAY) {
            u = jetid_delay_step(&s->input_delay[i], st->whole, st->frac, u, !s->started);
        } else {
            double theta = (temp_c + JETID_KELVIN_FROM_CELSIUS) / JETID_T_STD_K, delta = pressure_kpa / JETID_P_STD_KPA;
            u = u / (delta * sqrt(theta));
        }
    }
    return u;
}

static double jetid_step(jetid_state *s, double u, double temp_c, double pressure_kpa)
{
    const jetid_params *p = s->p;
    int first = !s->started, i;
    double v, y;
    u = jetid_input_stage(s, u, temp_c, pressure_kpa) + s->calibration_offset;
    v = p->split ? jetid_spool_step(s, u, first) : jetid_filter_step(&p->tf, &s->linear, u, first);
    if (p->has_soak) {
        if (first) s->soak_s = v;
        s->soak_s = s->soak_a * s->soak_s + (1.0 - s->soak_a) * v;
        v = v + p->soak_gain * (s->soak_s - v);
    }
    v += p->offset;
    y = jetid_static_map(p, v);
    for (i = 0; i < p->n_output_steps; i++) {
        const jetid_output_step *st = &p->output_steps[i];
        if (st->kind == JETID_STEP_SENSOR) {
            y = jetid_sensor_step(&s->sensor[i], st, s->dt, y, first);
        } else {
            double theta = (temp_c + JETID_KELVIN_FROM_CELSIUS) / JETID_T_STD_K, delta = pressure_kpa / JETID_P_STD_KPA;
            y *= pow(theta, st->theta_exp) * pow(delta, st->delta_exp);
        }
    }
    s->started = 1;
    return y;
}

static double jetid_mean(const double *x, size_t n)
{
    double s = 0.0;
    size_t i;
    for (i = 0; i < n; i++) s += x[i];
    return n ? s / (double)n : 0.0;
}

static double jetid_steady(const jetid_params *p, double x)
{
    return jetid_static_map(p, p->calibration_dc_gain * x + p->offset);
}

static double jetid_holds_cost(const jetid_params *p, const double *hu, const double *hy, size_t n, double b)
{
    double c = 0.0, r;
    size_t i;
    for (i = 0; i < n; i++) {
        r = hy[i] - jetid_steady(p, hu[i] + b);
        c += r * r;
    }
    return c;
}

/* calibration_drift: the input offset that puts the model's steady states on the run's own holds of
 * the measured output (last half of every stretch holding within 1 % of its range for hold_s), by
 * Gauss-Newton on the holds' means. u: the raw input; it goes through the input stage first. */
static double jetid_calibration_offset(const jetid_params *p, const double *u, const double *temp_c,
                                       const double *pressure_kpa, const double *y, size_t n, double dt)
{
    jetid_state s;
    double *us, *hu, *hy, lo, hi, tol, span, h, offset = 0.0;
    size_t k, start = 0, n_holds = 0, need, tail;
    int it;
    if (!p->has_calibration || n == 0) return 0.0;
    us = malloc(n * sizeof *us);
    hu = malloc(n * sizeof *hu);
    hy = malloc(n * sizeof *hy);
    if (!us || !hu || !hy) {
        free(us);
        free(hu);
        free(hy);
        return 0.0;
    }
    jetid_init(&s, p, dt, 0.0);
    for (k = 0; k < n; k++) {
        us[k] = jetid_input_stage(&s, u[k], temp_c ? temp_c[k] : 0.0, pressure_kpa ? pressure_kpa[k] : 0.0);
        s.started = 1;
    }
    lo = hi = y[0];
    for (k = 1; k < n; k++) {
        if (y[k] < lo) lo = y[k];
        if (y[k] > hi) hi = y[k];
    }
    tol = 0.01 * (hi - lo > DBL_MIN ? hi - lo : DBL_MIN);
    need = (size_t)ceil(p->hold_s / dt);
    tail = (size_t)round(0.5 * p->hold_s / dt);
    if (tail < 2) tail = 2;
    for (k = 1; k <= n; k++) {
        if (k == n || fabs(y[k] - y[start]) > tol) {
            if (k - start >= (need > tail ? need : tail)) {
                hu[n_holds] = jetid_mean(us + (k - tail), tail);
                hy[n_holds] = jetid_mean(y + (k - tail), tail);
                n_holds++;
            }
            start = k;
        }
    }
    lo = hi = us[0];
    for (k = 1; k < n; k++) {
        if (us[k] < lo) lo = us[k];
        if (us[k] > hi) hi = us[k];
    }
    span = hi - lo > DBL_MIN ? hi - lo : DBL_MIN;
    h = 1e-4 * span;
    for (it = 0; n_holds > 0 && isfinite(span) && it < 30; it++) {
        double jtj = 0.0, jtr = 0.0, step;
        for (k = 0; k < n_holds; k++) {
            double r = hy[k] - jetid_steady(p, hu[k] + offset);
            double j = (jetid_steady(p, hu[k] + offset + h) - jetid_steady(p, hu[k] + offset - h)) / (2.0 * h);
            jtj += j * j;
            jtr += j * r;
        }
        if (jtj <= DBL_MIN) break;
        step = jtr / jtj;
        if (step < -0.1 * span) step = -0.1 * span;
        if (step > 0.1 * span) step = 0.1 * span;
        while (fabs(step) > 1e-12 * span &&
               jetid_holds_cost(p, hu, hy, n_holds, offset + step) > jetid_holds_cost(p, hu, hy, n_holds, offset))
            step *= 0.5;
        offset += step;
        if (fabs(step) <= 1e-9 * span) break;
    }
    free(us);
    free(hu);
    free(hy);
    return isfinite(offset) && fabs(offset) <= 0.5 * span ? offset : 0.0;
}
"#;

const MAIN: &str = r#"
#ifndef JETID_NO_MAIN
static int jetid_needs_ambient(const jetid_params *p)
{
    int i;
    for (i = 0; i < p->n_input_steps; i++)
        if (p->input_steps[i].kind == JETID_STEP_AMBIENT) return 1;
    return 0;
}

/* Split a CSV line in place at commas; trims spaces and line ends. Returns the number of cells. */
static int jetid_split(char *line, char **cells, int max)
{
    int n = 0;
    char *c = line;
    while (n < max) {
        char *end;
        while (*c == ' ' || *c == '\t') c++;
        cells[n++] = c;
        end = c + strcspn(c, ",\r\n");
        c = end;
        while (end > cells[n - 1] && (end[-1] == ' ' || end[-1] == '\t')) end--;
        if (*c != ',') {
            *end = '\0';
            break;
        }
        *end = '\0';
        c++;
    }
    return n;
}

#define JETID_MAX_CELLS 1024
#define JETID_MAX_LINE 65536

int main(int argc, char **argv)
{
    static char line[JETID_MAX_LINE];
    char *cells[JETID_MAX_CELLS];
    const char *names[3 + JETID_N_OUTPUTS];
    int cols[3 + JETID_N_OUTPUTS], n_cols = 0, n_cells, i, o, calibrate = 0, ambient = 0, lineno = 1;
    double *data[3 + JETID_N_OUTPUTS];
    size_t n = 0, cap = 1024, k;
    const char *in = NULL, *out = NULL;
    FILE *f;
    double dt, *steps;
    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--calibrate") == 0) calibrate = 1;
        else if (!in) in = argv[i];
        else if (!out) out = argv[i];
        else in = NULL;
    }
    if (!in || !out) {
        fprintf(stderr, "usage: %s IN.csv OUT.csv [--calibrate]\n", argv[0]);
        return 2;
    }
    names[n_cols++] = "time_s";
    names[n_cols++] = JETID_INPUT;
    for (o = 0; o < JETID_N_OUTPUTS; o++) ambient |= jetid_needs_ambient(jetid_outputs[o]);
    if (ambient) {
        names[n_cols++] = "ambient_temp_c";
        names[n_cols++] = "ambient_pressure_kpa";
    }
    if (calibrate)
        for (o = 0; o < JETID_N_OUTPUTS; o++)
            if (jetid_outputs[o]->has_calibration) names[n_cols++] = jetid_outputs[o]->name;
    f = fopen(in, "r");
    if (!f || !fgets(line, sizeof line, f)) {
        fprintf(stderr, "error: cannot read %s\n", in);
        return 1;
    }
    n_cells = jetid_split(line, cells, JETID_MAX_CELLS);
    for (i = 0; i < n_cols; i++) {
        int c;
        cols[i] = -1;
        for (c = 0; c < n_cells; c++)
            if (strcmp(cells[c], names[i]) == 0) cols[i] = c;
        if (cols[i] < 0) {
            fprintf(stderr, "error: %s has no column '%s'\n", in, names[i]);
            return 1;
        }
        data[i] = malloc(cap * sizeof(double));
        if (!data[i]) return 1;
    }
    while (fgets(line, sizeof line, f)) {
        lineno++;
        if (!strchr(line, '\n') && !feof(f)) {
            fprintf(stderr, "error: %s line %d is longer than %d characters\n", in, lineno, JETID_MAX_LINE);
            return 1;
        }
        if (strspn(line, " \t\r\n,") == strlen(line)) continue;
        n_cells = jetid_split(line, cells, JETID_MAX_CELLS);
        if (n == cap) {
            cap *= 2;
            for (i = 0; i < n_cols; i++) {
                double *grown = realloc(data[i], cap * sizeof(double));
                if (!grown) return 1;
                data[i] = grown;
            }
        }
        for (i = 0; i < n_cols; i++) {
            char *end;
            if (cols[i] >= n_cells) {
                fprintf(stderr, "error: %s line %d has no cell for '%s'\n", in, lineno, names[i]);
                return 1;
            }
            data[i][n] = strtod(cells[cols[i]], &end);
            if (end == cells[cols[i]] || *end != '\0' || !isfinite(data[i][n])) {
                fprintf(stderr, "error: %s line %d: '%s' is not a number in column '%s'\n", in, lineno,
                        cells[cols[i]], names[i]);
                return 1;
            }
        }
        n++;
    }
    fclose(f);
    if (n < 2) {
        fprintf(stderr, "error: %s holds fewer than two samples\n", in);
        return 1;
    }
    /* The run's sample time: the median step, to 12 significant digits (as jetid reads it). */
    steps = malloc((n - 1) * sizeof *steps);
    if (!steps) return 1;
    for (k = 0; k + 1 < n; k++) steps[k] = data[0][k + 1] - data[0][k];
    for (k = 1; k + 1 < n; k++) { /* insertion sort: runs are short enough */
        double x = steps[k];
        size_t j = k;
        while (j > 0 && steps[j - 1] > x) {
            steps[j] = steps[j - 1];
            j--;
        }
        steps[j] = x;
    }
    dt = (n - 1) % 2 == 0 ? 0.5 * (steps[(n - 1) / 2 - 1] + steps[(n - 1) / 2]) : steps[(n - 1) / 2];
    free(steps);
    snprintf(line, sizeof line, "%.11e", dt);
    dt = strtod(line, NULL);
    if (!(fabs(dt / JETID_DT - 1.0) <= 0.02)) {
        fprintf(stderr, "error: %s is sampled every %g s but the model every %g s\n", in, dt, JETID_DT);
        return 1;
    }
    if (ambient)
        for (k = 0; k < n; k++)
            if (!(data[2][k] > -JETID_KELVIN_FROM_CELSIUS) || !(data[3][k] > 0.0)) {
                fprintf(stderr, "error: %s sample %lu: unphysical inlet conditions %g degC, %g kPa\n", in,
                        (unsigned long)k, data[2][k], data[3][k]);
                return 1;
            }
    {
        double *y[JETID_N_OUTPUTS];
        for (o = 0; o < JETID_N_OUTPUTS; o++) {
            jetid_state s;
            double offset = 0.0;
            const double *temp = ambient ? data[2] : NULL, *pres = ambient ? data[3] : NULL;
            for (i = 2; i < n_cols; i++)
                if (strcmp(names[i], jetid_outputs[o]->name) == 0)
                    offset = jetid_calibration_offset(jetid_outputs[o], data[1], temp, pres, data[i], n, dt);
            y[o] = malloc(n * sizeof(double));
            if (!y[o]) return 1;
            jetid_init(&s, jetid_outputs[o], dt, offset);
            for (k = 0; k < n; k++) y[o][k] = jetid_step(&s, data[1][k], temp ? temp[k] : 0.0, pres ? pres[k] : 0.0);
        }
        f = fopen(out, "w");
        if (!f) {
            fprintf(stderr, "error: cannot write %s\n", out);
            return 1;
        }
        fprintf(f, "time_s,%s", JETID_INPUT);
        for (o = 0; o < JETID_N_OUTPUTS; o++) fprintf(f, ",%s", jetid_outputs[o]->name);
        fprintf(f, "\n");
        for (k = 0; k < n; k++) {
            fprintf(f, "%.17g,%.17g", data[0][k], data[1][k]);
            for (o = 0; o < JETID_N_OUTPUTS; o++) fprintf(f, ",%.17g", y[o][k]);
            fprintf(f, "\n");
        }
        if (fclose(f) != 0) {
            fprintf(stderr, "error: cannot write %s\n", out);
            return 1;
        }
    }
    return 0;
}
#endif
"#;
