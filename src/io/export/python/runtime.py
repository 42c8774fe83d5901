
_MIN_POSITIVE = sys.float_info.min
_T_STD_K = 288.15
_P_STD_KPA = 101.325
_KELVIN_FROM_CELSIUS = 273.15
AMBIENT_CHANNELS = ("ambient_temp_c", "ambient_pressure_kpa")


def __getattr__(name):
    """TF, made on first use: python-control takes seconds to import, and reading and simulating a
    run do not need it."""
    if name != "TF":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import control

    globals()["TF"] = {n: control.TransferFunction(num, den, DT) for n, (num, den) in TF_COEFFS.items()}
    return globals()["TF"]


def _round_half_away(x):
    """Rust's f64::round for x >= 0 (Python's round() rounds half to even)."""
    whole = math.floor(x)
    return whole + 1 if x - whole >= 0.5 else whole


class _Filter:
    """G(z) in z^-1 simulated from the steady state of its first input."""

    def __init__(self, f):
        self.num, self.den, self.steady_gain = f["num"], f["den"], f["steady_gain"]
        self.u = None

    def step(self, x):
        if self.u is None:
            self.u = [x] * len(self.num)
            self.y = [self.steady_gain * x] * len(self.den)
        self.u = [x] + self.u[:-1]
        acc = 0.0
        for b, uk in zip(self.num, self.u):
            acc += b * uk
        for a, yk in zip(self.den[1:], self.y):
            acc -= a * yk
        self.y = [acc] + self.y[:-1]
        return acc


class _Delay:
    """u(k - whole - frac), linearly interpolated; the samples before the start equal the first."""

    def __init__(self, whole, frac):
        self.whole, self.frac = whole, frac
        self.line = None

    def step(self, x):
        if self.line is None:
            self.line = [x] * (self.whole + 2)
        self.line = [x] + self.line[:-1]
        return (1.0 - self.frac) * self.line[self.whole] + self.frac * self.line[self.whole + 1]


class _Spool:
    """The linear block split into its spool root and the rest: the spool's time constant scaled by
    the operating point it is heading for (schedule) and while falling (decel)."""

    def __init__(self, s, output, offset, limit, dt):
        self.dead = _Delay(s["dead_time"], 0.0)
        self.rest = _Filter(s["rest"]) if s["rest"] is not None else None
        self.ln_re, self.ln_im = s["ln_root"]
        self.pair, self.gain, self.decel, self.schedule = s["pair"], s["gain"], s["decel"], s["schedule"]
        self.output, self.offset = output, offset
        self.balance = None
        if self.schedule is not None and self.schedule[4] > 0.0:
            self.balance = _Balance(output, self.gain, offset, self.schedule[4], self.schedule[2])
        # The rate limit on the spool's state, per sample (rate_limit.rs StateLimit).
        self.limit = (limit[0] * dt, limit[1] * dt, limit[2] != 0) if limit is not None else None
        self.started = False

    def _clamp(self, nxt):
        """rate_limit.rs StateLimit::clamp: the state's change limited in the limited quantity's units."""
        up, down, through = self.limit
        v = self.gain * self.x + self.offset
        rate = self.gain * (static_map_slope(self.output, v) if through else 1.0)
        if not math.isfinite(rate) or abs(rate) <= _MIN_POSITIVE:
            return nxt
        if rate < 0.0:
            up, down = down, up
        r = abs(rate)
        return self.x + min(max(nxt - self.x, -down / r), up / r)

    def step(self, u):
        u = self.dead.step(u)
        r = self.rest.step(u) if self.rest is not None else u
        if not self.started:
            self.x = self.x_old = self.prev = self.prev_old = r
            self.started = True
        factor = 1.0
        if self.balance is not None:
            _, state_log_ratio, ref, span, _ = self.schedule
            factor = self.balance.factor(self.x, self.prev) * math.exp(-state_log_ratio * (self.x - ref) / span)
        elif self.schedule is not None:
            log_ratio, state_log_ratio, ref, span, _ = self.schedule
            factor = math.exp(-(log_ratio * (self.prev - ref) + state_log_ratio * (self.x - ref)) / span)
        if self.prev < self.x:
            factor *= self.decel
        f = max(factor, _MIN_POSITIVE)
        mag = math.exp(self.ln_re / f)
        root_re, root_im = mag * math.cos(self.ln_im / f), mag * math.sin(self.ln_im / f)
        if self.pair:
            a1, a2 = 2.0 * root_re, root_re * root_re + root_im * root_im
            nxt = a1 * self.x - a2 * self.x_old + (1.0 - a1 + a2) * self.prev_old
        else:
            nxt = root_re * self.x + (1.0 - root_re) * self.prev
        if self.limit is not None:
            nxt = self._clamp(nxt)
        self.x_old, self.x = self.x, nxt
        self.prev_old, self.prev = self.prev, r
        return self.gain * self.x


class _Balance:
    """power_balance.rs PowerBalance: the spool's power balance read through the static map; factor
    is the spool's time constant at state x heading for r over the one at the reference point."""

    def __init__(self, output, gain, offset, k, ref_x):
        self.map = OUTPUTS[output]["map"]
        self.output, self.gain, self.offset, self.k = output, gain, offset, k
        self.reference = None
        v_ref = gain * ref_x + offset
        smooth_ref, speed_ref = self._smooth(v_ref)[0], static_map(output, v_ref)
        if smooth_ref > 0.0 and speed_ref > 0.0:
            tau = self._tau(ref_x, ref_x, smooth_ref, speed_ref)
            if tau is not None:
                self.reference = (smooth_ref, speed_ref, tau)

    def _smooth(self, v):
        center, scale, coeffs, end_trend = self.map
        y, d = _map_polynomial(coeffs, end_trend, (v - center) / scale)
        return y, d / scale

    def _tau(self, x, r, smooth_ref, speed_ref):
        """(r - x)/dx/dt up to a constant, or None where the map gives no positive speed."""
        k, v = self.k, self.gain * x + self.offset
        n = static_map(self.output, v) / speed_ref
        dn_dx = static_map_slope(self.output, v) * self.gain / speed_ref
        if not n > 0.0:
            return None
        vr = self.gain * r + self.offset
        smooth, slope = self._smooth(v)
        p_x = max(smooth / smooth_ref, 1e-6) ** k
        p_r = max(self._smooth(vr)[0] / smooth_ref, 1e-6) ** k
        if abs(p_r - p_x) > 1e-9 * max(abs(p_x), 1e-9):
            dp_dx = (p_r - p_x) / (r - x)
        else:
            dp_dx = k * max(smooth / smooth_ref, 1e-6) ** (k - 1.0) * slope * self.gain / smooth_ref
        if dp_dx == 0.0:
            return None
        tau = n * dn_dx / dp_dx
        return tau if math.isfinite(tau) and tau > 0.0 else None

    def factor(self, x, r):
        if self.reference is None:
            return 1.0
        smooth_ref, speed_ref, at_ref = self.reference
        tau = self._tau(x, r, smooth_ref, speed_ref)
        return 1.0 if tau is None else min(max(tau / at_ref, 0.05), 20.0)


class _Soak:
    """Thermal soak: v + g (S_tau(z) v - v), S_tau a unit-gain first-order lag from v's first value."""

    def __init__(self, gain, tau_s, dt):
        self.gain, self.a = gain, math.exp(-dt / max(tau_s, _MIN_POSITIVE))
        self.s = None

    def step(self, v):
        if self.s is None:
            self.s = v
        self.s = self.a * self.s + (1.0 - self.a) * v
        return v + self.gain * (self.s - v)


class _Sensor:
    """Sensor lag (exact for an input linear between samples) and resonance (RK4)."""

    def __init__(self, freq_hz, zeta, lag_s, dt):
        self.dt, self.zeta = dt, zeta
        self.lag = lag_s > 1e-3
        if self.lag:
            self.a = math.exp(-dt / lag_s)
            self.ramp = 1.0 - lag_s * (1.0 - self.a) / dt
        self.omega = 2.0 * math.pi * freq_hz
        self.steps = max(math.ceil(self.omega * dt / 0.25), 4)
        self.h = dt / self.steps
        self.started = False

    def _deriv(self, pos, vel, u):
        return vel, self.omega * self.omega * (u - pos) - 2.0 * self.zeta * self.omega * vel

    def step(self, y):
        if not self.started:
            self.started = True
            self.y_prev = self.x = self.lagged = self.pos = y
            self.vel = 0.0
            return self.pos
        if self.lag:
            self.x = self.a * self.x + (1.0 - self.a) * self.y_prev + (y - self.y_prev) * self.ramp
            lagged = self.x
        else:
            lagged = y
        self.y_prev = y
        w0, w1, h, dt = self.lagged, lagged, self.h, self.dt
        pos, vel = self.pos, self.vel
        for k in range(self.steps):
            t = k * h
            u0 = w0 + (w1 - w0) * t / dt
            u1 = w0 + (w1 - w0) * (t + 0.5 * h) / dt
            u2 = w0 + (w1 - w0) * (t + h) / dt
            k1 = self._deriv(pos, vel, u0)
            k2 = self._deriv(pos + 0.5 * h * k1[0], vel + 0.5 * h * k1[1], u1)
            k3 = self._deriv(pos + 0.5 * h * k2[0], vel + 0.5 * h * k2[1], u1)
            k4 = self._deriv(pos + h * k3[0], vel + h * k3[1], u2)
            pos += h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
            vel += h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
        self.pos, self.vel, self.lagged = pos, vel, lagged
        return pos


def _poly(coeffs, x):
    y = 0.0
    for c in reversed(coeffs):
        y = y * x + c
    return y


def _poly_slope(coeffs, x):
    d = 0.0
    for i in range(len(coeffs) - 1, 0, -1):
        d = d * x + i * coeffs[i]
    return d


def _poly_curvature(coeffs, x):
    d = 0.0
    for i in range(len(coeffs) - 1, 1, -1):
        d = d * x + (i * (i - 1)) * coeffs[i]
    return d


def _map_polynomial(coeffs, end_trend, x):
    """static_map.rs StaticMap eval and slope: the polynomial part of f and its slope d/dx at x. Inside
    |x| <= 1 (everywhere without end_trend) the polynomial; beyond it the end's value, slope and
    curvature continue: an exponential approach where the curvature slows the map outwards, else
    their parabola."""
    if not end_trend or abs(x) <= 1.0:
        return _poly(coeffs, x), _poly_slope(coeffs, x)
    end = 1.0 if x > 0.0 else -1.0
    value, slope, curvature = _poly(coeffs, end), _poly_slope(coeffs, end), _poly_curvature(coeffs, end)
    t = end * (x - end)
    if end * slope * curvature < 0.0:
        length = abs(slope / curvature)
        return value + end * slope * (length * (1.0 - math.exp(-t / length))), slope * math.exp(-t / length)
    return value + (end * slope * t + 0.5 * curvature * t * t), slope + end * curvature * t


def static_map(output, v):
    """f(v): the map in x = (v - v_center)/v_scale (see _map_polynomial), plus the kink of
    static_map_order."""
    p = OUTPUTS[output]
    center, scale, coeffs, end_trend = p["map"]
    y, _ = _map_polynomial(coeffs, end_trend, (v - center) / scale)
    kink = 0.0
    if p["kink"] is not None:
        knot, slope_change = p["kink"]
        kink = slope_change * max(v - knot, 0.0)
    return y + kink


def static_map_slope(output, v):
    """df/dv, the kink included."""
    p = OUTPUTS[output]
    center, scale, coeffs, end_trend = p["map"]
    slope = _map_polynomial(coeffs, end_trend, (v - center) / scale)[1] / scale
    if p["kink"] is not None and v > p["kink"][0]:
        slope += p["kink"][1]
    return slope


def _read_off(read_off, n):
    """read_off_speed.rs ReadOffSpeed: the output at shaft speed n and its slope d/dN (a quartic
    in the scaled speed, with its end trend)."""
    center, scale = read_off[0], read_off[1]
    y, slope = _map_polynomial(list(read_off[2:7]), True, (n - center) / scale)
    return y, slope / scale


def _conditions(temp_c, pressure_kpa):
    if not (math.isfinite(temp_c) and temp_c > -_KELVIN_FROM_CELSIUS):
        raise ValueError(f"ambient_temp_c = {temp_c} is not a temperature")
    if not (math.isfinite(pressure_kpa) and pressure_kpa > 0.0):
        raise ValueError(f"ambient_pressure_kpa = {pressure_kpa} is not a pressure")
    return (temp_c + _KELVIN_FROM_CELSIUS) / _T_STD_K, pressure_kpa / _P_STD_KPA


class Model:
    """One output's model, stepped one sample at a time (as the C export's step function)."""

    def __init__(self, output, dt=DT, calibration_offset=0.0):
        p = OUTPUTS[output]
        self.output, self.p, self.offset = output, p, calibration_offset
        self.input_steps = [_Delay(s[1], s[2]) if s[0] == "delay" else None for s in p["input_steps"]]
        if p["split"] is not None:
            self.linear = _Spool(p["split"], output, p["offset"], p.get("rate_limit"), dt)
        else:
            self.linear = _Filter(p["tf"])
        self.soak = _Soak(p["soak"][0], p["soak"][1], dt) if p["soak"] is not None else None
        # A soak with an exponent k > 0 acts on the output's power y**k after the static map.
        self.soak_on_power = p["soak"] is not None and p["soak"][2] > 0.0
        self.dt = dt
        self.output_steps = self.fresh_output_steps()

    def fresh_output_steps(self):
        """The output stage's sensors (and the soak on the speed's power), at rest until their first
        sample."""
        if self.soak_on_power:
            self.soak = _Soak(self.p["soak"][0], self.p["soak"][1], self.dt)
        return [_Sensor(s[1], s[2], s[3], self.dt) if s[0] == "sensor" else None for s in self.p["output_steps"]]

    def input_stage(self, u, temp_c=None, pressure_kpa=None):
        """The input as the linear block sees it: delayed, corrected for inlet conditions."""
        for spec, delay in zip(self.p["input_steps"], self.input_steps):
            if delay is not None:
                u = delay.step(u)
            else:
                theta, delta = _conditions(temp_c, pressure_kpa)
                u = u / (delta * math.sqrt(theta))
        return u

    def step(self, u, temp_c=None, pressure_kpa=None):
        """The next output sample from the next input sample (and inlet conditions, when corrected)."""
        v = self.linear_step(self.input_stage(u, temp_c, pressure_kpa))
        return self.output_step(v, temp_c, pressure_kpa, self.output_steps)

    def linear_step(self, u_stage):
        """The static map's argument v from the next input-stage sample (calibration offset added)."""
        v = self.linear.step(u_stage + self.offset)
        if self.soak is not None and not self.soak_on_power:
            v = self.soak.step(v)
        return v + self.p["offset"]

    def output_step(self, v, temp_c, pressure_kpa, sensors):
        """The output from v: the static map, then the sensors and the inlet-conditions factor."""
        y = static_map(self.output, v)
        if self.soak_on_power:
            k = self.p["soak"][2]
            power = self.soak.step(math.copysign(abs(y) ** k, y))
            y = math.copysign(abs(power) ** (1.0 / k), power)
        corrected = None
        for spec, sensor in zip(self.p["output_steps"], sensors):
            if sensor is not None:
                y = sensor.step(y)
            else:
                theta, delta = _conditions(temp_c, pressure_kpa)
                factor = theta ** spec[1] * delta ** spec[2]
                y *= factor
                corrected = (theta, delta, factor)
        read_off = self.p["read_off"]
        if read_off is not None and corrected is not None:
            # Read off in corrected quantities: y/(theta^a delta^b) = P(N/sqrt(theta)).
            theta, delta, factor = corrected
            y = _read_off(read_off, y / factor)[0] * theta ** read_off[7] * delta ** read_off[8]
        elif read_off is not None:
            y = _read_off(read_off, y)[0]
        return y


def _plateaus(y, dt, hold_s, tail_s):
    """Windows (start, end): the last tail_s of each stretch where y holds within 1 % of its range."""
    lo, hi = min(y), max(y)
    tol = 0.01 * max(hi - lo, _MIN_POSITIVE)
    need = math.ceil(hold_s / dt)
    tail = max(_round_half_away(tail_s / dt), 2)
    out, start = [], 0
    for k in range(1, len(y) + 1):
        if k == len(y) or abs(y[k] - y[start]) > tol:
            if k - start >= max(need, tail):
                out.append((k - tail, k))
            start = k
    return out


def _steady_stretches(u, y, dt, hold_s):
    """Where the run held the engine steady: the last half of the output's holds longer than hold_s,
    and the input's holds after hold_s of settling (their last hold_s / 2), merged where they overlap."""
    tail = 0.5 * hold_s
    found = sorted(_plateaus(y, dt, hold_s, tail) + _plateaus(u, dt, hold_s + tail, tail))
    merged = []
    for a, b in found:
        if merged and a <= merged[-1][1]:
            merged[-1] = (merged[-1][0], max(merged[-1][1], b))
        else:
            merged.append((a, b))
    return merged


def _mean(x):
    s = 0.0
    for v in x:
        s += v
    return s / len(x) if len(x) else 0.0


def calibration_offset(output, u, temp, pres, y, dt=DT):
    """calibration_drift's input offset for one run: the offset that puts the model's response on the
    run's own steady stretches (holds of the measured output y or of the input after the input stage),
    compared by their means. The response to u + b is the static map and output stage of v + G(1)·b,
    with v the linear block's response to u."""
    p = OUTPUTS[output]
    if p["calibration"] is None:
        return 0.0
    hold_s, dc = p["calibration"]
    model = Model(output, dt)
    u_stage = [model.input_stage(uk, tk, pk) for uk, tk, pk in zip(u, temp, pres)]
    v = [model.linear_step(us) for us in u_stage]
    holds = [(a, b, _mean(y[a:b])) for a, b in _steady_stretches(u_stage, y, dt, hold_s)]
    lo, hi = min(u_stage), max(u_stage)
    span = max(hi - lo, _MIN_POSITIVE)
    if not holds or not math.isfinite(span):
        return 0.0

    def at_holds(b):
        sensors = model.fresh_output_steps()
        r = [model.output_step(vk + dc * b, tk, pk, sensors) for vk, tk, pk in zip(v, temp, pres)]
        return [_mean(r[a:e]) for a, e, _ in holds]

    def cost(m):
        return sum((hold[2] - mk) ** 2 for hold, mk in zip(holds, m))

    h = 1e-4 * span
    offset = 0.0
    here = at_holds(offset)
    for _ in range(30):
        up, down = at_holds(offset + h), at_holds(offset - h)
        jtj = jtr = 0.0
        for hold, mk, uk, dk in zip(holds, here, up, down):
            j = (uk - dk) / (2.0 * h)
            jtj += j * j
            jtr += j * (hold[2] - mk)
        if not jtj > _MIN_POSITIVE:
            break
        step = min(max(jtr / jtj, -0.1 * span), 0.1 * span)
        following = at_holds(offset + step)
        while abs(step) > 1e-12 * span and not cost(following) <= cost(here):
            step *= 0.5
            following = at_holds(offset + step)
        offset += step
        here = following
        if abs(step) <= 1e-9 * span:
            break
    return offset if math.isfinite(offset) and abs(offset) <= 0.5 * span else 0.0


def needs_ambient(output):
    return any(s[0] == "ambient" for s in OUTPUTS[output]["input_steps"])


def simulate(u, aux=None, measured=None, dt=DT):
    """Every output from the input u (array), from the steady state of u[0].

    aux: {channel: array}, with ambient_temp_c and ambient_pressure_kpa for outputs corrected for
    inlet conditions. measured: {output: array} of measured outputs, used only by calibration_drift
    (its per-run offset); without it the run is simulated uncalibrated, as `jetid predict` does for
    a run without that output. Returns {output: numpy array}."""
    u = [float(x) for x in u]
    aux = aux or {}
    measured = measured or {}
    out = {}
    for name in OUTPUTS:
        temp = pres = [None] * len(u)
        if needs_ambient(name):
            missing = [c for c in AMBIENT_CHANNELS if c not in aux]
            if missing:
                raise ValueError(f"output '{name}' is corrected for inlet conditions and needs {missing}")
            temp, pres = [float(x) for x in aux[AMBIENT_CHANNELS[0]]], [float(x) for x in aux[AMBIENT_CHANNELS[1]]]
        offset = 0.0
        if OUTPUTS[name]["calibration"] is not None and name in measured:
            offset = calibration_offset(name, u, temp, pres, [float(y) for y in measured[name]], dt)
        model = Model(name, dt, offset)
        out[name] = np.array([model.step(uk, tk, pk) for uk, tk, pk in zip(u, temp, pres)])
    return out


def _tf_zinv(num, den):
    """A control.TransferFunction from coefficients in z^-1 (padded to equal length)."""
    import control

    n = max(len(num), len(den))
    return control.TransferFunction(list(num) + [0.0] * (n - len(num)), list(den) + [0.0] * (n - len(den)), DT)


def local_dynamics(output, u_star):
    """The unit-steady-gain local dynamics at the steady input u_star, in z^-1 (num, den), as jetid's
    operating points build them: the linear block (its spool at the time constant of u_star when
    scheduled; the rising one when asymmetric), then the effects' dead time, soak and sensor."""
    p = OUTPUTS[output]
    s = p["split"]
    if s is None:
        g1 = p["tf"]["steady_gain"]
        num, den = np.array(p["tf"]["num"]) / g1, np.array(p["tf"]["den"])
    else:
        factor = 1.0
        if s["schedule"] is not None and s["schedule"][4] > 0.0:
            _, state_log_ratio, ref, span, k = s["schedule"]
            balance = _Balance(output, s["gain"], p["offset"], k, ref)
            factor = balance.factor(u_star, u_star) * math.exp(-state_log_ratio * (u_star - ref) / span)
        elif s["schedule"] is not None:
            log_ratio, state_log_ratio, ref, span, _ = s["schedule"]
            factor = math.exp(-(log_ratio + state_log_ratio) * (u_star - ref) / span)
        f = max(factor, _MIN_POSITIVE)
        mag = math.exp(s["ln_root"][0] / f)
        re, im = mag * math.cos(s["ln_root"][1] / f), mag * math.sin(s["ln_root"][1] / f)
        if s["pair"]:
            a1, a2 = 2.0 * re, re * re + im * im
            spool_num, spool_den = [0.0, 0.0, 1.0 - a1 + a2], [1.0, -a1, a2]
        else:
            spool_num, spool_den = [0.0, 1.0 - re], [1.0, -re]
        num, den = np.convolve([0.0] * s["dead_time"] + [1.0], spool_num), np.array(spool_den)
        if s["rest"] is not None:
            num, den = np.convolve(num, s["rest"]["num"]), np.convolve(den, s["rest"]["den"])
    fixed = p["effect_dynamics"]
    num, den = np.convolve(num, fixed["num"]), np.convolve(den, fixed["den"])
    return num / (np.sum(num) / np.sum(den)), den


def operating_point(output, u_star):
    """The local linear model at the steady state of input u_star (on a standard day, without
    calibration offset), as a control.TransferFunction: K G(z)/G(1) with K = f'(v*) G(1) the local
    gain (times P'(f(v*)) for an output read off the speed), v* = G(1) u_star + offset the linear block's steady output, and the effects linearised
    where they act (see local_dynamics)."""
    p = OUTPUTS[output]
    g1 = p["tf"]["steady_gain"]
    v_star = g1 * u_star + p["offset"]
    k = static_map_slope(output, v_star) * g1
    if p["read_off"] is not None:
        k *= _read_off(p["read_off"], static_map(output, v_star))[1]
    num, den = local_dynamics(output, u_star)
    return _tf_zinv(k * num, den)


def _roots(kinds, x, bounded):
    """Roots from their coordinates (see COVARIANCE): atanh of a real pole / of a pair's modulus with
    its angle when bounded (poles), the positions themselves otherwise (zeros). Returns the roots and
    how many coordinates they took."""
    roots, at = [], 0
    for kind in kinds:
        if kind == "real":
            roots.append(complex(math.tanh(x[at]) if bounded else x[at], 0.0))
            at += 1
        else:
            z = cmath.rect(math.tanh(x[at]), x[at + 1]) if bounded else complex(x[at], x[at + 1])
            roots += [z, z.conjugate()]
            at += 2
    return roots, at


def _covariance(output):
    c = COVARIANCE[output]
    if c is None:
        raise ValueError(f"the model file holds no parameter covariance for {output!r}: re-run `jetid --batch`")
    return c


def sample_parameters(output, n, seed=0):
    """n parameter vectors (rows, in the order of COVARIANCE[output]["names"]) drawn from the normal
    distribution of the covariance, reproducibly from seed."""
    c = _covariance(output)
    rng = np.random.default_rng(seed)
    return rng.multivariate_normal(np.array(c["values"]), np.array(c["matrix"]), size=n, method="eigh")


def model_at(output, theta):
    """The model of parameter vector theta: {"theta", "tf": the linear block G(z) as a
    control.TransferFunction (its roots from theta, its steady gain and dead time held), "map": the
    static map as OUTPUTS[output]["map"] with theta's coefficients, "effects": each effect's free
    parameters}. The effects' parameters are given as drawn, in the form the fit moves them."""
    c = _covariance(output)
    poles, at = _roots(c["poles"], theta, True)
    zeros, used = _roots(c["zeros"], theta[at:], False)
    at += used
    den = np.real(np.poly(poles))
    num = np.real(np.poly(zeros)) if zeros else np.array([1.0])
    num = num * c["steady_gain"] / (np.sum(num) / np.sum(den))
    num_zinv = [0.0] * (len(poles) - len(zeros) + c["delay"]) + list(num)
    center, scale, _, end_trend = OUTPUTS[output]["map"]
    m = c["map"]
    return {
        "theta": np.asarray(theta),
        "tf": _tf_zinv(num_zinv, den),
        "map": (center, scale, [float(b) for b in theta[at:at + m]], end_trend),
        "effects": np.asarray(theta[at + m:]),
    }


def sample_models(output, n, seed=0):
    """n models drawn from the parameter covariance (see model_at): the spread a robust controller
    design has to allow for."""
    return [model_at(output, theta) for theta in sample_parameters(output, n, seed)]


def operating_point_ci95(output, u_star, n=2000, seed=0):
    """The 95 % interval of the local gain dy/du at the steady input u_star: the 2.5 and 97.5
    percentiles over n static maps drawn from the covariance (G(1) and the kink's knot held)."""
    c = _covariance(output)
    p = OUTPUTS[output]
    g1 = c["steady_gain"]
    v_star = g1 * u_star + p["offset"]
    gains = []
    for theta in sample_parameters(output, n, seed):
        center, scale, coeffs, end_trend = model_at(output, theta)["map"]
        slope = _map_polynomial(coeffs, end_trend, (v_star - center) / scale)[1] / scale
        if p["kink"] is not None and v_star > p["kink"][0]:
            slope += p["kink"][1]
        gains.append(slope * g1)
    return {"gain": [float(np.percentile(gains, 2.5)), float(np.percentile(gains, 97.5))]}
