

# ---- The command line: `jetid predict --model MODEL --input IN.csv --out OUT.csv` as a program. ----

_VALUE_OPTIONS = ("--map", "--sample-time", "--window", "--quality", "--invalid")
_USAGE = (
    "usage: {} IN.csv OUT.csv [--calibrate] [--map ROLE=COLUMN]... [--sample-time SECONDS]\n"
    "       [--window START:END] [--quality COLUMN] [--invalid CHANNEL=V1,V2]... [--resample]"
)


def parse_args(argv):
    """The command line as {option: value(s)} with "files"; None when it cannot be read."""
    args = {"files": [], "--map": [], "--invalid": [], "--calibrate": False, "--resample": False}
    i = 1
    while i < len(argv):
        arg = argv[i]
        name, eq, value = arg.partition("=")
        if arg in ("--calibrate", "--resample"):
            args[arg] = True
        elif name in _VALUE_OPTIONS:
            if not eq:
                i += 1
                if i == len(argv):
                    return None
                value = argv[i]
            if name in ("--map", "--invalid"):
                args[name].append(value)
            else:
                args[name] = value
        elif arg.startswith("--"):
            return None
        else:
            args["files"].append(arg)
        i += 1
    return args if len(args["files"]) == 2 else None


def positive_secs(text):
    """cli::positive_secs, as `jetid predict` reads --sample-time."""
    v = _parse_f64(_trim(text))
    if v is not None and math.isfinite(v) and v > 0.0:
        return v
    got = _display(v) if v is not None else f'"{text}"'
    raise ValueError(
        f"invalid value '{text}' for '--sample-time <SECONDS>': must be a positive number of seconds, got {got}"
    )


def load_options(args):
    """cli/read_args.rs ReadArgs::options: the --map, --window and --invalid strings checked in
    that order; --calibrate maps every output calibration_drift corrects, as --map output=NAME."""
    opts = LoadOptions()
    calibrated = [f"output={n}" for n in OUTPUTS if OUTPUTS[n]["calibration"] is not None]
    for spec in args["--map"] + (calibrated if args["--calibrate"] else []):
        add_map_spec(opts, spec)
    check_map(opts)
    if "--sample-time" in args:
        opts.sample_time_secs = positive_secs(args["--sample-time"])
    if "--window" in args:
        opts.window = parse_window(args["--window"])
    opts.quality = args.get("--quality")
    opts.resample = args["--resample"]
    for spec in args["--invalid"]:
        add_invalid_spec(opts, spec)
    if opts.window == ("auto",):
        raise ValueError(
            "--window auto is not available in this program: the running part is found by jetid's running-window "
            "search; give --window START:END (`jetid inspect RUN.csv --window auto` shows the part it finds)"
        )
    # Started from the steady state, `jetid predict` needs the input alone unless outputs are mapped.
    opts.input_only = not opts.outputs
    return opts


def check_run(run, file):
    """What `jetid predict` checks of a run before simulating it (cli/predict.rs run)."""
    if run.input[0] != INPUT:
        raise ValueError(
            f"{MODEL_FILE} was identified from the input '{INPUT}', but {file} gives '{run.input[0]}' as its input: a "
            "model driven by another signal predicts nonsense (map the same signal with --map input=COLUMN)"
        )
    if abs(run.dt / DT - 1.0) > 0.02:
        raise ValueError(
            f"{file} is sampled every {_significant(run.dt, 5)} s but the model {MODEL_FILE} every "
            f"{_significant(DT, 5)} s; the model is discrete-time: resample the run (--resample puts an irregular "
            "log on its median step) or identify a model at its sample time"
        )


def ambient_channels(run, output, file):
    """AmbientCorrection::conditions: the inlet channels an output corrected for them reads, checked."""
    found = {}
    for channel in AMBIENT_CHANNELS:
        values = run.channel(channel)
        if values is None:
            raise ValueError(
                f"simulating output '{output}' on {file}: effect 'ambient_correction' needs the channel '{channel}', "
                f"which run '{run.name}' does not have"
            )
        found[channel] = values
    for channel, lowest in zip(AMBIENT_CHANNELS, (-_KELVIN_FROM_CELSIUS, 0.0)):
        for k, v in enumerate(found[channel]):
            if v <= lowest:
                raise ValueError(
                    f"simulating output '{output}' on {file}: channel '{channel}' of run '{run.name}' has the "
                    f"unphysical value {_display(v)} at sample {k}"
                )
    return found


def write_prediction(path, run, y):
    """write_run: time_s, the input and one column per output, written to a temporary file that is
    then renamed into place."""
    tmp = path + ".tmp"
    try:
        with open(tmp, "w", newline="") as f:
            f.write(",".join(["time_s", INPUT] + list(OUTPUTS)) + "\n")
            u = run.input[1]
            for k in range(len(run.t)):
                f.write(",".join(repr(float(x)) for x in [run.t[k], u[k]] + [y[n][k] for n in OUTPUTS]) + "\n")
        os.replace(tmp, path)
    except OSError as e:
        raise ValueError(f"{path}: cannot write the file: {e.strerror} (os error {e.errno})") from None


def main(argv):
    args = parse_args(argv)
    if args is None:
        print(_USAGE.format(argv[0]), file=sys.stderr)
        return 2
    file, out = args["files"]
    run = load_run(file, load_options(args))
    check_run(run, file)
    aux = {}
    for name in OUTPUTS:
        if needs_ambient(name):
            aux = ambient_channels(run, name, file)
    y = simulate(run.input[1], aux, dict(run.outputs), run.dt)
    write_prediction(out, run, y)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except (OSError, ValueError) as e:
        sys.stderr.buffer.write(f"error: {e}\n".encode("utf-8", "surrogateescape"))
        sys.exit(1)
