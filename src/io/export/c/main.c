
#ifndef JETID_NO_MAIN
/* ---- The command line: `jetid predict --model MODEL --input IN.csv --out OUT.csv` as a program. ---- */

static int jetid_needs_ambient(const jetid_params *p)
{
    int i;
    for (i = 0; i < p->n_input_steps; i++)
        if (p->input_steps[i].kind == JETID_STEP_AMBIENT) return 1;
    return 0;
}

/* The command line's strings. */
typedef struct {
    const char *in, *out, *sample_time, *window, *quality;
    const char **maps, **invalid;
    int n_maps, n_invalid, calibrate, resample;
} jetid_args;

/* The command line, or 0 when it cannot be read. Options take their value as the next argument or
 * after '='. */
static int jetid_parse_args(int argc, char **argv, jetid_args *a)
{
    int i;
    memset(a, 0, sizeof *a);
    a->maps = jetid_alloc((size_t)argc * sizeof *a->maps);
    a->invalid = jetid_alloc((size_t)argc * sizeof *a->invalid);
    for (i = 1; i < argc; i++) {
        static const char *const names[] = {"--map", "--sample-time", "--window", "--quality", "--invalid"};
        const char *arg = argv[i], *value = NULL;
        int k, which = -1;
        if (strcmp(arg, "--calibrate") == 0) {
            a->calibrate = 1;
            continue;
        }
        if (strcmp(arg, "--resample") == 0) {
            a->resample = 1;
            continue;
        }
        for (k = 0; k < 5; k++) {
            size_t n = strlen(names[k]);
            if (strncmp(arg, names[k], n) == 0 && (arg[n] == '\0' || arg[n] == '=')) {
                which = k;
                value = arg[n] == '=' ? arg + n + 1 : (i + 1 < argc ? argv[++i] : NULL);
            }
        }
        if (which < 0 && strncmp(arg, "--", 2) == 0) return 0;
        if (which >= 0 && !value) return 0;
        if (which == 0) a->maps[a->n_maps++] = value;
        else if (which == 1) a->sample_time = value;
        else if (which == 2) a->window = value;
        else if (which == 3) a->quality = value;
        else if (which == 4) a->invalid[a->n_invalid++] = value;
        else if (!a->in) a->in = arg;
        else if (!a->out) a->out = arg;
        else return 0;
    }
    return a->in && a->out;
}

/* cli::positive_secs, as `jetid predict` reads --sample-time. */
static double jetid_positive_secs(const char *text)
{
    char *trimmed = jetid_trim(text), buf[JETID_DISPLAY_LEN];
    double v;
    jetid_text m = {NULL, 0, 0};
    int ok = jetid_parse_f64(trimmed, strlen(trimmed), 0, &v);
    free(trimmed);
    if (ok && isfinite(v) && v > 0.0) return v;
    jetid_add(&m, "invalid value '");
    jetid_add(&m, text);
    jetid_add(&m, "' for '--sample-time <SECONDS>': must be a positive number of seconds, got ");
    if (ok) {
        jetid_add(&m, jetid_display(v, buf));
    } else {
        jetid_add(&m, "\"");
        jetid_add(&m, text);
        jetid_add(&m, "\"");
    }
    jetid_refuse(&m);
    return 0.0;
}

/* cli/read_args.rs ReadArgs::options: the --map, --window and --invalid strings checked in that
 * order; --calibrate maps every output calibration_drift corrects, as --map output=NAME. */
static void jetid_load_options(const jetid_args *a, jetid_options *o)
{
    int k;
    memset(o, 0, sizeof *o);
    for (k = 0; k < a->n_maps; k++) jetid_add_map_spec(o, a->maps[k]);
    for (k = 0; a->calibrate && k < JETID_N_OUTPUTS; k++)
        if (jetid_outputs[k]->has_calibration) {
            jetid_text spec = {NULL, 0, 0};
            jetid_add(&spec, "output=");
            jetid_add(&spec, jetid_outputs[k]->name);
            jetid_add_map_spec(o, spec.s);
        }
    jetid_check_map(o);
    if (a->sample_time) {
        o->has_sample_time = 1;
        o->sample_time_secs = jetid_positive_secs(a->sample_time);
    }
    if (a->window) o->window = jetid_parse_window(a->window);
    o->quality = a->quality;
    o->resample = a->resample;
    for (k = 0; k < a->n_invalid; k++) jetid_add_invalid_spec(o, a->invalid[k]);
    if (o->window.kind == JETID_WINDOW_AUTO) {
        fprintf(stderr, "error: --window auto is not available in this program: the running part is found by jetid's "
                        "running-window search; give --window START:END (`jetid inspect RUN.csv --window auto` shows "
                        "the part it finds)\n");
        exit(1);
    }
    /* Started from the steady state, `jetid predict` needs the input alone unless outputs are mapped. */
    o->input_only = o->n_outputs == 0;
}

/* What `jetid predict` checks of a run before simulating it (cli/predict.rs run). */
static void jetid_check_run(const jetid_run *run, const char *file)
{
    char a[JETID_DISPLAY_LEN], b[JETID_DISPLAY_LEN];
    jetid_text m = {NULL, 0, 0};
    if (strcmp(run->names[0], JETID_INPUT) != 0) {
        jetid_add(&m, JETID_MODEL_FILE " was identified from the input '" JETID_INPUT "', but ");
        jetid_add(&m, file);
        jetid_add(&m, " gives '");
        jetid_add(&m, run->names[0]);
        jetid_add(&m, "' as its input: a model driven by another signal predicts nonsense (map the same signal with "
                      "--map input=COLUMN)");
        jetid_refuse(&m);
    }
    if (fabs(run->dt / JETID_DT - 1.0) > 0.02) {
        jetid_add(&m, file);
        jetid_add(&m, " is sampled every ");
        jetid_add(&m, jetid_significant(run->dt, 5, a));
        jetid_add(&m, " s but the model " JETID_MODEL_FILE " every ");
        jetid_add(&m, jetid_significant(JETID_DT, 5, b));
        jetid_add(&m, " s; the model is discrete-time: resample the run (--resample puts an irregular log on its "
                      "median step) or identify a model at its sample time");
        jetid_refuse(&m);
    }
}

/* Run::aux, else Run::channel: the values of the channel called `name`, or NULL. */
static double *jetid_channel(const jetid_run *run, const char *name)
{
    int c;
    for (c = 1 + run->n_outputs; c < run->n_channels; c++)
        if (strcmp(run->names[c], name) == 0) return run->values[c];
    for (c = 0; c < run->n_channels; c++)
        if (strcmp(run->names[c], name) == 0) return run->values[c];
    return NULL;
}

/* AmbientCorrection::conditions: the inlet channels an output corrected for them reads, checked. */
static void jetid_ambient_channels(const jetid_run *run, const char *output, const char *file, double **temp,
                                   double **pres)
{
    static const char *const names[2] = {"ambient_temp_c", "ambient_pressure_kpa"};
    double *found[2], lowest[2] = {-JETID_KELVIN_FROM_CELSIUS, 0.0};
    char buf[JETID_DISPLAY_LEN], at[32];
    size_t k;
    int c;
    for (c = 0; c < 2; c++) {
        found[c] = jetid_channel(run, names[c]);
        if (!found[c]) {
            jetid_text m = {NULL, 0, 0};
            jetid_add(&m, "simulating output '");
            jetid_add(&m, output);
            jetid_add(&m, "' on ");
            jetid_add(&m, file);
            jetid_add(&m, ": effect 'ambient_correction' needs the channel '");
            jetid_add(&m, names[c]);
            jetid_add(&m, "', which run '");
            jetid_add(&m, run->name);
            jetid_add(&m, "' does not have");
            jetid_refuse(&m);
        }
    }
    for (c = 0; c < 2; c++)
        for (k = 0; k < run->n; k++)
            if (found[c][k] <= lowest[c]) {
                jetid_text m = {NULL, 0, 0};
                jetid_add(&m, "simulating output '");
                jetid_add(&m, output);
                jetid_add(&m, "' on ");
                jetid_add(&m, file);
                jetid_add(&m, ": channel '");
                jetid_add(&m, names[c]);
                jetid_add(&m, "' of run '");
                jetid_add(&m, run->name);
                jetid_add(&m, "' has the unphysical value ");
                jetid_add(&m, jetid_display(found[c][k], buf));
                snprintf(at, sizeof at, " at sample %lu", (unsigned long)k);
                jetid_add(&m, at);
                jetid_refuse(&m);
            }
    *temp = found[0];
    *pres = found[1];
}

/* write_run: time_s, the input and one column per output, to a temporary file renamed into place. */
static void jetid_write_prediction(const char *path, const jetid_run *run, double *const *y)
{
    jetid_text tmp = {NULL, 0, 0};
    FILE *f;
    size_t k;
    int o, ok;
    jetid_add(&tmp, path);
    jetid_add(&tmp, ".tmp");
    f = fopen(tmp.s, "w");
    ok = f != NULL;
    if (ok) {
        fprintf(f, "time_s,%s", JETID_INPUT);
        for (o = 0; o < JETID_N_OUTPUTS; o++) fprintf(f, ",%s", jetid_outputs[o]->name);
        fprintf(f, "\n");
        for (k = 0; k < run->n; k++) {
            fprintf(f, "%.17g,%.17g", run->t[k], run->values[0][k]);
            for (o = 0; o < JETID_N_OUTPUTS; o++) fprintf(f, ",%.17g", y[o][k]);
            fprintf(f, "\n");
        }
        ok = fclose(f) == 0 && rename(tmp.s, path) == 0;
    }
    if (!ok) {
        jetid_text m = {NULL, 0, 0};
        char code[32];
        int err = errno;
        snprintf(code, sizeof code, " (os error %d)", err);
        remove(tmp.s);
        jetid_add(&m, path);
        jetid_add(&m, ": cannot write the file: ");
        jetid_add(&m, strerror(err));
        jetid_add(&m, code);
        jetid_refuse(&m);
    }
    free(tmp.s);
}

int main(int argc, char **argv)
{
    jetid_args args;
    jetid_options opts;
    jetid_run run;
    double *y[JETID_N_OUTPUTS], *temp = NULL, *pres = NULL;
    size_t k;
    int o, c;
    if (!jetid_parse_args(argc, argv, &args)) {
        fprintf(stderr,
                "usage: %s IN.csv OUT.csv [--calibrate] [--map ROLE=COLUMN]... [--sample-time SECONDS]\n"
                "       [--window START:END] [--quality COLUMN] [--invalid CHANNEL=V1,V2]... [--resample]\n",
                argv[0]);
        return 2;
    }
    jetid_load_options(&args, &opts);
    jetid_load_run(args.in, &opts, &run);
    jetid_check_run(&run, args.in);
    for (o = 0; o < JETID_N_OUTPUTS; o++)
        if (jetid_needs_ambient(jetid_outputs[o]) && !temp)
            jetid_ambient_channels(&run, jetid_outputs[o]->name, args.in, &temp, &pres);
    for (o = 0; o < JETID_N_OUTPUTS; o++) {
        jetid_state s;
        double offset = 0.0;
        for (c = 1; c <= run.n_outputs; c++)
            if (strcmp(run.names[c], jetid_outputs[o]->name) == 0)
                offset = jetid_calibration_offset(jetid_outputs[o], run.values[0], temp, pres, run.values[c], run.n,
                                                  run.dt);
        y[o] = jetid_alloc(run.n * sizeof(double));
        jetid_init(&s, jetid_outputs[o], run.dt, offset);
        for (k = 0; k < run.n; k++)
            y[o][k] = jetid_step(&s, run.values[0][k], temp ? temp[k] : 0.0, pres ? pres[k] : 0.0);
    }
    jetid_write_prediction(args.out, &run, y);
    return 0;
}
#endif
