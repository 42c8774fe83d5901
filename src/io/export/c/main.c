
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
