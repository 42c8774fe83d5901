
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
    int end_trend; /* 1: beyond |x| > 1 the map continues its end (see jetid_map_polynomial) */
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
    double load_exponent; /* > 0: the spool runs its power balance through the map (jetid_balance_factor) */
    int has_soak;
    double soak_gain, soak_tau_s;
    double soak_power_exponent; /* > 0: the soak acts on y^k after the static map; 0: on v */
    int has_rate_limit;
    double rise_per_s, fall_per_s;
    int limit_through_map;
    int n_output_steps;
    jetid_output_step output_steps[2];
    int has_read_off; /* 1: the output is read off the speed, P(y) after the output steps */
    double read_off_center, read_off_scale;
    double read_off_c0, read_off_c1, read_off_c2, read_off_c3, read_off_c4;
    double read_off_theta_exp, read_off_delta_exp; /* the output's own correction, when corrected */
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

static double jetid_map_slope(const jetid_params *p, double v);
static double jetid_map_smooth_slope(const jetid_params *p, double v);
static double jetid_map_polynomial(const jetid_params *p, double x);
static double jetid_static_map(const jetid_params *p, double v);

/* power_balance.rs PowerBalance::time_constant: (r - x)/dx/dt of the spool's power balance up to a
 * constant, or 0 where the map gives no positive speed. */
static double jetid_balance_tau(const jetid_params *p, double x, double r, double smooth_ref, double speed_ref)
{
    double k = p->load_exponent, v = p->gain * x + p->offset, vr, n, dn_dx, smooth, p_x, p_r, dp_dx, tau;
    n = jetid_static_map(p, v) / speed_ref;
    dn_dx = jetid_map_slope(p, v) * p->gain / speed_ref;
    if (!(n > 0.0)) return 0.0;
    vr = p->gain * r + p->offset;
    smooth = jetid_map_polynomial(p, (v - p->v_center) / p->v_scale);
    p_x = pow(fmax(smooth / smooth_ref, 1e-6), k);
    p_r = pow(fmax(jetid_map_polynomial(p, (vr - p->v_center) / p->v_scale) / smooth_ref, 1e-6), k);
    if (fabs(p_r - p_x) > 1e-9 * fmax(fabs(p_x), 1e-9)) {
        dp_dx = (p_r - p_x) / (r - x);
    } else {
        double sr = fmax(smooth / smooth_ref, 1e-6);
        dp_dx = k * pow(sr, k - 1.0) * jetid_map_smooth_slope(p, v) * p->gain / smooth_ref;
    }
    tau = n * dn_dx / dp_dx;
    return isfinite(tau) && tau > 0.0 ? tau : 0.0;
}

/* power_balance.rs PowerBalance::factor: the spool's time constant at state x heading for r over
 * the one at the reference operating point (bounded to [0.05, 20]); 1 where the map gives no
 * positive speed. */
static double jetid_balance_factor(const jetid_params *p, double x, double r)
{
    double v_ref = p->gain * p->ref_input + p->offset, smooth_ref, speed_ref, at_ref, tau;
    smooth_ref = jetid_map_polynomial(p, (v_ref - p->v_center) / p->v_scale);
    speed_ref = jetid_static_map(p, v_ref);
    if (!(smooth_ref > 0.0 && speed_ref > 0.0)) return 1.0;
    at_ref = jetid_balance_tau(p, p->ref_input, p->ref_input, smooth_ref, speed_ref);
    tau = jetid_balance_tau(p, x, r, smooth_ref, speed_ref);
    if (at_ref <= 0.0 || tau <= 0.0) return 1.0;
    tau /= at_ref;
    return tau < 0.05 ? 0.05 : tau > 20.0 ? 20.0 : tau;
}

/* rate_limit.rs StateLimit::clamp: the spool state's change limited in the limited quantity's units
 * (the output's, through the map's slope, or v's). */
static double jetid_limit_state(const jetid_state *s, double x, double next)
{
    const jetid_params *p = s->p;
    double up = p->rise_per_s * s->dt, down = p->fall_per_s * s->dt, v = p->gain * x + p->offset, rate, r, change;
    rate = p->gain * (p->limit_through_map ? jetid_map_slope(p, v) : 1.0);
    if (!isfinite(rate) || fabs(rate) <= DBL_MIN) return next;
    if (rate < 0.0) {
        double t = up;
        up = down;
        down = t;
    }
    r = fabs(rate);
    change = next - x;
    if (change > up / r) change = up / r;
    if (change < -down / r) change = -down / r;
    return x + change;
}

static double jetid_spool_step(jetid_state *s, double u, int first)
{
    const jetid_params *p = s->p;
    double r, factor = 1.0, f, mag, re, im, next;
    u = jetid_delay_step(&s->dead, p->dead_time, 0.0, u, first);
    r = p->has_rest ? jetid_filter_step(&p->rest, &s->rest, u, first) : u;
    if (first) s->x = s->x_old = s->prev = s->prev_old = r;
    if (p->has_schedule && p->load_exponent > 0.0)
        factor = jetid_balance_factor(p, s->x, s->prev) *
                 exp(-p->state_log_ratio * (s->x - p->ref_input) / p->input_span);
    else if (p->has_schedule)
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
    if (p->has_rate_limit) next = jetid_limit_state(s, s->x, next);
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

/* The polynomial c[0] + c[1] x + ... (n coefficients): its value (k = 0), slope d/dx (k = 1) or
 * curvature (k = 2) at x. */
static double jetid_poly_of(const double *c, int n, double x, int k)
{
    double y = 0.0;
    int i;
    for (i = n - 1; i >= k; i--) y = y * x + (k == 0 ? 1.0 : k == 1 ? i : i * (i - 1.0)) * c[i];
    return y;
}

static double jetid_poly(const jetid_params *p, double x, int k)
{
    return jetid_poly_of(p->coeffs, p->n_coeffs, x, k);
}

/* static_map.rs StaticMap::eval of the polynomial c (n coefficients) at x. Inside |x| <= 1
 * (everywhere without end_trend) the polynomial; beyond it the end's value, slope and curvature
 * continue: an exponential approach where the curvature slows the map outwards, else their parabola. */
static double jetid_polynomial_map(const double *c, int n, int end_trend, double x)
{
    double end, value, slope, curvature, t, length;
    if (!end_trend || (x <= 1.0 && x >= -1.0)) return jetid_poly_of(c, n, x, 0);
    end = x > 0.0 ? 1.0 : -1.0;
    value = jetid_poly_of(c, n, end, 0);
    slope = jetid_poly_of(c, n, end, 1);
    curvature = jetid_poly_of(c, n, end, 2);
    t = end * (x - end);
    if (end * slope * curvature < 0.0) {
        length = fabs(slope / curvature);
        return value + end * slope * (length * (1.0 - exp(-t / length)));
    }
    return value + (end * slope * t + 0.5 * curvature * t * t);
}

/* The polynomial part of the static map f at x. */
static double jetid_map_polynomial(const jetid_params *p, double x)
{
    return jetid_polynomial_map(p->coeffs, p->n_coeffs, p->end_trend, x);
}

/* read_off_speed.rs ReadOffSpeed::eval: the output at shaft speed n (a quartic with its end trend). */
static double jetid_read_off(const jetid_params *p, double n)
{
    const double c[5] = {p->read_off_c0, p->read_off_c1, p->read_off_c2, p->read_off_c3, p->read_off_c4};
    return jetid_polynomial_map(c, 5, 1, (n - p->read_off_center) / p->read_off_scale);
}

/* static_map.rs StaticMap::slope: df/dv of the polynomial part. */
static double jetid_map_smooth_slope(const jetid_params *p, double v)
{
    double x = (v - p->v_center) / p->v_scale, dx, end, slope, curvature, t;
    if (!p->end_trend || (x <= 1.0 && x >= -1.0)) {
        dx = jetid_poly(p, x, 1);
    } else {
        end = x > 0.0 ? 1.0 : -1.0;
        slope = jetid_poly(p, end, 1);
        curvature = jetid_poly(p, end, 2);
        t = end * (x - end);
        if (end * slope * curvature < 0.0) {
            dx = slope * exp(-t / fabs(slope / curvature));
        } else {
            dx = slope + end * curvature * t;
        }
    }
    return dx / p->v_scale;
}

/* The map's slope with the kink: df/dv. */
static double jetid_map_slope(const jetid_params *p, double v)
{
    double dx = jetid_map_smooth_slope(p, v);
    if (p->has_kink && v > p->knot_v) dx += p->slope_change;
    return dx;
}

/* f(v): the map in x = (v - v_center)/v_scale, plus the kink of static_map_order. */
static double jetid_static_map(const jetid_params *p, double v)
{
    double kink = 0.0;
    if (p->has_kink) kink = p->slope_change * (v - p->knot_v > 0.0 ? v - p->knot_v : 0.0);
    return jetid_map_polynomial(p, (v - p->v_center) / p->v_scale) + kink;
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

/* The soak branch on x: x + g (S_tau(z) x - x), S_tau a unit-gain first-order lag from x's first value. */
static double jetid_soak_step(jetid_state *s, double x, int first)
{
    if (first) s->soak_s = x;
    s->soak_s = s->soak_a * s->soak_s + (1.0 - s->soak_a) * x;
    return x + s->p->soak_gain * (s->soak_s - x);
}

/* The soak on the output's power y^k (k = soak_power_exponent), the output given back; signs kept. */
static double jetid_soak_power_step(jetid_state *s, double y, int first)
{
    double k = s->p->soak_power_exponent;
    double power = jetid_soak_step(s, copysign(pow(fabs(y), k), y), first);
    return copysign(pow(fabs(power), 1.0 / k), power);
}

/* The static map's argument v from the next input-stage sample (calibration offset added). */
static double jetid_linear_step(jetid_state *s, double u, int first)
{
    const jetid_params *p = s->p;
    double v;
    u += s->calibration_offset;
    v = p->split ? jetid_spool_step(s, u, first) : jetid_filter_step(&p->tf, &s->linear, u, first);
    if (p->has_soak && !(p->soak_power_exponent > 0.0)) v = jetid_soak_step(s, v, first);
    return v + p->offset;
}

/* The output from v: the static map, then the sensors (their state in sensor) and the inlet
 * conditions' factor; read off the speed last, for an output that is. */
static double jetid_output_stage(jetid_state *s, double v, double temp_c, double pressure_kpa, int first)
{
    const jetid_params *p = s->p;
    jetid_sensor_state *sensor = s->sensor;
    double dt = s->dt;
    int i, corrected = 0;
    double y = jetid_static_map(p, v), theta = 1.0, delta = 1.0, factor = 1.0;
    if (p->has_soak && p->soak_power_exponent > 0.0) y = jetid_soak_power_step(s, y, first);
    for (i = 0; i < p->n_output_steps; i++) {
        const jetid_output_step *st = &p->output_steps[i];
        if (st->kind == JETID_STEP_SENSOR) {
            y = jetid_sensor_step(&sensor[i], st, dt, y, first);
        } else {
            theta = (temp_c + JETID_KELVIN_FROM_CELSIUS) / JETID_T_STD_K;
            delta = pressure_kpa / JETID_P_STD_KPA;
            factor = pow(theta, st->theta_exp) * pow(delta, st->delta_exp);
            y *= factor;
            corrected = 1;
        }
    }
    /* Read off the speed: in corrected quantities when the speed's model is corrected. */
    if (p->has_read_off && corrected) {
        y = jetid_read_off(p, y / factor) * pow(theta, p->read_off_theta_exp) * pow(delta, p->read_off_delta_exp);
    } else if (p->has_read_off) {
        y = jetid_read_off(p, y);
    }
    return y;
}

static double jetid_step(jetid_state *s, double u, double temp_c, double pressure_kpa)
{
    int first = !s->started;
    double v = jetid_linear_step(s, jetid_input_stage(s, u, temp_c, pressure_kpa), first);
    double y = jetid_output_stage(s, v, temp_c, pressure_kpa, first);
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

/* The holds' means of the model's response to the input offset b: the output stage of v + G(1)·b,
 * v the linear block's response without the offset; into out[0 .. n_holds). */
static void jetid_response_at_holds(const jetid_params *p, const double *v, const double *temp_c,
                                    const double *pressure_kpa, size_t n, double dt, double b, const size_t *wa,
                                    const size_t *wb, size_t n_holds, double *out)
{
    jetid_state s;
    size_t k, h = 0;
    double sum = 0.0;
    jetid_init(&s, p, dt, 0.0);
    for (k = 0; k < n && h < n_holds; k++) {
        double y = jetid_output_stage(&s, v[k] + p->calibration_dc_gain * b, temp_c ? temp_c[k] : 0.0,
                                     pressure_kpa ? pressure_kpa[k] : 0.0, k == 0);
        if (k >= wa[h]) sum += y;
        if (k + 1 == wb[h]) {
            out[h] = sum / (double)(wb[h] - wa[h]);
            sum = 0.0;
            h++;
        }
    }
}

static double jetid_holds_cost(const double *hy, const double *m, size_t n_holds)
{
    double c = 0.0, r;
    size_t i;
    for (i = 0; i < n_holds; i++) {
        r = hy[i] - m[i];
        c += r * r;
    }
    return c;
}

/* The windows [a, b) of x's holds: the last tail_s of every stretch holding within 1 % of x's range
 * for at least hold_s (and tail_s), appended to a/b from index count; returns the new count. */
static size_t jetid_plateaus(const double *x, size_t n, double dt, double hold_s, double tail_s, size_t *a,
                             size_t *b, size_t count)
{
    double lo = x[0], hi = x[0], tol;
    size_t k, start = 0, need, tail;
    for (k = 1; k < n; k++) {
        if (x[k] < lo) lo = x[k];
        if (x[k] > hi) hi = x[k];
    }
    tol = 0.01 * (hi - lo > DBL_MIN ? hi - lo : DBL_MIN);
    need = (size_t)ceil(hold_s / dt);
    tail = (size_t)round(tail_s / dt);
    if (tail < 2) tail = 2;
    for (k = 1; k <= n; k++) {
        if (k == n || fabs(x[k] - x[start]) > tol) {
            if (k - start >= (need > tail ? need : tail)) {
                a[count] = k - tail;
                b[count] = k;
                count++;
            }
            start = k;
        }
    }
    return count;
}

/* calibration_drift: the input offset that puts the model's response on the run's own steady
 * stretches, by Gauss-Newton on their means. A steady stretch is the last half of a hold of the
 * measured output longer than hold_s, or the last hold_s / 2 of a hold of the input after hold_s of
 * settling, merged where the two overlap. u: the raw input; it goes through the input stage first. */
static double jetid_calibration_offset(const jetid_params *p, const double *u, const double *temp_c,
                                       const double *pressure_kpa, const double *y, size_t n, double dt)
{
    jetid_state s;
    double *us, *v, *hy, *m, lo, hi, span, h, offset = 0.0, tail_s;
    size_t k, i, n_found, n_holds = 0, *wa, *wb, ta, tb;
    int it;
    if (!p->has_calibration || n == 0) return 0.0;
    us = malloc(n * sizeof *us);
    v = malloc(n * sizeof *v);
    hy = malloc(n * sizeof *hy);
    m = malloc(4 * n * sizeof *m);
    wa = malloc(2 * n * sizeof *wa);
    wb = malloc(2 * n * sizeof *wb);
    if (!us || !v || !hy || !m || !wa || !wb) {
        free(us);
        free(v);
        free(hy);
        free(m);
        free(wa);
        free(wb);
        return 0.0;
    }
    jetid_init(&s, p, dt, 0.0);
    for (k = 0; k < n; k++) {
        us[k] = jetid_input_stage(&s, u[k], temp_c ? temp_c[k] : 0.0, pressure_kpa ? pressure_kpa[k] : 0.0);
        v[k] = jetid_linear_step(&s, us[k], k == 0);
        s.started = 1;
    }
    tail_s = 0.5 * p->hold_s;
    n_found = jetid_plateaus(y, n, dt, p->hold_s, tail_s, wa, wb, 0);
    n_found = jetid_plateaus(us, n, dt, p->hold_s + tail_s, tail_s, wa, wb, n_found);
    /* Sorted by start, then end (insertion sort: a run has a few holds). */
    for (k = 1; k < n_found; k++) {
        ta = wa[k];
        tb = wb[k];
        for (i = k; i > 0 && (wa[i - 1] > ta || (wa[i - 1] == ta && wb[i - 1] > tb)); i--) {
            wa[i] = wa[i - 1];
            wb[i] = wb[i - 1];
        }
        wa[i] = ta;
        wb[i] = tb;
    }
    /* Merged where they overlap, in place. */
    for (k = 0; k < n_found; k++) {
        if (n_holds > 0 && wa[k] <= wb[n_holds - 1]) {
            if (wb[k] > wb[n_holds - 1]) wb[n_holds - 1] = wb[k];
        } else {
            wa[n_holds] = wa[k];
            wb[n_holds] = wb[k];
            n_holds++;
        }
    }
    for (k = 0; k < n_holds; k++) hy[k] = jetid_mean(y + wa[k], wb[k] - wa[k]);
    lo = hi = us[0];
    for (k = 1; k < n; k++) {
        if (us[k] < lo) lo = us[k];
        if (us[k] > hi) hi = us[k];
    }
    span = hi - lo > DBL_MIN ? hi - lo : DBL_MIN;
    h = 1e-4 * span;
    {
        /* The response's hold means: here, offset + h, offset - h, and the trial step. */
        double *here = m, *up = m + n, *down = m + 2 * n, *next = m + 3 * n, *swap;
        if (n_holds > 0) jetid_response_at_holds(p, v, temp_c, pressure_kpa, n, dt, offset, wa, wb, n_holds, here);
        for (it = 0; n_holds > 0 && isfinite(span) && it < 30; it++) {
            double jtj = 0.0, jtr = 0.0, step;
            jetid_response_at_holds(p, v, temp_c, pressure_kpa, n, dt, offset + h, wa, wb, n_holds, up);
            jetid_response_at_holds(p, v, temp_c, pressure_kpa, n, dt, offset - h, wa, wb, n_holds, down);
            for (k = 0; k < n_holds; k++) {
                double j = (up[k] - down[k]) / (2.0 * h);
                jtj += j * j;
                jtr += j * (hy[k] - here[k]);
            }
            if (!(jtj > DBL_MIN)) break;
            step = jtr / jtj;
            if (step < -0.1 * span) step = -0.1 * span;
            if (step > 0.1 * span) step = 0.1 * span;
            jetid_response_at_holds(p, v, temp_c, pressure_kpa, n, dt, offset + step, wa, wb, n_holds, next);
            while (fabs(step) > 1e-12 * span && !(jetid_holds_cost(hy, next, n_holds) <= jetid_holds_cost(hy, here, n_holds))) {
                step *= 0.5;
                jetid_response_at_holds(p, v, temp_c, pressure_kpa, n, dt, offset + step, wa, wb, n_holds, next);
            }
            offset += step;
            swap = here;
            here = next;
            next = swap;
            if (fabs(step) <= 1e-9 * span) break;
        }
    }
    free(us);
    free(v);
    free(hy);
    free(m);
    free(wa);
    free(wb);
    return isfinite(offset) && fabs(offset) <= 0.5 * span ? offset : 0.0;
}
