
#ifndef JETID_NO_MAIN
/* ---- Reading a run file as `jetid predict` reads it (src/io/csv_run): the same steps in the same
 * order, the same checks and the same messages, so that this program accepts and refuses the same
 * files. Each function names the Rust function it follows. ---- */

#define JETID_TIME_COLUMN "time_s"
#define JETID_INPUT_COLUMN "fuel_flow_gph"
#define JETID_MIN_SAMPLES 10
#define JETID_MAX_BAD_FRACTION 0.5
#define JETID_TIME_TOLERANCE 0.01
#define JETID_RECORD_READ_BACK 65536
#define JETID_DISPLAY_LEN 400 /* the longest f64 Rust's `{}` writes (5e-324) fits */
#define JETID_NUMBER 0
#define JETID_MISSING 1
#define JETID_NOT_NUMBER 2

static const char *const jetid_canonical_outputs[2] = {"shaft_speed_rpm", "thrust_n"};

/* A growing text, for messages. */
typedef struct {
    char *s;
    size_t len, cap;
} jetid_text;

static void *jetid_alloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p) {
        fprintf(stderr, "error: out of memory\n");
        exit(1);
    }
    return p;
}

static void *jetid_grow(void *p, size_t n)
{
    p = realloc(p, n ? n : 1);
    if (!p) {
        fprintf(stderr, "error: out of memory\n");
        exit(1);
    }
    return p;
}

static void jetid_add_bytes(jetid_text *t, const char *s, size_t n)
{
    if (t->len + n + 1 > t->cap) {
        t->cap = 2 * (t->len + n + 1);
        t->s = jetid_grow(t->s, t->cap);
    }
    memcpy(t->s + t->len, s, n);
    t->len += n;
    t->s[t->len] = '\0';
}

static void jetid_add(jetid_text *t, const char *s)
{
    jetid_add_bytes(t, s, strlen(s));
}

/* Print "error: MESSAGE" and stop with status 1, as jetid does. */
static void jetid_refuse(jetid_text *message)
{
    fprintf(stderr, "error: %s\n", message->s ? message->s : "");
    exit(1);
}

/* An f64 as Rust's `{}` writes it: the shortest digits that read back, never an exponent. */
static const char *jetid_display(double x, char *out)
{
    char e[64], digits[24], *o = out;
    const char *c;
    int p, nd = 0, point, k;
    if (isnan(x)) return "NaN";
    if (isinf(x)) return x > 0 ? "inf" : "-inf";
    if (x == 0.0) return signbit(x) ? "-0" : "0";
    if (x < 0) *o++ = '-';
    for (p = 1; p <= 17; p++) {
        snprintf(e, sizeof e, "%.*e", p - 1, fabs(x));
        if (strtod(e, NULL) == fabs(x)) break;
    }
    for (c = e; *c && *c != 'e'; c++)
        if (*c >= '0' && *c <= '9') digits[nd++] = *c;
    point = atoi(c + 1) + 1;
    while (nd > 1 && digits[nd - 1] == '0') nd--;
    if (point >= nd) {
        for (k = 0; k < nd; k++) *o++ = digits[k];
        for (k = nd; k < point; k++) *o++ = '0';
    } else if (point > 0) {
        for (k = 0; k < nd; k++) {
            if (k == point) *o++ = '.';
            *o++ = digits[k];
        }
    } else {
        *o++ = '0';
        *o++ = '.';
        for (k = 0; k < -point; k++) *o++ = '0';
        for (k = 0; k < nd; k++) *o++ = digits[k];
    }
    *o = '\0';
    return out;
}

/* core::numerics::stats::significant: x to `digits` significant digits. */
static const char *jetid_significant(double x, int digits, char *out)
{
    double magnitude;
    char *e;
    if (x == 0.0 || !isfinite(x)) return jetid_display(x, out);
    magnitude = floor(log10(fabs(x)));
    if (magnitude >= -3.0 && magnitude < 5.0) {
        int decimals = digits - 1 - (int)magnitude;
        snprintf(out, JETID_DISPLAY_LEN, "%.*f", decimals > 0 ? decimals : 0, x);
        return out;
    }
    snprintf(out, JETID_DISPLAY_LEN, "%.*e", digits - 1, x);
    e = strchr(out, 'e');
    if (e) snprintf(e + 1, 16, "%d", atoi(e + 1)); /* Rust writes e-5, not e-05 */
    return out;
}

/* ---- Text: UTF-8, Latin-1 and white space as Rust reads them. ---- */

/* The length of the valid UTF-8 sequence at s (of n bytes), or 0 with *bad the bytes of its maximal
 * invalid part (from_utf8_lossy replaces them by one U+FFFD). */
static size_t jetid_utf8_len(const unsigned char *s, size_t n, size_t *bad)
{
    unsigned char b = s[0], lo = 0x80, hi = 0xBF;
    size_t len, k;
    *bad = 1;
    if (b < 0x80) return 1;
    if (b >= 0xC2 && b <= 0xDF) len = 2;
    else if (b >= 0xE0 && b <= 0xEF) len = 3;
    else if (b >= 0xF0 && b <= 0xF4) len = 4;
    else return 0;
    if (b == 0xE0) lo = 0xA0;
    if (b == 0xED) hi = 0x9F;
    if (b == 0xF0) lo = 0x90;
    if (b == 0xF4) hi = 0x8F;
    for (k = 1; k < len; k++) {
        if (k >= n || s[k] < (k == 1 ? lo : 0x80) || s[k] > (k == 1 ? hi : 0xBF)) return 0;
        *bad = k + 1;
    }
    return len;
}

static int jetid_utf8_valid(const unsigned char *s, size_t n)
{
    size_t i = 0, bad, len;
    while (i < n) {
        len = jetid_utf8_len(s + i, n - i, &bad);
        if (!len) return 0;
        i += len;
    }
    return 1;
}

/* String::from_utf8_lossy, cut to max_chars characters followed by "…" (table.rs shown). */
static void jetid_add_lossy(jetid_text *t, const unsigned char *s, size_t n, size_t max_chars)
{
    size_t i = 0, chars = 0, bad, len;
    while (i < n) {
        if (chars == max_chars) {
            jetid_add(t, "\xe2\x80\xa6");
            return;
        }
        len = jetid_utf8_len(s + i, n - i, &bad);
        if (len) {
            jetid_add_bytes(t, (const char *)s + i, len);
            i += len;
        } else {
            jetid_add(t, "\xef\xbf\xbd");
            i += bad;
        }
        chars++;
    }
}

/* The code point at s (valid UTF-8), and its length. */
static unsigned long jetid_code_point(const unsigned char *s, size_t *len)
{
    if (s[0] < 0x80) return *len = 1, s[0];
    if (s[0] < 0xE0) return *len = 2, ((s[0] & 0x1Ful) << 6) | (s[1] & 0x3F);
    if (s[0] < 0xF0) return *len = 3, ((s[0] & 0x0Ful) << 12) | ((s[1] & 0x3Ful) << 6) | (s[2] & 0x3F);
    return *len = 4, ((s[0] & 0x07ul) << 18) | ((s[1] & 0x3Ful) << 12) | ((s[2] & 0x3Ful) << 6) | (s[3] & 0x3F);
}

/* char::is_whitespace. */
static int jetid_is_whitespace(unsigned long c)
{
    return (c >= 0x09 && c <= 0x0D) || c == 0x20 || c == 0x85 || c == 0xA0 || c == 0x1680 ||
           (c >= 0x2000 && c <= 0x200A) || c == 0x2028 || c == 0x2029 || c == 0x202F || c == 0x205F || c == 0x3000;
}

/* str::trim of a valid UTF-8 string, into a new string. */
static char *jetid_trim(const char *text)
{
    const unsigned char *s = (const unsigned char *)text;
    size_t a = 0, b = strlen(text), len;
    char *out;
    while (a < b && jetid_is_whitespace(jetid_code_point(s + a, &len))) a += len;
    while (b > a) {
        size_t start = b - 1;
        while (start > a && (s[start] & 0xC0) == 0x80) start--;
        if (!jetid_is_whitespace(jetid_code_point(s + start, &len))) break;
        b = start;
    }
    out = jetid_alloc(b - a + 1);
    memcpy(out, text + a, b - a);
    out[b - a] = '\0';
    return out;
}

/* A header name as read_table reads it: UTF-8, else Latin-1 (each byte its code point); a BOM
 * dropped from the first; trimmed. */
static char *jetid_header_name(const unsigned char *s, size_t n, int first)
{
    jetid_text t = {NULL, 0, 0};
    char *name;
    size_t i;
    if (jetid_utf8_valid(s, n)) {
        jetid_add_bytes(&t, (const char *)s, n);
    } else {
        for (i = 0; i < n; i++) {
            char two[2];
            if (s[i] < 0x80) {
                jetid_add_bytes(&t, (const char *)s + i, 1);
            } else {
                two[0] = (char)(0xC0 | (s[i] >> 6));
                two[1] = (char)(0x80 | (s[i] & 0x3F));
                jetid_add_bytes(&t, two, 2);
            }
        }
    }
    jetid_add(&t, "");
    i = 0;
    while (first && strncmp(t.s + i, "\xef\xbb\xbf", 3) == 0) i += 3;
    name = jetid_trim(t.s + i);
    free(t.s);
    return name;
}

/* Whether s[0..n] is `word` (lower case) in any case of ASCII letters. */
static int jetid_equal_nocase(const char *s, size_t n, const char *word)
{
    size_t k;
    if (strlen(word) != n) return 0;
    for (k = 0; k < n; k++)
        if (tolower((unsigned char)s[k]) != word[k]) return 0;
    return 1;
}

/* str::parse::<f64>'s grammar: [+-] then inf, infinity, nan (any case) or digits with an optional
 * point and exponent; no white space, no hex, no underscores. */
static int jetid_is_rust_f64(const char *s, size_t n)
{
    size_t i = 0, whole = 0, frac = 0, exp = 0;
    if (i < n && (s[i] == '+' || s[i] == '-')) i++;
    if (jetid_equal_nocase(s + i, n - i, "inf") || jetid_equal_nocase(s + i, n - i, "infinity") ||
        jetid_equal_nocase(s + i, n - i, "nan"))
        return 1;
    while (i < n && s[i] >= '0' && s[i] <= '9') i++, whole++;
    if (i < n && s[i] == '.') {
        i++;
        while (i < n && s[i] >= '0' && s[i] <= '9') i++, frac++;
    }
    if (whole + frac == 0) return 0;
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        if (i < n && (s[i] == '+' || s[i] == '-')) i++;
        while (i < n && s[i] >= '0' && s[i] <= '9') i++, exp++;
        if (!exp) return 0;
    }
    return i == n;
}

/* The f64 Rust reads from s[0..n], or 0 when it reads none (`comma`: with ',' read as '.'). */
static int jetid_parse_f64(const char *s, size_t n, int comma, double *value)
{
    char buf[64], *copy = n < sizeof buf ? buf : jetid_alloc(n + 1);
    size_t k;
    int ok;
    for (k = 0; k < n; k++) copy[k] = comma && s[k] == ',' ? '.' : s[k];
    copy[n] = '\0';
    ok = jetid_is_rust_f64(copy, n);
    if (ok) *value = strtod(copy, NULL);
    if (copy != buf) free(copy);
    return ok;
}

/* table.rs parse_cell: JETID_NUMBER (a finite number), JETID_MISSING (empty, NaN or infinite) or
 * JETID_NOT_NUMBER. */
static int jetid_parse_cell(const unsigned char *s, size_t n, double *value)
{
    int ok;
    if (n == 0) return JETID_MISSING;
    ok = jetid_parse_f64((const char *)s, n, 0, value);
    if (!ok && memchr(s, ',', n)) ok = jetid_parse_f64((const char *)s, n, 1, value);
    if (!ok) return JETID_NOT_NUMBER;
    return isfinite(*value) ? JETID_NUMBER : JETID_MISSING;
}

/* ---- The table (table.rs) ---- */

/* One record: its fields' bytes one after another, each field's [from, to) after trimming. */
typedef struct {
    unsigned char *bytes;
    size_t len, cap;
    size_t *from, *to;
    size_t n_fields, cap_fields;
    size_t start; /* where reading the record began (csv's Position::byte) */
} jetid_record;

static void jetid_record_push(jetid_record *r, unsigned char b)
{
    if (r->len == r->cap) {
        r->cap = r->cap ? 2 * r->cap : 256;
        r->bytes = jetid_grow(r->bytes, r->cap);
    }
    r->bytes[r->len++] = b;
}

/* The field from `from` to the end of the bytes, trimmed of ASCII white space as the csv reader
 * trims (" \t\n\f\r"). */
static void jetid_record_end_field(jetid_record *r, size_t from)
{
    size_t to = r->len;
    while (from < to && strchr(" \t\n\f\r", r->bytes[from]) && r->bytes[from]) from++;
    while (to > from && strchr(" \t\n\f\r", r->bytes[to - 1]) && r->bytes[to - 1]) to--;
    if (r->n_fields == r->cap_fields) {
        r->cap_fields = r->cap_fields ? 2 * r->cap_fields : 16;
        r->from = jetid_grow(r->from, r->cap_fields * sizeof *r->from);
        r->to = jetid_grow(r->to, r->cap_fields * sizeof *r->to);
    }
    r->from[r->n_fields] = from;
    r->to[r->n_fields++] = to;
}

/* table.rs csv_reader: the next record of d[0..n] from *pos as the csv crate reads it: a BOM where
 * reading starts (*pos 0) dropped, empty lines and lines starting with '#' skipped, a field opening
 * with '"' quoted up to the next lone '"' ("" is a quote; separators and line ends inside are text)
 * and going on unquoted after it, fields trimmed. A comment running to the end of the data (no line
 * feed after it) is a record of one empty field, as csv-core's DFA reads it. 0 at the end. */
static int jetid_read_record(const unsigned char *d, size_t n, size_t *pos, unsigned char sep, jetid_record *r)
{
    size_t i = *pos;
    r->start = i;
    r->len = r->n_fields = 0;
    if (i == 0 && n >= 3 && memcmp(d, "\xef\xbb\xbf", 3) == 0) i = 3;
    for (;;) {
        if (i >= n) return *pos = n, 0;
        if (d[i] == '\r' || d[i] == '\n') {
            i++;
        } else if (d[i] == '#') {
            const unsigned char *nl = memchr(d + i, '\n', n - i);
            if (!nl) {
                jetid_record_end_field(r, 0);
                return *pos = n, 1;
            }
            i = (size_t)(nl - d) + 1;
        } else {
            break;
        }
    }
    for (;;) {
        size_t from = r->len;
        if (i < n && d[i] == '"') {
            for (i++; i < n; i++) {
                if (d[i] != '"') {
                    jetid_record_push(r, d[i]);
                } else if (i + 1 < n && d[i + 1] == '"') {
                    jetid_record_push(r, '"');
                    i++;
                } else {
                    i++;
                    break;
                }
            }
        }
        while (i < n && d[i] != sep && d[i] != '\r' && d[i] != '\n') jetid_record_push(r, d[i++]);
        jetid_record_end_field(r, from);
        if (i >= n) return *pos = n, 1;
        if (d[i++] != sep) return *pos = i, 1;
    }
}

/* table.rs not_text: what a file that is not text is, from its first bytes; NULL for text. */
static const char *jetid_not_text(const unsigned char *d, size_t n)
{
    if (n >= 2 && d[0] == 0x1f && d[1] == 0x8b) return "gzip-compressed: decompress it first (gunzip)";
    if (n >= 4 && memcmp(d, "PK\x03\x04", 4) == 0)
        return "a zip archive (a spreadsheet's .xlsx, say): export the sheet as CSV";
    if (memchr(d, 0, n)) return "binary (it holds NUL bytes)";
    return NULL;
}

/* table.rs separator(first_data_line(..)): ';' or a tab when the first line that is not a '#'
 * comment has one and no comma, else a comma. */
static unsigned char jetid_separator(const unsigned char *d, size_t n)
{
    const unsigned char *nl;
    size_t i = 0, end;
    while (i < n && d[i] == '#') {
        nl = memchr(d + i, '\n', n - i);
        i = nl ? (size_t)(nl - d) + 1 : n;
    }
    nl = memchr(d + i, '\n', n - i);
    end = nl ? (size_t)(nl - d) : n;
    if (memchr(d + i, ',', end - i)) return ',';
    if (memchr(d + i, ';', end - i)) return ';';
    if (memchr(d + i, '\t', end - i)) return '\t';
    return ',';
}

/* table.rs Table: the header, every cell parsed (row by row: cells[row * n_cols + col] with its
 * kind) and each record's offset. */
typedef struct {
    const char *file;
    const unsigned char *data;
    size_t size;
    unsigned char sep;
    char **header;
    int n_cols;
    size_t n_rows, cap_rows;
    double *cells;
    unsigned char *kinds;
    size_t *starts;
} jetid_table;

/* Source::line_at: the 1-based line of the record read from byte `start` (a record's offset may
 * point at the end of the line before; up to four line-end bytes are stepped over). */
static unsigned long jetid_line_at(const jetid_table *t, size_t start)
{
    size_t end = t->size < start + 4 ? t->size : start + 4, k = start < end ? start : end, i;
    unsigned long line = 1;
    while (k < end && (t->data[k] == '\r' || t->data[k] == '\n')) k++;
    for (i = 0; i < k; i++) line += t->data[i] == '\n';
    return line;
}

static unsigned long jetid_line(const jetid_table *t, size_t row)
{
    return jetid_line_at(t, t->starts[row]);
}

/* Table::text: the cell's text as a message shows it, read again from the record's bytes. */
static void jetid_add_cell_text(jetid_text *m, const jetid_table *t, size_t row, int col)
{
    jetid_record r = {NULL, 0, 0, NULL, NULL, 0, 0, 0};
    size_t start = t->starts[row], pos = 0, n = t->size - start;
    if (n > JETID_RECORD_READ_BACK) n = JETID_RECORD_READ_BACK;
    if (jetid_read_record(t->data + start, n, &pos, t->sep, &r) && (size_t)col < r.n_fields)
        jetid_add_lossy(m, r.bytes + r.from[col], r.to[col] - r.from[col], 40);
    free(r.bytes);
    free(r.from);
    free(r.to);
}

/* "FILE: line L (data row R), column "C"" for a cell (row 0-based). */
static void jetid_add_where(jetid_text *m, const jetid_table *t, size_t row, const char *what, int col)
{
    char line[64];
    snprintf(line, sizeof line, ": line %lu (data row %lu), ", jetid_line(t, row), (unsigned long)row + 1);
    jetid_add(m, t->file);
    jetid_add(m, line);
    jetid_add(m, what);
    jetid_add(m, " \"");
    jetid_add(m, t->header[col]);
    jetid_add(m, "\"");
}

static void jetid_refuse_file(const char *file, const char *what)
{
    jetid_text m = {NULL, 0, 0};
    jetid_add(&m, file);
    jetid_add(&m, what);
    jetid_refuse(&m);
}

/* The file's bytes (load_run_with_notes: a folder or an unreadable file is refused). */
static unsigned char *jetid_read_bytes(const char *file, size_t *size)
{
    FILE *f = fopen(file, "rb");
    unsigned char *d;
    size_t cap = 1 << 16, got;
    char code[32];
    if (!f) {
        jetid_text m = {NULL, 0, 0};
        int err = errno;
        snprintf(code, sizeof code, " (os error %d)", err);
        jetid_add(&m, file);
        jetid_add(&m, ": cannot read the file: ");
        jetid_add(&m, strerror(err));
        jetid_add(&m, code);
        jetid_refuse(&m);
    }
    d = jetid_alloc(cap);
    *size = 0;
    errno = 0;
    while ((got = fread(d + *size, 1, cap - *size, f)) > 0) {
        *size += got;
        if (*size == cap) d = jetid_grow(d, cap *= 2);
    }
    if (ferror(f)) {
#ifdef EISDIR
        if (errno == EISDIR) jetid_refuse_file(file, ": is a folder, not a run file; give the CSV file in it");
#endif
        jetid_refuse_file(file, ": cannot read the file");
    }
    fclose(f);
    return d;
}

/* table.rs read_table. */
static void jetid_read_table(const char *file, jetid_table *t)
{
    jetid_record r = {NULL, 0, 0, NULL, NULL, 0, 0, 0};
    size_t pos = 0, head = 0, k;
    int c, c2, any = 0;
    const char *what;
    t->file = file;
    t->data = jetid_read_bytes(file, &t->size);
    head = t->size < JETID_RECORD_READ_BACK ? t->size : JETID_RECORD_READ_BACK;
    what = jetid_not_text(t->data, head);
    if (what) {
        jetid_text m = {NULL, 0, 0};
        jetid_add(&m, file);
        jetid_add(&m, ": not a text CSV file: it is ");
        jetid_add(&m, what);
        jetid_refuse(&m);
    }
    t->sep = jetid_separator(t->data, head);
    if (!jetid_read_record(t->data, t->size, &pos, t->sep, &r))
        jetid_refuse_file(file, ": empty file: no header row");
    t->n_cols = (int)r.n_fields;
    t->header = jetid_alloc(r.n_fields * sizeof *t->header);
    for (c = 0; c < t->n_cols; c++) {
        t->header[c] = jetid_header_name(r.bytes + r.from[c], r.to[c] - r.from[c], c == 0);
        any |= t->header[c][0] != '\0';
    }
    if (!any) jetid_refuse_file(file, ": empty file: no header row");
    for (c = 0; c < t->n_cols; c++)
        for (c2 = c + 1; t->header[c][0] && c2 < t->n_cols; c2++)
            if (strcmp(t->header[c], t->header[c2]) == 0) {
                jetid_text m = {NULL, 0, 0};
                char cols[64];
                jetid_add(&m, file);
                jetid_add(&m, ": line 1: column \"");
                jetid_add(&m, t->header[c]);
                snprintf(cols, sizeof cols, "\" appears twice (columns %d and %d)", c + 1, c2 + 1);
                jetid_add(&m, cols);
                jetid_refuse(&m);
            }
    t->n_rows = 0;
    t->cap_rows = 1024;
    t->cells = jetid_alloc(t->cap_rows * t->n_cols * sizeof *t->cells);
    t->kinds = jetid_alloc(t->cap_rows * t->n_cols);
    t->starts = jetid_alloc(t->cap_rows * sizeof *t->starts);
    while (jetid_read_record(t->data, t->size, &pos, t->sep, &r)) {
        if (r.n_fields != (size_t)t->n_cols) {
            jetid_text m = {NULL, 0, 0};
            char counts[160];
            snprintf(counts, sizeof counts, ": line %lu (data row %lu): %lu fields, the header has %d",
                     jetid_line_at(t, r.start), (unsigned long)t->n_rows + 1, (unsigned long)r.n_fields, t->n_cols);
            jetid_add(&m, file);
            jetid_add(&m, counts);
            jetid_refuse(&m);
        }
        if (t->n_rows == t->cap_rows) {
            t->cap_rows *= 2;
            t->cells = jetid_grow(t->cells, t->cap_rows * t->n_cols * sizeof *t->cells);
            t->kinds = jetid_grow(t->kinds, t->cap_rows * t->n_cols);
            t->starts = jetid_grow(t->starts, t->cap_rows * sizeof *t->starts);
        }
        for (c = 0; c < t->n_cols; c++) {
            k = t->n_rows * t->n_cols + c;
            t->cells[k] = 0.0;
            t->kinds[k] = (unsigned char)jetid_parse_cell(r.bytes + r.from[c], r.to[c] - r.from[c], &t->cells[k]);
        }
        t->starts[t->n_rows++] = r.start;
    }
    free(r.bytes);
    free(r.from);
    free(r.to);
}

/* Ctx::cell_error: the message for a cell that is not a finite number (row 0-based). */
static void jetid_refuse_cell(const jetid_table *t, size_t row, int col)
{
    jetid_text m = {NULL, 0, 0};
    int missing = t->kinds[row * t->n_cols + col] == JETID_MISSING;
    jetid_add_where(&m, t, row, "column", col);
    jetid_add(&m, missing ? ": missing value (cell \"" : ": \"");
    jetid_add_cell_text(&m, t, row, col);
    jetid_add(&m, missing ? "\" is empty, NaN or infinite)" : "\" is not a number");
    jetid_refuse(&m);
}

/* ---- Options (csv_run.rs LoadOptions, column_map.rs ColumnMap, window.rs Window) ---- */

#define JETID_WINDOW_NONE 0
#define JETID_WINDOW_SAMPLES 1
#define JETID_WINDOW_SECONDS 2
#define JETID_WINDOW_AUTO 3

/* `--window`: a half-open part of the run, in samples or seconds; an absent end is the file's. */
typedef struct {
    int kind, has_start, has_end;
    unsigned long long first, last; /* samples: START and END */
    double start, end;              /* seconds: START and END */
} jetid_window;

/* The sentinels of one channel (`--invalid CHANNEL=V1,V2`). */
typedef struct {
    char *channel;
    double *values;
    size_t n;
} jetid_invalid;

/* How a run file is read, as `jetid predict` takes it from its command line. */
typedef struct {
    char *time, *input;
    char **outputs, **aux;
    int n_outputs, n_aux;
    int has_sample_time;
    double sample_time_secs;
    jetid_window window;
    const char *quality;
    int resample;
    jetid_invalid *invalid; /* sorted by channel, as a BTreeMap */
    int n_invalid;
    int input_only;
} jetid_options;

static void jetid_refuse_text(const char *a, const char *b, const char *c, const char *d, const char *e)
{
    jetid_text m = {NULL, 0, 0};
    jetid_add(&m, a);
    jetid_add(&m, b);
    jetid_add(&m, c);
    jetid_add(&m, d ? d : "");
    jetid_add(&m, e ? e : "");
    jetid_refuse(&m);
}

/* MapSpec::from_str, then ColumnMap::add. */
static void jetid_add_map_spec(jetid_options *o, const char *spec)
{
    const char *eq = strchr(spec, '=');
    char *role, *column, *raw;
    int k;
    if (!eq) jetid_refuse_text("bad --map \"", spec, "\": expected ROLE=COLUMN with ROLE one of time, input, output, aux", 0, 0);
    raw = jetid_alloc((size_t)(eq - spec) + 1);
    memcpy(raw, spec, (size_t)(eq - spec));
    raw[eq - spec] = '\0';
    role = jetid_trim(raw);
    column = jetid_trim(eq + 1);
    free(raw);
    if (!role[0] || !column[0])
        jetid_refuse_text("bad --map \"", spec, "\": expected ROLE=COLUMN with ROLE one of time, input, output, aux", 0, 0);
    raw = jetid_alloc(strlen(role) + 1);
    for (k = 0; role[k]; k++) raw[k] = (char)((unsigned char)role[k] < 0x80 ? tolower((unsigned char)role[k]) : role[k]);
    raw[k] = '\0';
    if (strcmp(raw, "output") == 0 || strcmp(raw, "aux") == 0) {
        int out = strcmp(raw, "output") == 0, n = out ? o->n_outputs : o->n_aux;
        char ***list = out ? &o->outputs : &o->aux;
        for (k = 0; k < n; k++)
            if (strcmp((*list)[k], column) == 0) return;
        *list = jetid_grow(*list, (size_t)(n + 1) * sizeof **list);
        (*list)[n] = column;
        if (out) o->n_outputs++;
        else o->n_aux++;
    } else if (strcmp(raw, "time") == 0 || strcmp(raw, "input") == 0) {
        char **single = strcmp(raw, "time") == 0 ? &o->time : &o->input;
        if (*single && strcmp(*single, column) != 0) {
            jetid_text m = {NULL, 0, 0};
            jetid_add(&m, "bad --map: the ");
            jetid_add(&m, raw);
            jetid_add(&m, " column is given twice (\"");
            jetid_add(&m, *single);
            jetid_add(&m, "\" and \"");
            jetid_add(&m, column);
            jetid_add(&m, "\")");
            jetid_refuse(&m);
        }
        *single = column;
    } else {
        jetid_text m = {NULL, 0, 0};
        jetid_add(&m, "bad --map \"");
        jetid_add(&m, spec);
        jetid_add(&m, "\": unknown role \"");
        jetid_add(&m, role);
        jetid_add(&m, "\" (roles: time, input, output, aux)");
        jetid_refuse(&m);
    }
    free(raw);
}

/* ColumnMap::entries: the mapped columns in the order time, input, outputs, aux (at most
 * 2 + n_outputs + n_aux). */
static int jetid_map_entries(const jetid_options *o, const char **roles, const char **columns)
{
    int n = 0, k;
    if (o->time) roles[n] = "time", columns[n++] = o->time;
    if (o->input) roles[n] = "input", columns[n++] = o->input;
    for (k = 0; k < o->n_outputs; k++) roles[n] = "output", columns[n++] = o->outputs[k];
    for (k = 0; k < o->n_aux; k++) roles[n] = "aux", columns[n++] = o->aux[k];
    return n;
}

/* ColumnMap::check: no column plays two roles. */
static void jetid_check_map(const jetid_options *o)
{
    const char **roles = jetid_alloc((size_t)(2 + o->n_outputs + o->n_aux) * sizeof *roles);
    const char **columns = jetid_alloc((size_t)(2 + o->n_outputs + o->n_aux) * sizeof *columns);
    int n = jetid_map_entries(o, roles, columns), i, j;
    for (i = 0; i < n; i++)
        for (j = i + 1; j < n; j++)
            if (strcmp(columns[i], columns[j]) == 0) {
                jetid_text m = {NULL, 0, 0};
                jetid_add(&m, "bad --map: column \"");
                jetid_add(&m, columns[i]);
                jetid_add(&m, "\" is given two roles (");
                jetid_add(&m, roles[i]);
                jetid_add(&m, " and ");
                jetid_add(&m, roles[j]);
                jetid_add(&m, ")");
                jetid_refuse(&m);
            }
    free(roles);
    free(columns);
}

static void jetid_refuse_window(const char *spec, const char *reason, const char *quoted)
{
    jetid_text m = {NULL, 0, 0};
    jetid_add(&m, "bad --window \"");
    jetid_add(&m, spec);
    jetid_add(&m, "\": ");
    if (quoted) {
        jetid_add(&m, "\"");
        jetid_add(&m, quoted);
        jetid_add(&m, "\"");
    }
    jetid_add(&m, reason);
    jetid_add(&m, " (expected START:END in samples, e.g. 935:2603, in seconds, e.g. 12.5s:80s, or auto)");
    jetid_refuse(&m);
}

/* One end of a window (trimmed text `s`) into *samples or *seconds: 0 when empty. */
static int jetid_window_side(const char *spec, const char *s, int in_seconds, unsigned long long *samples,
                             double *seconds)
{
    size_t n = strlen(s), k;
    if (!n) return 0;
    if (in_seconds) {
        char *number = jetid_alloc(n), *trimmed;
        memcpy(number, s, n - 1);
        number[n - 1] = '\0';
        trimmed = jetid_trim(number);
        if (!jetid_parse_f64(trimmed, strlen(trimmed), 0, seconds) || !isfinite(*seconds))
            jetid_refuse_window(spec, " is not a time in seconds", s);
        free(number);
        free(trimmed);
        return 1;
    }
    k = s[0] == '+'; /* str::parse::<usize> takes a '+' */
    *samples = 0;
    if (k == n) jetid_refuse_window(spec, " is not a sample index (a whole number; add `s` for seconds)", s);
    for (; k < n; k++) {
        unsigned digit = (unsigned)(s[k] - '0');
        if (s[k] < '0' || s[k] > '9' || *samples > (ULLONG_MAX - digit) / 10)
            jetid_refuse_window(spec, " is not a sample index (a whole number; add `s` for seconds)", s);
        *samples = *samples * 10 + digit;
    }
    return 1;
}

/* Window::from_str. */
static jetid_window jetid_parse_window(const char *spec)
{
    jetid_window w = {JETID_WINDOW_NONE, 0, 0, 0, 0, 0.0, 0.0};
    char *trimmed = jetid_trim(spec), *start, *end, *raw;
    const char *colon = strchr(spec, ':');
    size_t ns, ne;
    int s_sec, e_sec;
    if (jetid_equal_nocase(trimmed, strlen(trimmed), "auto")) {
        w.kind = JETID_WINDOW_AUTO;
        return w;
    }
    if (!colon) jetid_refuse_window(spec, "no ':' between START and END", NULL);
    raw = jetid_alloc((size_t)(colon - spec) + 1);
    memcpy(raw, spec, (size_t)(colon - spec));
    raw[colon - spec] = '\0';
    start = jetid_trim(raw);
    end = jetid_trim(colon + 1);
    ns = strlen(start);
    ne = strlen(end);
    if (!ns && !ne) jetid_refuse_window(spec, "START and END are both empty", NULL);
    s_sec = ns && (start[ns - 1] == 's' || start[ns - 1] == 'S');
    e_sec = ne && (end[ne - 1] == 's' || end[ne - 1] == 'S');
    if (ns && ne && s_sec != e_sec) jetid_refuse_window(spec, "give both ends in samples or both in seconds", NULL);
    w.kind = (ns ? s_sec : e_sec) ? JETID_WINDOW_SECONDS : JETID_WINDOW_SAMPLES;
    w.has_start = jetid_window_side(spec, start, w.kind == JETID_WINDOW_SECONDS, &w.first, &w.start);
    w.has_end = jetid_window_side(spec, end, w.kind == JETID_WINDOW_SECONDS, &w.last, &w.end);
    if (w.has_start && w.has_end && (w.kind == JETID_WINDOW_SECONDS ? w.start >= w.end : w.first >= w.last))
        jetid_refuse_window(spec, "the window is empty (START must be before END)", NULL);
    free(raw);
    free(trimmed);
    free(start);
    free(end);
    return w;
}

/* Window's Display. */
static void jetid_add_window(jetid_text *m, const jetid_window *w)
{
    char buf[JETID_DISPLAY_LEN];
    int side;
    for (side = 0; side < 2; side++) {
        if (side) jetid_add(m, ":");
        if (!(side ? w->has_end : w->has_start)) continue;
        if (w->kind == JETID_WINDOW_SAMPLES) {
            snprintf(buf, sizeof buf, "%llu", side ? w->last : w->first);
            jetid_add(m, buf);
        } else {
            jetid_add(m, jetid_display(side ? w->end : w->start, buf));
            jetid_add(m, "s");
        }
    }
}

/* LoadOptions::with_invalid_specs, for one CHANNEL=V1,V2. */
static void jetid_add_invalid_spec(jetid_options *o, const char *spec)
{
    const char *eq = strchr(spec, '='), *v;
    char *raw, *channel;
    double *values = NULL;
    size_t n = 0;
    int k, bad = !eq;
    if (!bad) {
        for (v = eq + 1;; v = strchr(v, ',') + 1) {
            const char *stop = strchr(v, ',');
            size_t len = stop ? (size_t)(stop - v) : strlen(v);
            char *item = jetid_alloc(len + 1), *trimmed;
            memcpy(item, v, len);
            item[len] = '\0';
            trimmed = jetid_trim(item);
            values = jetid_grow(values, (n + 1) * sizeof *values);
            if (!jetid_parse_f64(trimmed, strlen(trimmed), 0, &values[n]) || !isfinite(values[n])) bad = 1;
            n++;
            free(item);
            free(trimmed);
            if (!stop) break;
        }
    }
    raw = jetid_alloc(eq ? (size_t)(eq - spec) + 1 : 1);
    memcpy(raw, spec, eq ? (size_t)(eq - spec) : 0);
    raw[eq ? eq - spec : 0] = '\0';
    channel = jetid_trim(raw);
    free(raw);
    if (bad || !channel[0])
        jetid_refuse_text("--invalid: bad --invalid \"", spec,
                          "\": expected CHANNEL=VALUE[,VALUE...], e.g. T_inlet_C=-3276.8,3276.8", 0, 0);
    for (k = 0; k < o->n_invalid && strcmp(o->invalid[k].channel, channel) < 0; k++) {
    }
    if (k == o->n_invalid || strcmp(o->invalid[k].channel, channel) != 0) {
        o->invalid = jetid_grow(o->invalid, (size_t)(o->n_invalid + 1) * sizeof *o->invalid);
        memmove(o->invalid + k + 1, o->invalid + k, (size_t)(o->n_invalid - k) * sizeof *o->invalid);
        o->invalid[k].channel = channel;
        o->invalid[k].values = NULL;
        o->invalid[k].n = 0;
        o->n_invalid++;
    }
    o->invalid[k].values = jetid_grow(o->invalid[k].values, (o->invalid[k].n + n) * sizeof(double));
    memcpy(o->invalid[k].values + o->invalid[k].n, values, n * sizeof(double));
    o->invalid[k].n += n;
    free(values);
}

/* ---- Columns to roles (column_map.rs) ---- */

/* column_map.rs Layout: the column of every role (-1: none). */
typedef struct {
    int time;          /* the time column, or -1: the time is k * sample_time_secs */
    int input;
    int *outputs, n_outputs;
    int *aux, n_aux;   /* mapped auxiliary columns: every cell must be numeric */
    int *extras, n_extras; /* the other named columns: kept if numeric throughout */
    int quality;
    int ignored;       /* a time_s column overridden by the sample time */
} jetid_layout;

static int jetid_find(const jetid_table *t, const char *name)
{
    int c;
    for (c = 0; c < t->n_cols; c++)
        if (strcmp(t->header[c], name) == 0) return c;
    return -1;
}

/* "columns present: A, B" (the named columns). */
static void jetid_add_present(jetid_text *m, const jetid_table *t)
{
    int c, first = 1;
    jetid_add(m, "columns present: ");
    for (c = 0; c < t->n_cols; c++)
        if (t->header[c][0]) {
            if (!first) jetid_add(m, ", ");
            jetid_add(m, t->header[c]);
            first = 0;
        }
}

/* Header::mapped: the column the map gives `role`. */
static int jetid_mapped(const jetid_table *t, const char *role, const char *name)
{
    int c = jetid_find(t, name);
    if (c < 0) {
        jetid_text m = {NULL, 0, 0};
        jetid_add(&m, t->file);
        jetid_add(&m, ": bad --map ");
        jetid_add(&m, role);
        jetid_add(&m, "=");
        jetid_add(&m, name);
        jetid_add(&m, ": no column \"");
        jetid_add(&m, name);
        jetid_add(&m, "\"; ");
        jetid_add_present(&m, t);
        jetid_refuse(&m);
    }
    return c;
}

/* Header::required: a column `role` needs under its default (or given) name. */
static int jetid_required(const jetid_table *t, const char *role, const char *name)
{
    int c = jetid_find(t, name);
    if (c < 0) {
        jetid_text m = {NULL, 0, 0};
        jetid_add(&m, t->file);
        jetid_add(&m, ": no ");
        jetid_add(&m, role);
        jetid_add(&m, " column \"");
        jetid_add(&m, name);
        jetid_add(&m, "\"; ");
        jetid_add_present(&m, t);
        if (strcmp(role, "time") == 0) jetid_add(&m, "; give --sample-time SECONDS or --map time=COLUMN");
        if (strcmp(role, "input") == 0) jetid_add(&m, "; map one with --map input=COLUMN");
        jetid_refuse(&m);
    }
    return c;
}

/* column_map.rs time_base. */
static void jetid_time_base(const jetid_table *t, const jetid_options *o, jetid_layout *l)
{
    char buf[JETID_DISPLAY_LEN];
    l->time = l->ignored = -1;
    if (o->time && o->has_sample_time) {
        jetid_text m = {NULL, 0, 0};
        jetid_add(&m, t->file);
        jetid_add(&m, ": time is given twice: by column \"");
        jetid_add(&m, o->time);
        jetid_add(&m, "\" and by a sample time of ");
        jetid_add(&m, jetid_display(o->sample_time_secs, buf));
        jetid_add(&m, " s; give one");
        jetid_refuse(&m);
    } else if (o->time) {
        l->time = jetid_mapped(t, "time", o->time);
    } else if (o->has_sample_time) {
        int k, mapped_elsewhere = o->input && strcmp(o->input, JETID_TIME_COLUMN) == 0;
        for (k = 0; k < o->n_outputs; k++) mapped_elsewhere |= strcmp(o->outputs[k], JETID_TIME_COLUMN) == 0;
        for (k = 0; k < o->n_aux; k++) mapped_elsewhere |= strcmp(o->aux[k], JETID_TIME_COLUMN) == 0;
        if (!mapped_elsewhere) l->ignored = jetid_find(t, JETID_TIME_COLUMN);
    } else {
        l->time = jetid_required(t, "time", JETID_TIME_COLUMN);
    }
}

/* column_map.rs output_columns. */
static void jetid_output_columns(const jetid_table *t, const jetid_options *o, jetid_layout *l)
{
    int k;
    l->outputs = jetid_alloc((size_t)(o->n_outputs + 2) * sizeof *l->outputs);
    l->n_outputs = 0;
    if (o->input_only) return;
    if (o->n_outputs) {
        for (k = 0; k < o->n_outputs; k++) l->outputs[l->n_outputs++] = jetid_mapped(t, "output", o->outputs[k]);
        return;
    }
    for (k = 0; k < 2; k++)
        if (jetid_find(t, jetid_canonical_outputs[k]) >= 0)
            l->outputs[l->n_outputs++] = jetid_find(t, jetid_canonical_outputs[k]);
    if (!l->n_outputs) {
        jetid_text m = {NULL, 0, 0};
        jetid_add(&m, t->file);
        jetid_add(&m, ": no output column (shaft_speed_rpm or thrust_n); ");
        jetid_add_present(&m, t);
        jetid_add(&m, "; map one with --map output=COLUMN");
        jetid_refuse(&m);
    }
}

/* column_map.rs quality_column. */
static int jetid_quality_column(const jetid_table *t, const jetid_options *o)
{
    const char **roles, **columns;
    int n, k;
    if (!o->quality) return -1;
    roles = jetid_alloc((size_t)(2 + o->n_outputs + o->n_aux) * sizeof *roles);
    columns = jetid_alloc((size_t)(2 + o->n_outputs + o->n_aux) * sizeof *columns);
    n = jetid_map_entries(o, roles, columns);
    for (k = 0; k < n; k++)
        if (strcmp(columns[k], o->quality) == 0) {
            jetid_text m = {NULL, 0, 0};
            jetid_add(&m, t->file);
            jetid_add(&m, ": bad --map: column \"");
            jetid_add(&m, o->quality);
            jetid_add(&m, "\" is given two roles (");
            jetid_add(&m, roles[k]);
            jetid_add(&m, " and quality)");
            jetid_refuse(&m);
        }
    free(roles);
    free(columns);
    return jetid_required(t, "quality", o->quality);
}

/* column_map.rs resolve_layout. */
static void jetid_resolve_layout(const jetid_table *t, const jetid_options *o, jetid_layout *l)
{
    int k, c;
    jetid_time_base(t, o, l);
    l->input = o->input ? jetid_mapped(t, "input", o->input) : jetid_required(t, "input", JETID_INPUT_COLUMN);
    jetid_output_columns(t, o, l);
    l->aux = jetid_alloc((size_t)(o->n_aux + 1) * sizeof *l->aux);
    for (l->n_aux = 0; l->n_aux < o->n_aux; l->n_aux++) l->aux[l->n_aux] = jetid_mapped(t, "aux", o->aux[l->n_aux]);
    l->quality = jetid_quality_column(t, o);
    l->extras = jetid_alloc((size_t)t->n_cols * sizeof *l->extras);
    l->n_extras = 0;
    for (c = 0; !o->n_aux && c < t->n_cols; c++) {
        int used = c == l->input || c == l->quality || c == l->ignored || c == l->time || !t->header[c][0];
        for (k = 0; k < l->n_outputs; k++) used |= c == l->outputs[k];
        if (!used) l->extras[l->n_extras++] = c;
    }
}

/* ---- Rows, repair and the time axis (read.rs, window.rs, repair.rs) ---- */

static void jetid_refuse_too_few(const char *file, size_t found)
{
    char counts[96];
    snprintf(counts, sizeof counts, ": %lu samples, at least %d are needed", (unsigned long)found, JETID_MIN_SAMPLES);
    jetid_refuse_file(file, counts);
}

/* Ctx::quality: which rows the quality column marks good (all of them without one). */
static unsigned char *jetid_quality(const jetid_table *t, const jetid_layout *l)
{
    unsigned char *good = jetid_alloc(t->n_rows);
    size_t row;
    for (row = 0; row < t->n_rows; row++) {
        size_t k = row * t->n_cols + l->quality;
        if (l->quality < 0) {
            good[row] = 1;
        } else if (t->kinds[k] == JETID_NUMBER && fabs(t->cells[k] - 1.0) < 1e-9) {
            good[row] = 1;
        } else if (t->kinds[k] == JETID_NUMBER && fabs(t->cells[k]) < 1e-9) {
            good[row] = 0;
        } else {
            jetid_text m = {NULL, 0, 0};
            jetid_add_where(&m, t, row, "quality column", l->quality);
            jetid_add(&m, ": \"");
            jetid_add_cell_text(&m, t, row, l->quality);
            jetid_add(&m, "\" is not 0 or 1");
            jetid_refuse(&m);
        }
    }
    return good;
}

/* Ctx::time_of_row: a row's time for a window in seconds; NaN when unreadable. */
static double jetid_time_of_row(const jetid_table *t, const jetid_layout *l, const jetid_options *o, size_t row)
{
    size_t k = row * t->n_cols + l->time;
    if (l->time < 0) return (double)row * o->sample_time_secs;
    return t->kinds[k] == JETID_NUMBER ? t->cells[k] : NAN;
}

static void jetid_refuse_window_rows(const jetid_table *t, const jetid_options *o, const char *reason)
{
    jetid_text m = {NULL, 0, 0};
    jetid_add(&m, t->file);
    jetid_add(&m, ": bad --window ");
    jetid_add_window(&m, &o->window);
    jetid_add(&m, ": ");
    jetid_add(&m, reason);
    jetid_refuse(&m);
}

/* Window::select: the rows [*a, *b) the window keeps. */
static void jetid_window_rows(const jetid_table *t, const jetid_layout *l, const jetid_options *o, size_t *a,
                              size_t *b)
{
    const jetid_window *w = &o->window;
    size_t n = t->n_rows, row;
    char reason[2 * JETID_DISPLAY_LEN + 120], lo_text[JETID_DISPLAY_LEN], hi_text[JETID_DISPLAY_LEN];
    double lo = INFINITY, hi = -INFINITY;
    int found = 0;
    if (w->kind == JETID_WINDOW_SAMPLES) {
        unsigned long long first = w->has_start ? w->first : 0, last = w->has_end ? w->last : n;
        if (last > n || first >= n) {
            snprintf(reason, sizeof reason, "out of range: the file has %lu samples (0..%lu)", (unsigned long)n,
                     (unsigned long)n);
            jetid_refuse_window_rows(t, o, reason);
        }
        if (first >= last) jetid_refuse_window_rows(t, o, "the window is empty");
        *a = (size_t)first;
        *b = (size_t)last;
        return;
    }
    for (row = 0; row < n; row++) {
        double time = jetid_time_of_row(t, l, o, row);
        if (!isfinite(time)) continue;
        if (time < lo) lo = time;
        if (time > hi) hi = time;
        if ((!w->has_start || time >= w->start) && (!w->has_end || time < w->end)) {
            if (!found) *a = row;
            *b = row + 1;
            found = 1;
        }
    }
    if (!found) {
        snprintf(reason, sizeof reason, "out of range: no sample has a time in it (the file spans %s s to %s s)",
                 jetid_display(lo, lo_text), jetid_display(hi, hi_text));
        jetid_refuse_window_rows(t, o, reason);
    }
}

/* read.rs select_rows: the rows kept, [*first, *end), once bad samples at either end of the window
 * are trimmed. */
static void jetid_select_rows(const jetid_table *t, const jetid_layout *l, const jetid_options *o,
                              const unsigned char *good, size_t *first, size_t *end)
{
    size_t a = 0, b = t->n_rows, row, bad = 0;
    if (t->n_rows < JETID_MIN_SAMPLES) jetid_refuse_too_few(t->file, t->n_rows);
    if (o->window.kind != JETID_WINDOW_NONE) jetid_window_rows(t, l, o, &a, &b);
    for (row = a; row < b; row++) bad += !good[row];
    if (l->quality >= 0 && (double)bad > JETID_MAX_BAD_FRACTION * (double)(b - a)) {
        jetid_text m = {NULL, 0, 0};
        char counts[160], pct[JETID_DISPLAY_LEN];
        jetid_add(&m, t->file);
        jetid_add(&m, ": quality column \"");
        jetid_add(&m, t->header[l->quality]);
        snprintf(counts, sizeof counts, "\": %lu of %lu samples are flagged bad (more than ", (unsigned long)bad,
                 (unsigned long)(b - a));
        jetid_add(&m, counts);
        jetid_add(&m, jetid_display(100.0 * JETID_MAX_BAD_FRACTION, pct));
        jetid_add(&m, " %)");
        jetid_refuse(&m);
    }
    for (*first = a; *first < b && !good[*first]; (*first)++) {
    }
    if (*first == b) *first = a;
    for (*end = b; *end > a && !good[*end - 1]; (*end)--) {
    }
    if (*end <= a || *end < *first) *end = *first;
    if (*end - *first < JETID_MIN_SAMPLES) jetid_refuse_too_few(t->file, *end - *first);
}

/* repair.rs fill_gaps: NaN by linear interpolation between the nearest finite neighbours; at either
 * end the nearest finite value. */
static void jetid_fill_gaps(double *v, size_t n)
{
    size_t i = 0, k, next;
    long prev = -1;
    while (i < n) {
        if (isfinite(v[i])) {
            prev = (long)i++;
            continue;
        }
        for (next = i; next < n && !isfinite(v[next]); next++) {
        }
        if (prev < 0 && next == n) return;
        for (k = i; k < next; k++) {
            if (prev >= 0 && next < n)
                v[k] = v[prev] + (v[next] - v[prev]) * (double)(k - (size_t)prev) / (double)(next - (size_t)prev);
            else
                v[k] = prev >= 0 ? v[prev] : v[next];
        }
        i = next;
    }
}

/* Ctx::column: column `col` over the kept rows, NaN in bad rows. A bad cell in a good row is
 * refused when `strict`; otherwise the column is left out (NULL). */
static double *jetid_column(const jetid_table *t, int col, size_t first, size_t end, const unsigned char *good,
                            int strict)
{
    double *v = jetid_alloc((end - first) * sizeof *v);
    size_t row;
    for (row = first; row < end; row++) {
        size_t k = row * t->n_cols + col;
        if (!good[row]) {
            v[row - first] = NAN;
        } else if (t->kinds[k] == JETID_NUMBER) {
            v[row - first] = t->cells[k];
        } else if (strict) {
            jetid_refuse_cell(t, row, col);
        } else {
            free(v);
            return NULL;
        }
    }
    return v;
}

/* Ctx::repaired_column: a strict column with its bad samples interpolated. */
static double *jetid_repaired_column(const jetid_table *t, int col, size_t first, size_t end,
                                     const unsigned char *good)
{
    double *v = jetid_column(t, col, first, end, good, 1);
    jetid_fill_gaps(v, end - first);
    return v;
}

/* A run as read: its time axis, sample time and channels (the input, the outputs, the auxiliary
 * channels). */
typedef struct {
    char *name; /* the file stem */
    double dt;
    size_t n;
    double *t;
    int n_channels, n_outputs;
    char **names;
    double **values;
} jetid_run;

static void jetid_add_channel(jetid_run *run, char *name, double *values)
{
    run->names = jetid_grow(run->names, (size_t)(run->n_channels + 1) * sizeof *run->names);
    run->values = jetid_grow(run->values, (size_t)(run->n_channels + 1) * sizeof *run->values);
    run->names[run->n_channels] = name;
    run->values[run->n_channels++] = values;
}

/* read.rs read_channels: the input, the outputs and the auxiliary channels (mapped, or the other
 * columns that are numeric throughout) over the kept rows. */
static void jetid_read_channels(const jetid_table *t, const jetid_layout *l, size_t first, size_t end,
                                const unsigned char *good, jetid_run *run)
{
    int k;
    jetid_add_channel(run, t->header[l->input], jetid_repaired_column(t, l->input, first, end, good));
    for (k = 0; k < l->n_outputs; k++)
        jetid_add_channel(run, t->header[l->outputs[k]], jetid_repaired_column(t, l->outputs[k], first, end, good));
    for (k = 0; k < l->n_aux; k++)
        jetid_add_channel(run, t->header[l->aux[k]], jetid_repaired_column(t, l->aux[k], first, end, good));
    for (k = 0; k < l->n_extras; k++) {
        double *v = jetid_column(t, l->extras[k], first, end, good, 0);
        if (!v) continue;
        jetid_fill_gaps(v, end - first);
        jetid_add_channel(run, t->header[l->extras[k]], v);
    }
    run->n_outputs = l->n_outputs;
}

/* read.rs mark_invalid: every sentinel becomes a gap, interpolated. */
static void jetid_mark_invalid(const char *file, jetid_run *run, const jetid_options *o)
{
    int i, c, k;
    size_t j, count;
    char buf[JETID_DISPLAY_LEN];
    for (i = 0; i < o->n_invalid; i++) {
        const jetid_invalid *inv = &o->invalid[i];
        double *v;
        for (c = 0; c < run->n_channels && strcmp(run->names[c], inv->channel) != 0; c++) {
        }
        if (c == run->n_channels) {
            jetid_text m = {NULL, 0, 0};
            jetid_add(&m, file);
            jetid_add(&m, ": invalid values are given for channel \"");
            jetid_add(&m, inv->channel);
            jetid_add(&m, "\", which the run does not have (channels: ");
            for (k = 0; k < run->n_channels; k++) {
                if (k) jetid_add(&m, ", ");
                jetid_add(&m, run->names[k]);
            }
            jetid_add(&m, ")");
            jetid_refuse(&m);
        }
        v = run->values[c];
        for (j = 0, count = 0; j < run->n; j++) {
            for (k = 0; k < (int)inv->n; k++)
                if (fabs(v[j] - inv->values[k]) <= 1e-9 * (fabs(inv->values[k]) > 1.0 ? fabs(inv->values[k]) : 1.0)) {
                    v[j] = NAN;
                    count++;
                    break;
                }
        }
        if (count == run->n && count > 0) {
            jetid_text m = {NULL, 0, 0};
            jetid_add(&m, file);
            jetid_add(&m, ": channel \"");
            jetid_add(&m, inv->channel);
            jetid_add(&m, "\" holds only its invalid-value sentinels (");
            for (k = 0; k < (int)inv->n; k++) {
                if (k) jetid_add(&m, ", ");
                jetid_add(&m, jetid_display(inv->values[k], buf));
            }
            jetid_add(&m, "): it has no reading to use");
            jetid_refuse(&m);
        }
        jetid_fill_gaps(v, run->n);
    }
}

static int jetid_compare(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* repair.rs mark_outliers: a sample 100 ranges from its neighbours' median and 100 times the
 * channel's size cannot be a measurement: interpolated. */
static void jetid_mark_outliers(double *v, size_t n)
{
    double *sorted = jetid_alloc(n * sizeof *sorted), p1, p50, p99, range, limit, size_limit, near[6];
    unsigned char *outlier = jetid_alloc(n);
    size_t m = 0, k, j, found = 0;
    for (k = 0; k < n; k++)
        if (isfinite(v[k])) sorted[m++] = v[k];
    if (m < 7) {
        free(sorted);
        free(outlier);
        return;
    }
    qsort(sorted, m, sizeof *sorted, jetid_compare);
    p1 = sorted[(size_t)round((double)(m - 1) * 0.01)];
    p50 = sorted[(size_t)round((double)(m - 1) * 0.5)];
    p99 = sorted[(size_t)round((double)(m - 1) * 0.99)];
    range = p99 - p1;
    if (range < 1e-9 * fabs(p50)) range = 1e-9 * fabs(p50);
    if (range < DBL_MIN) range = DBL_MIN;
    limit = 100.0 * range;
    size_limit = fabs(p1) > fabs(p99) ? fabs(p1) : fabs(p99);
    size_limit = 100.0 * (size_limit > DBL_MIN ? size_limit : DBL_MIN);
    for (k = 0; k < n; k++) {
        size_t count = 0;
        outlier[k] = 0;
        if (!isfinite(v[k])) continue;
        for (j = k >= 3 ? k - 3 : 0; j < n && j <= k + 3; j++)
            if (j != k && isfinite(v[j])) near[count++] = v[j];
        if (!count) continue;
        qsort(near, count, sizeof *near, jetid_compare);
        if (fabs(v[k] - near[count / 2]) > limit && fabs(v[k]) > size_limit) outlier[k] = 1, found++;
    }
    for (k = 0; k < n; k++)
        if (outlier[k]) v[k] = NAN;
    if (found) jetid_fill_gaps(v, n);
    free(sorted);
    free(outlier);
}

/* repair.rs median_step: the median step, to 12 significant digits. */
static double jetid_median_step(const double *t, size_t n)
{
    double *steps, median;
    char text[64];
    size_t k;
    if (n < 2) return 0.0;
    steps = jetid_alloc((n - 1) * sizeof *steps);
    for (k = 0; k + 1 < n; k++) steps[k] = t[k + 1] - t[k];
    qsort(steps, n - 1, sizeof *steps, jetid_compare);
    median = (n - 1) % 2 == 0 ? 0.5 * (steps[(n - 1) / 2 - 1] + steps[(n - 1) / 2]) : steps[(n - 1) / 2];
    free(steps);
    snprintf(text, sizeof text, "%.11e", median);
    return strtod(text, NULL);
}

/* repair.rs merge_repeated_times: rows repeating a time stamp merged into their mean. */
static void jetid_merge_repeated_times(jetid_run *run)
{
    size_t k, a, groups = 0, j;
    int c;
    for (k = 1; k < run->n; k++)
        if (run->t[k] < run->t[k - 1] || !isfinite(run->t[k])) return;
    for (a = 0; a < run->n; a = k) {
        for (k = a + 1; k < run->n && run->t[k] == run->t[a]; k++) {
        }
        for (c = 0; c < run->n_channels; c++) {
            double sum = 0.0;
            for (j = a; j < k; j++) sum += run->values[c][j];
            run->values[c][groups] = sum / (double)(k - a);
        }
        run->t[groups++] = run->t[a];
    }
    run->n = groups;
}

/* repair.rs resample: every channel onto t[0] + k dt by linear interpolation. */
static void jetid_resample(jetid_run *run, double dt)
{
    size_t count, k, j = 0, *at;
    double *w, *grid, t0 = run->t[0];
    int c;
    if (!(dt > 0.0 && isfinite(dt))) return;
    count = (size_t)floor((run->t[run->n - 1] - t0) / dt + 1e-9) + 1;
    grid = jetid_alloc(count * sizeof *grid);
    w = jetid_alloc(count * sizeof *w);
    at = jetid_alloc(count * sizeof *at);
    for (k = 0; k < count; k++) {
        grid[k] = t0 + (double)k * dt;
        while (j + 2 < run->n && run->t[j + 1] <= grid[k]) j++;
        at[k] = j;
        w[k] = 0.0;
        if (j + 1 < run->n && run->t[j + 1] > run->t[j]) {
            w[k] = (grid[k] - run->t[j]) / (run->t[j + 1] - run->t[j]);
            w[k] = w[k] < 0.0 ? 0.0 : w[k] > 1.0 ? 1.0 : w[k];
        }
    }
    for (c = 0; c < run->n_channels; c++) {
        double *v = run->values[c], *out = jetid_alloc(count * sizeof *out);
        for (k = 0; k < count; k++) {
            double x = v[at[k]], y = at[k] + 1 < run->n ? v[at[k] + 1] : x;
            out[k] = x + (y - x) * w[k];
        }
        free(v);
        run->values[c] = out;
    }
    free(run->t);
    free(w);
    free(at);
    run->t = grid;
    run->n = count;
}

/* read.rs uniform_time with repair.rs check_time: the sample time once the time strictly increases
 * and every step is within 1 % of the median step; with --resample, repeated stamps merged and an
 * irregular axis resampled instead of refused (`first_row`: the data row of t[0], 0-based). */
static void jetid_uniform_time(const jetid_table *t, const jetid_layout *l, const jetid_options *o,
                               size_t first_row, jetid_run *run)
{
    size_t k, row;
    double dt, limit;
    char a[JETID_DISPLAY_LEN], b[JETID_DISPLAY_LEN], pct[JETID_DISPLAY_LEN];
    jetid_text m = {NULL, 0, 0};
    if (l->time < 0) {
        run->dt = o->sample_time_secs;
        return;
    }
    if (o->resample) jetid_merge_repeated_times(run);
    for (k = 1; k < run->n; k++)
        if (run->t[k] <= run->t[k - 1] || !isfinite(run->t[k])) {
            row = first_row + k;
            jetid_add_where(&m, t, row, "column", l->time);
            jetid_add(&m, ": time ");
            jetid_add(&m, jetid_display(run->t[k], a));
            jetid_add(&m, " s does not increase (previous sample ");
            jetid_add(&m, jetid_display(run->t[k - 1], b));
            jetid_add(&m, " s); a log with repeated or irregular time stamps is read with resample = true in the "
                          "project's [load] or --resample");
            jetid_refuse(&m);
        }
    dt = jetid_median_step(run->t, run->n);
    limit = JETID_TIME_TOLERANCE * dt * (1.0 + 1e-9);
    for (k = 1; k < run->n; k++)
        if (fabs((run->t[k] - run->t[k - 1]) - dt) > limit) {
            if (o->resample) {
                jetid_resample(run, dt);
                break;
            }
            row = first_row + k;
            jetid_add_where(&m, t, row, "column", l->time);
            jetid_add(&m, ": time step ");
            jetid_add(&m, jetid_display(run->t[k] - run->t[k - 1], a));
            jetid_add(&m, " s differs from the sample time ");
            jetid_add(&m, jetid_display(dt, b));
            jetid_add(&m, " s by more than ");
            jetid_add(&m, jetid_display(100.0 * JETID_TIME_TOLERANCE, pct));
            jetid_add(&m, " %; use --resample to resample onto a uniform grid");
            jetid_refuse(&m);
        }
    run->dt = dt;
}

/* The file's stem, as Path::file_stem gives it: the name without its last extension. */
static char *jetid_stem(const char *file)
{
    const char *slash = strrchr(file, '/'), *name = slash ? slash + 1 : file, *dot = strrchr(name, '.');
    size_t n = dot && dot != name ? (size_t)(dot - name) : strlen(name);
    char *stem = jetid_alloc(n + 1);
    memcpy(stem, name, n);
    stem[n] = '\0';
    return stem;
}

/* csv_run.rs load_run and read.rs parse: the run, or jetid's refusal. */
static void jetid_load_run(const char *file, const jetid_options *o, jetid_run *run)
{
    jetid_table t;
    jetid_layout l;
    unsigned char *good;
    size_t first, end, row;
    int c;
    jetid_read_table(file, &t);
    jetid_resolve_layout(&t, o, &l);
    good = jetid_quality(&t, &l);
    jetid_select_rows(&t, &l, o, good, &first, &end);
    memset(run, 0, sizeof *run);
    run->name = jetid_stem(file);
    run->n = end - first;
    if (l.time >= 0) {
        run->t = jetid_repaired_column(&t, l.time, first, end, good);
    } else {
        run->t = jetid_alloc(run->n * sizeof *run->t);
        for (row = first; row < end; row++) run->t[row - first] = (double)row * o->sample_time_secs;
    }
    jetid_read_channels(&t, &l, first, end, good, run);
    jetid_mark_invalid(file, run, o);
    for (c = 0; c < run->n_channels; c++) jetid_mark_outliers(run->values[c], run->n);
    jetid_uniform_time(&t, &l, o, first, run);
    if (run->n < JETID_MIN_SAMPLES) jetid_refuse_too_few(file, run->n);
    free(good);
}
#endif
