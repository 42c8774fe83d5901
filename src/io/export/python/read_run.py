

# ---- Reading a run file as `jetid predict` reads it (src/io/csv_run): the same steps in the same
# order, the same checks and the same messages, so that this program accepts and refuses the same
# files. Each function names the Rust function it follows. ----

TIME_COLUMN = "time_s"
INPUT_COLUMN = "fuel_flow_gph"
OUTPUT_COLUMNS = ("shaft_speed_rpm", "thrust_n")
MIN_SAMPLES = 10
MAX_BAD_FRACTION = 0.5
TIME_TOLERANCE = 0.01
_RECORD_READ_BACK = 1 << 16
_BOM = b"\xef\xbb\xbf"
# What Rust's str::trim removes (char::is_whitespace); the csv reader trims ASCII " \t\n\x0c\r".
_WHITESPACE = "\t\n\x0b\x0c\r \x85\xa0\u1680\u2000\u2001\u2002\u2003\u2004\u2005\u2006\u2007\u2008\u2009\u200a\u2028\u2029\u202f\u205f\u3000"
_CSV_WHITESPACE = b" \t\n\x0c\r"
_MISSING = "missing"
_NOT_NUMBER = "not a number"
# Rust's f64::from_str: no white space, no hex, no underscores; inf, infinity and nan in any case.
_RUST_F64 = re.compile(r"[+-]?(?:inf|infinity|nan|(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:e[+-]?[0-9]+)?)\Z", re.I | re.A)
_RUST_USIZE = re.compile(r"\+?[0-9]+\Z")


class RunFileError(ValueError):
    """A run file jetid refuses, with jetid's message (src/io/csv_run/error.rs)."""


def _trim(text):
    """str::trim."""
    return text.strip(_WHITESPACE)


def _parse_f64(text):
    """str::parse::<f64>: the number, or None when Rust would not read it."""
    return float(text) if _RUST_F64.match(text) else None


def _display(x):
    """An f64 as Rust's `{}` writes it: the shortest digits that read back, never an exponent."""
    if math.isnan(x):
        return "NaN"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    sign = "-" if math.copysign(1.0, x) < 0 else ""
    mantissa, _, exponent = repr(abs(x)).partition("e")
    whole, _, frac = mantissa.partition(".")
    digits, exp = (whole + frac).lstrip("0"), int(exponent or 0) - len(frac)
    if not digits:
        return sign + "0"
    stripped = digits.rstrip("0")
    exp += len(digits) - len(stripped)
    digits = stripped
    if exp >= 0:
        return sign + digits + "0" * exp
    point = len(digits) + exp
    if point > 0:
        return sign + digits[:point] + "." + digits[point:]
    return sign + "0." + "0" * (-point) + digits


def _significant(x, digits):
    """core::numerics::stats::significant."""
    if x == 0.0 or not math.isfinite(x):
        return _display(x)
    magnitude = math.floor(math.log10(abs(x)))
    if -3 <= magnitude < 5:
        return "%.*f" % (int(max(digits - 1 - magnitude, 0)), x)
    mantissa, exponent = ("%.*e" % (digits - 1, x)).split("e")
    return f"{mantissa}e{int(exponent)}"


# -- Options (csv_run.rs LoadOptions, column_map.rs ColumnMap, window.rs Window) --


class LoadOptions:
    """How a run file is read: csv_run.rs LoadOptions, from the command line as `jetid predict`
    takes it (cli/read_args.rs)."""

    def __init__(self):
        self.time, self.input, self.outputs, self.aux = None, None, [], []
        self.sample_time_secs = None
        self.window = None
        self.quality = None
        self.resample = False
        self.invalid = {}
        self.input_only = False

    def entries(self):
        """ColumnMap::entries: every mapped column with its role, time, input, outputs, aux."""
        out = [("time", self.time)] if self.time is not None else []
        out += [("input", self.input)] if self.input is not None else []
        return out + [("output", c) for c in self.outputs] + [("aux", c) for c in self.aux]


def add_map_spec(opts, spec):
    """MapSpec::from_str, then ColumnMap::add."""
    role, eq, column = spec.partition("=")
    role, column = _trim(role), _trim(column)
    if not eq or not role or not column:
        raise ValueError(f'bad --map "{spec}": expected ROLE=COLUMN with ROLE one of time, input, output, aux')
    role_name = role.lower() if role.isascii() else role
    if role_name not in ("time", "input", "output", "aux"):
        raise ValueError(f'bad --map "{spec}": unknown role "{role}" (roles: time, input, output, aux)')
    if role_name in ("output", "aux"):
        listed = opts.outputs if role_name == "output" else opts.aux
        if column not in listed:
            listed.append(column)
        return
    first = getattr(opts, role_name)
    if first is not None and first != column:
        raise ValueError(f'bad --map: the {role_name} column is given twice ("{first}" and "{column}")')
    setattr(opts, role_name, column)


def check_map(opts):
    """ColumnMap::check: no column plays two roles."""
    entries = opts.entries()
    for i, (role, column) in enumerate(entries):
        for other, c in entries[i + 1:]:
            if c == column:
                raise ValueError(f'bad --map: column "{column}" is given two roles ({role} and {other})')


def parse_window(spec):
    """Window::from_str: ("samples" | "seconds", start, end) or ("auto",)."""

    def fail(reason):
        return ValueError(
            f'bad --window "{spec}": {reason} (expected START:END in samples, e.g. 935:2603, in seconds, '
            "e.g. 12.5s:80s, or auto)"
        )

    if _trim(spec).lower() == "auto":
        return ("auto",)
    start, colon, end = spec.partition(":")
    if not colon:
        raise fail("no ':' between START and END")
    start, end = _trim(start), _trim(end)
    if not start and not end:
        raise fail("START and END are both empty")

    def in_seconds(s):
        return s.endswith(("s", "S"))

    if not start:
        seconds = in_seconds(end)
    elif not end:
        seconds = in_seconds(start)
    elif in_seconds(start) == in_seconds(end):
        seconds = in_seconds(start)
    else:
        raise fail("give both ends in samples or both in seconds")

    def side(s):
        if not s:
            return None
        if seconds:
            v = _parse_f64(_trim(s[:-1]))
            if v is None or not math.isfinite(v):
                raise fail(f'"{s}" is not a time in seconds')
            return v
        if not _RUST_USIZE.match(s) or int(s) >= 1 << 64:
            raise fail(f'"{s}" is not a sample index (a whole number; add `s` for seconds)')
        return int(s)

    a, b = side(start), side(end)
    if a is not None and b is not None and a >= b:
        raise fail("the window is empty (START must be before END)")
    return ("seconds" if seconds else "samples", a, b)


def window_display(window):
    """Window's Display."""
    kind, start, end = window
    if kind == "samples":
        return f"{'' if start is None else start}:{'' if end is None else end}"
    return f"{'' if start is None else _display(start) + 's'}:{'' if end is None else _display(end) + 's'}"


def add_invalid_spec(opts, spec):
    """LoadOptions::with_invalid_specs, for one CHANNEL=V1,V2."""
    bad = ValueError(f'--invalid: bad --invalid "{spec}": expected CHANNEL=VALUE[,VALUE...], e.g. T_inlet_C=-3276.8,3276.8')
    channel, eq, listed = spec.partition("=")
    if not eq:
        raise bad
    values = [_parse_f64(_trim(v)) for v in listed.split(",")]
    if any(v is None for v in values) or not _trim(channel) or not all(math.isfinite(v) for v in values):
        raise bad
    opts.invalid.setdefault(_trim(channel), []).extend(values)


# -- The table (table.rs) --


def _not_text(start):
    """table.rs not_text: what a file that is not text is, from its first bytes."""
    if start.startswith(b"\x1f\x8b"):
        return "gzip-compressed: decompress it first (gunzip)"
    if start.startswith(b"PK\x03\x04"):
        return "a zip archive (a spreadsheet's .xlsx, say): export the sheet as CSV"
    if b"\x00" in start:
        return "binary (it holds NUL bytes)"
    return None


def _first_data_line(data):
    """table.rs first_data_line: the text from the first line that is not a `#` comment on."""
    while data[:1] == b"#":
        i = data.find(b"\n")
        data = b"" if i < 0 else data[i + 1:]
    return data


def _separator(data):
    """table.rs separator: `;` or a tab when the header line has one and no comma, else a comma."""
    first_line = data.split(b"\n", 1)[0]
    for sep in b",;\t":
        if bytes([sep]) in first_line:
            return sep
    return ord(",")


_FIELD_ENDS = {}


def _csv_unquoted(data, i, sep):
    """The rest of a field up to the separator or a line end: (bytes, next offset, record ended)."""
    ends = _FIELD_ENDS.setdefault(sep, re.compile(b"[" + re.escape(bytes([sep])) + b"\r\n]"))
    m = ends.search(data, i)
    if m is None:
        return data[i:], len(data), True
    j = m.start()
    return data[i:j], j + 1, data[j] != sep


def _csv_field(data, i, sep):
    """One field as csv-core reads it: a field opening with `"` is quoted up to the next lone `"`
    (`""` is a quote; separators and line ends inside are text), and goes on unquoted after it."""
    if data[i:i + 1] != b'"':
        return _csv_unquoted(data, i, sep)
    out, i = bytearray(), i + 1
    while True:
        j = data.find(b'"', i)
        if j < 0:
            out += data[i:]
            return bytes(out), len(data), True
        out += data[i:j]
        i = j + 1
        if data[i:i + 1] != b'"':
            break
        out.append(ord('"'))
        i += 1
    rest, i, ended = _csv_unquoted(data, i, sep)
    return bytes(out) + rest, i, ended


def _csv_records(data, sep):
    """table.rs csv_reader: the records of data as the csv crate reads them (a BOM at the start
    dropped, empty lines and lines starting with `#` skipped, fields trimmed of ASCII white space),
    each with its byte offset (where reading it began, as csv's Position::byte). A comment that
    runs to the end of the data (no line feed after it) is read as a record of one empty field, as
    csv-core's DFA reads it."""
    i, n = (3 if data.startswith(_BOM) else 0), len(data)
    start = 0
    while True:
        while i < n and data[i] in b"\r\n#":
            if data[i] == ord("#"):
                j = data.find(b"\n", i)
                if j < 0:
                    yield start, [b""]
                    return
                i = j + 1
            else:
                i += 1
        if i >= n:
            return
        fields, ended = [], False
        while not ended:
            field, i, ended = _csv_field(data, i, sep)
            fields.append(field.strip(_CSV_WHITESPACE))
        yield start, fields
        start = i


def _line_at(data, start):
    """Source::line_at: the 1-based line of the record read from byte `start` (a record's offset
    may point at the end of the line before; up to four line-end bytes are stepped over)."""
    end = min(len(data), start + 4)
    k = min(start, end)
    while k < end and data[k] in b"\r\n":
        k += 1
    return 1 + data.count(b"\n", 0, k)


def _parse_cell(raw):
    """table.rs parse_cell: a finite number, _MISSING (empty, NaN or infinite) or _NOT_NUMBER."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        return _NOT_NUMBER
    if not text:
        return _MISSING
    v = _parse_f64(text)
    if v is None and "," in text:
        v = _parse_f64(text.replace(",", "."))
    if v is None:
        return _NOT_NUMBER
    return v if math.isfinite(v) else _MISSING


def _shown(raw):
    """table.rs shown: a cell as text for a message, cut to 40 characters."""
    text = raw.decode("utf-8", "replace")
    return text[:40] + "…" if len(text) > 40 else text


def _header_name(i, raw):
    """A header name as read_table reads it: UTF-8, else Latin-1; a BOM dropped; trimmed."""
    try:
        name = raw.decode("utf-8")
    except UnicodeDecodeError:
        name = raw.decode("latin-1")
    return _trim(name.lstrip("\ufeff") if i == 0 else name)


class Table:
    """table.rs Table: the header, every cell parsed (column by column) and each record's offset."""

    def __init__(self, file, data):
        self.file, self.data = file, data
        what = _not_text(data[:_RECORD_READ_BACK])
        if what is not None:
            raise RunFileError(f"{file}: not a text CSV file: it is {what}")
        self.sep = _separator(_first_data_line(data[:_RECORD_READ_BACK]))
        records = _csv_records(data, self.sep)
        first = next(records, None)
        if first is None:
            raise RunFileError(f"{file}: empty file: no header row")
        self.header = [_header_name(i, raw) for i, raw in enumerate(first[1])]
        if all(not name for name in self.header):
            raise RunFileError(f"{file}: empty file: no header row")
        for i, name in enumerate(self.header):
            if name and name in self.header[i + 1:]:
                second = self.header.index(name, i + 1) + 1
                raise RunFileError(f'{file}: line 1: column "{name}" appears twice (columns {i + 1} and {second})')
        self.columns = [[] for _ in self.header]
        self.starts = []
        for start, fields in records:
            if len(fields) != len(self.header):
                raise RunFileError(
                    f"{file}: line {_line_at(data, start)} (data row {len(self.starts) + 1}): {len(fields)} fields, "
                    f"the header has {len(self.header)}"
                )
            for column, raw in zip(self.columns, fields):
                column.append(_parse_cell(raw))
            self.starts.append(start)

    def n_rows(self):
        return len(self.starts)

    def line(self, row):
        """Table::line."""
        return _line_at(self.data, self.starts[row])

    def text(self, row, col):
        """Table::text: the cell's text, read again from the record's bytes."""
        start = self.starts[row]
        for _, fields in _csv_records(self.data[start:start + _RECORD_READ_BACK], self.sep):
            return _shown(fields[col] if col < len(fields) else b"")
        return ""

    def cell_error(self, row, col, missing):
        """Ctx::cell_error (`row` 0-based)."""
        where = f'{self.file}: line {self.line(row)} (data row {row + 1}), column "{self.header[col]}"'
        if missing:
            return RunFileError(f'{where}: missing value (cell "{self.text(row, col)}" is empty, NaN or infinite)')
        return RunFileError(f'{where}: "{self.text(row, col)}" is not a number')


# -- Columns to roles (column_map.rs) --


class Layout:
    """column_map.rs Layout: the column of every role; time is ("column", index) or ("fixed", dt)."""

    def __init__(self, time, input, outputs, aux, quality, ignored):
        self.time, self.input, self.outputs, self.aux = time, input, outputs, aux
        self.quality, self.ignored, self.extras = quality, ignored, []

    def used(self):
        used = [self.input] + self.outputs + self.aux + ([self.quality] if self.quality is not None else [])
        used += self.ignored
        return used + ([self.time[1]] if self.time[0] == "column" else [])


def _present(header):
    return ", ".join(name for name in header if name)


def _mapped(file, header, role, name):
    """Header::mapped."""
    if name not in header:
        raise RunFileError(f'{file}: bad --map {role}={name}: no column "{name}"; columns present: {_present(header)}')
    return header.index(name)


def _required(file, header, role, name):
    """Header::required."""
    if name not in header:
        hint = {"time": "; give --sample-time SECONDS or --map time=COLUMN", "input": "; map one with --map input=COLUMN"}
        raise RunFileError(
            f'{file}: no {role} column "{name}"; columns present: {_present(header)}{hint.get(role, "")}'
        )
    return header.index(name)


def _time_base(file, header, opts):
    """column_map.rs time_base."""
    if opts.time is not None and opts.sample_time_secs is not None:
        raise RunFileError(
            f'{file}: time is given twice: by column "{opts.time}" and by a sample time of '
            f"{_display(opts.sample_time_secs)} s; give one"
        )
    if opts.time is not None:
        return ("column", _mapped(file, header, "time", opts.time)), []
    if opts.sample_time_secs is not None:
        mapped_elsewhere = any(c == TIME_COLUMN for _, c in opts.entries())
        ignored = [header.index(TIME_COLUMN)] if TIME_COLUMN in header and not mapped_elsewhere else []
        return ("fixed", opts.sample_time_secs), ignored
    return ("column", _required(file, header, "time", TIME_COLUMN)), []


def _output_columns(file, header, opts):
    """column_map.rs output_columns."""
    if opts.input_only:
        return []
    if opts.outputs:
        return [_mapped(file, header, "output", c) for c in opts.outputs]
    found = [header.index(name) for name in OUTPUT_COLUMNS if name in header]
    if not found:
        raise RunFileError(
            f"{file}: no output column (shaft_speed_rpm or thrust_n); columns present: {_present(header)}; "
            "map one with --map output=COLUMN"
        )
    return found


def _quality_column(file, header, opts):
    """column_map.rs quality_column."""
    if opts.quality is None:
        return None
    for role, column in opts.entries():
        if column == opts.quality:
            raise RunFileError(f'{file}: bad --map: column "{column}" is given two roles ({role} and quality)')
    return _required(file, header, "quality", opts.quality)


def resolve_layout(file, header, opts):
    """column_map.rs resolve_layout."""
    time, ignored = _time_base(file, header, opts)
    if opts.input is not None:
        input_col = _mapped(file, header, "input", opts.input)
    else:
        input_col = _required(file, header, "input", INPUT_COLUMN)
    outputs = _output_columns(file, header, opts)
    aux = [_mapped(file, header, "aux", c) for c in opts.aux]
    layout = Layout(time, input_col, outputs, aux, _quality_column(file, header, opts), ignored)
    if not opts.aux:
        used = layout.used()
        layout.extras = [i for i, name in enumerate(header) if i not in used and name]
    return layout


# -- Rows, repair and the time axis (read.rs, window.rs, repair.rs) --


def _too_few_samples(file, found):
    return RunFileError(f"{file}: {found} samples, at least {MIN_SAMPLES} are needed")


def _quality(table, layout):
    """Ctx::quality: which rows the quality column marks good (all of them without one)."""
    col = layout.quality
    if col is None:
        return [True] * table.n_rows()
    good = []
    for row, v in enumerate(table.columns[col]):
        if isinstance(v, float) and abs(v - 1.0) < 1e-9:
            good.append(True)
        elif isinstance(v, float) and abs(v) < 1e-9:
            good.append(False)
        else:
            raise RunFileError(
                f'{table.file}: line {table.line(row)} (data row {row + 1}), quality column "{table.header[col]}": '
                f'"{table.text(row, col)}" is not 0 or 1'
            )
    return good


def _time_of_row(table, time, row):
    """Ctx::time_of_row: a row's time for a window in seconds; NaN when unreadable."""
    if time[0] == "fixed":
        return row * time[1]
    v = table.columns[time[1]][row]
    return v if isinstance(v, float) else math.nan


def _window_rows(window, n_rows, time_of_row):
    """Window::select: the rows (a, b) kept, or the reason the window does not fit."""
    kind, start, end = window
    if kind == "samples":
        a = 0 if start is None else start
        b = n_rows if end is None else end
        if b > n_rows or a >= n_rows:
            return None, f"out of range: the file has {n_rows} samples (0..{n_rows})"
        if a >= b:
            return None, "the window is empty"
        return (a, b), None

    def inside(t):
        return math.isfinite(t) and (start is None or t >= start) and (end is None or t < end)

    times = [time_of_row(i) for i in range(n_rows)]
    rows = [i for i, t in enumerate(times) if inside(t)]
    if rows:
        return (rows[0], rows[-1] + 1), None
    known = [t for t in times if math.isfinite(t)]
    lo, hi = (min(known), max(known)) if known else (math.inf, -math.inf)
    return None, f"out of range: no sample has a time in it (the file spans {_display(lo)} s to {_display(hi)} s)"


def select_rows(table, layout, opts, good):
    """read.rs select_rows: the rows of the window, and those kept once bad ends are trimmed."""
    file, n_rows = table.file, table.n_rows()
    if n_rows < MIN_SAMPLES:
        raise _too_few_samples(file, n_rows)
    window = (0, n_rows)
    if opts.window is not None:
        window, reason = _window_rows(opts.window, n_rows, lambda row: _time_of_row(table, layout.time, row))
        if reason is not None:
            raise RunFileError(f"{file}: bad --window {window_display(opts.window)}: {reason}")
    rows = range(*window)
    bad = len(rows) - sum(1 for row in rows if good[row])
    if layout.quality is not None and bad > MAX_BAD_FRACTION * len(rows):
        raise RunFileError(
            f'{file}: quality column "{table.header[layout.quality]}": {bad} of {len(rows)} samples are flagged bad '
            f"(more than {_display(100.0 * MAX_BAD_FRACTION)} %)"
        )
    first = next((row for row in rows if good[row]), window[0])
    last = next((row for row in reversed(rows) if good[row]), None)
    end = first if last is None else last + 1
    if end - first < MIN_SAMPLES:
        raise _too_few_samples(file, end - first)
    return window, (first, end)


def _column(table, col, kept, good, strict):
    """Ctx::column: the column over the kept rows, NaN in bad rows; a bad cell in a good row is an
    error when strict, otherwise None (the column is left out)."""
    values = []
    for row in range(*kept):
        v = table.columns[col][row]
        if not good[row]:
            values.append(math.nan)
        elif isinstance(v, float):
            values.append(v)
        elif strict:
            raise table.cell_error(row, col, v == _MISSING)
        else:
            return None
    return values


def fill_gaps(values):
    """repair.rs fill_gaps: NaN by linear interpolation between the nearest finite neighbours; at
    either end the nearest finite value."""
    n, prev, i = len(values), None, 0
    while i < n:
        if math.isfinite(values[i]):
            prev, i = i, i + 1
            continue
        nxt = next((j for j in range(i, n) if math.isfinite(values[j])), None)
        end = n if nxt is None else nxt
        for k in range(i, end):
            if prev is not None and nxt is not None:
                values[k] = values[prev] + (values[nxt] - values[prev]) * (k - prev) / (nxt - prev)
            elif prev is not None or nxt is not None:
                values[k] = values[prev if prev is not None else nxt]
            else:
                return
        i = end


def _repaired_column(table, col, kept, good):
    """Ctx::repaired_column."""
    values = _column(table, col, kept, good, True)
    fill_gaps(values)
    return values


def read_channels(table, layout, kept, good):
    """read.rs read_channels: names and values of the input, the outputs and the auxiliary channels
    (mapped, or the other columns that are numeric throughout)."""
    names, values = [], []
    for col in [layout.input] + layout.outputs + layout.aux:
        names.append(table.header[col])
        values.append(_repaired_column(table, col, kept, good))
    for col in layout.extras:
        column = _column(table, col, kept, good, False)
        if column is not None:
            fill_gaps(column)
            names.append(table.header[col])
            values.append(column)
    return names, values


def mark_invalid(file, names, values, invalid):
    """read.rs mark_invalid: every sentinel becomes a gap, interpolated."""
    for channel in sorted(invalid):
        sentinels = invalid[channel]
        if channel not in names:
            raise RunFileError(
                f'{file}: invalid values are given for channel "{channel}", which the run does not have '
                f"(channels: {', '.join(names)})"
            )
        column = values[names.index(channel)]
        count = 0
        for k, v in enumerate(column):
            if any(abs(v - s) <= 1e-9 * max(abs(s), 1.0) for s in sentinels):
                column[k] = math.nan
                count += 1
        if count == len(column) and count > 0:
            raise RunFileError(
                f'{file}: channel "{channel}" holds only its invalid-value sentinels '
                f"({', '.join(_display(s) for s in sentinels)}): it has no reading to use"
            )
        fill_gaps(column)


def mark_outliers(values):
    """repair.rs mark_outliers: a sample 100 ranges from its neighbours' median and 100 times the
    channel's size cannot be a measurement: interpolated."""
    finite = sorted(v for v in values if math.isfinite(v))
    if len(finite) < 7:
        return
    def at(q):
        return finite[int(_round_half_away((len(finite) - 1) * q))]
    p1, p50, p99 = at(0.01), at(0.5), at(0.99)
    limit = 100.0 * max(p99 - p1, 1e-9 * abs(p50), _MIN_POSITIVE)
    size_limit = 100.0 * max(abs(p1), abs(p99), _MIN_POSITIVE)
    found = []
    for k, v in enumerate(values):
        if not math.isfinite(v):
            continue
        neighbours = sorted(x for j, x in enumerate(values[max(k - 3, 0):k + 4], max(k - 3, 0))
                            if j != k and math.isfinite(x))
        if neighbours and abs(v - neighbours[len(neighbours) // 2]) > limit and abs(v) > size_limit:
            found.append(k)
    for k in found:
        values[k] = math.nan
    if found:
        fill_gaps(values)


def median_step(t):
    """repair.rs median_step: the median step to 12 significant digits."""
    steps = sorted(b - a for a, b in zip(t, t[1:]))
    if not steps:
        return 0.0
    mid = len(steps) // 2
    m = 0.5 * (steps[mid - 1] + steps[mid]) if len(steps) % 2 == 0 else steps[mid]
    return float("%.11e" % m)


def check_time(t):
    """repair.rs check_time: the sample time, or the problem ("increase" | "uniform", k, a, b)."""
    for k in range(1, len(t)):
        if t[k] <= t[k - 1] or not math.isfinite(t[k]):
            return None, ("increase", k, t[k - 1], t[k])
    dt = median_step(t)
    limit = TIME_TOLERANCE * dt * (1.0 + 1e-9)
    for k in range(1, len(t)):
        if abs((t[k] - t[k - 1]) - dt) > limit:
            return None, ("uniform", k, t[k] - t[k - 1], dt)
    return dt, None


def merge_repeated_times(t, channels):
    """repair.rs merge_repeated_times: rows repeating a time stamp merged into their mean."""
    if any(b < a or not math.isfinite(b) for a, b in zip(t, t[1:])):
        return t, channels
    groups, start = [], 0
    for k in range(1, len(t) + 1):
        if k == len(t) or t[k] != t[start]:
            groups.append((start, k))
            start = k
    if len(groups) == len(t):
        return t, channels

    def mean(part):
        s = 0.0
        for v in part:
            s += v
        return s / max(len(part), 1)

    return [t[a] for a, _ in groups], [[mean(v[a:b]) for a, b in groups] for v in channels]


def resample(t, channels, dt):
    """repair.rs resample: every channel onto t[0] + k dt by linear interpolation."""
    if not t:
        return [], channels
    if not (dt > 0.0 and math.isfinite(dt)):
        return list(t), channels
    t0, count = t[0], int(math.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
    grid = [t0 + k * dt for k in range(count)]
    weights, j = [], 0
    for tk in grid:
        while j + 2 < len(t) and t[j + 1] <= tk:
            j += 1
        ta, tb = t[j], (t[j + 1] if j + 1 < len(t) else None)
        weights.append((j, min(max((tk - ta) / (tb - ta), 0.0), 1.0) if tb is not None and tb > ta else 0.0))
    out = []
    for v in channels:
        out.append([v[j] + ((v[j + 1] if j + 1 < len(v) else v[j]) - v[j]) * w for j, w in weights])
    return grid, out


def uniform_time(table, layout, opts, first_row, t, values):
    """read.rs uniform_time: the sample time, and the time axis and channels made uniform."""
    if layout.time[0] == "fixed":
        return layout.time[1], t, values
    if opts.resample:
        t, values = merge_repeated_times(t, values)
    dt, problem = check_time(t)
    if problem is None:
        return dt, t, values
    kind, k, a, b = problem
    if kind == "uniform" and opts.resample:
        dt = median_step(t)
        t, values = resample(t, values, dt)
        return dt, t, values
    row, col = first_row + k, layout.time[1]
    where = f'{table.file}: line {table.line(row)} (data row {row + 1}), column "{table.header[col]}"'
    if kind == "increase":
        raise RunFileError(
            f"{where}: time {_display(b)} s does not increase (previous sample {_display(a)} s); a log with repeated or "
            "irregular time stamps is read with resample = true in the project's [load] or --resample"
        )
    raise RunFileError(
        f"{where}: time step {_display(a)} s differs from the sample time {_display(b)} s by more than "
        f"{_display(100.0 * TIME_TOLERANCE)} %; use --resample to resample onto a uniform grid"
    )


class Run:
    """A run as read: its time axis, sample time and channels (name, values) by role."""

    def __init__(self, name, dt, t, input, outputs, aux):
        self.name, self.dt, self.t, self.input, self.outputs, self.aux = name, dt, t, input, outputs, aux

    def channel(self, name):
        """Run::aux, else Run::channel: the values of the channel called name, or None."""
        for c_name, values in self.aux + [self.input] + self.outputs:
            if c_name == name:
                return values
        return None


def _read_bytes(file):
    """load_run_with_notes: the file's bytes; a folder or an unreadable file is refused."""
    try:
        if os.path.isdir(file):
            raise RunFileError(f"{file}: is a folder, not a run file; give the CSV file in it")
        with open(file, "rb") as f:
            return f.read()
    except OSError as e:
        raise RunFileError(f"{file}: cannot read the file: {e.strerror} (os error {e.errno})") from None


def load_run(file, opts):
    """csv_run.rs load_run and read.rs parse: the run, or the RunFileError jetid gives."""
    data = _read_bytes(file)
    table = Table(file, data)
    layout = resolve_layout(file, table.header, opts)
    good = _quality(table, layout)
    _, kept = select_rows(table, layout, opts, good)
    if layout.time[0] == "column":
        t = _repaired_column(table, layout.time[1], kept, good)
    else:
        t = [row * layout.time[1] for row in range(*kept)]
    names, values = read_channels(table, layout, kept, good)
    mark_invalid(file, names, values, opts.invalid)
    for column in values:
        mark_outliers(column)
    dt, t, values = uniform_time(table, layout, opts, kept[0], t, values)
    if len(t) < MIN_SAMPLES:
        raise _too_few_samples(file, len(t))
    channels = list(zip(names, values))
    n_out = len(layout.outputs)
    name = os.path.splitext(os.path.basename(file))[0] or os.path.basename(file)
    return Run(name, dt, t, channels[0], channels[1:1 + n_out], channels[1 + n_out:])
