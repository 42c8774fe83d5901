
function o = find_output(m, name)
for i = 1:numel(m.outputs)
    if strcmp(m.outputs{i}.name, name) || strcmp(m.outputs{i}.ident, name)
        o = m.outputs{i};
        return;
    end
end
error('jetid:output', 'the model has no output ''%s''', name);
end

function out = simulate_all(m, u, aux, measured, dt)
if nargin < 3, aux = []; end
if nargin < 4, measured = []; end
if nargin < 5 || isempty(dt), dt = m.dt; end
u = u(:)';
out = struct();
for i = 1:numel(m.outputs)
    o = m.outputs{i};
    [us, theta, delta] = input_stage(o, u, aux);
    v = linear_stage(o, us, dt);
    if ~isempty(o.calibration) && isstruct(measured) && isfield(measured, o.ident)
        offset = calibration_offset(o, us, v, theta, delta, measured.(o.ident)(:)', dt);
        if offset ~= 0, v = linear_stage(o, us + offset, dt); end
    end
    out.(o.ident) = output_stage(o, v, theta, delta, dt);
end
end

function [u, theta, delta] = input_stage(o, u, aux)
theta = [];
delta = [];
for i = 1:numel(o.input_steps)
    s = o.input_steps{i};
    if strcmp(s.kind, 'delay')
        u = delay(u, s.whole, s.frac);
    else
        t = aux.ambient_temp_c(:)';
        p = aux.ambient_pressure_kpa(:)';
        if any(~isfinite(t) | t <= -273.15) || any(~isfinite(p) | p <= 0)
            error('jetid:ambient', 'unphysical inlet conditions');
        end
        theta = (t + 273.15) / 288.15;
        delta = p / 101.325;
        u = u ./ (delta .* sqrt(theta));
    end
end
end

function y = delay(u, whole, frac)
% u(k - whole - frac), linearly interpolated; samples before the start equal the first.
n = numel(u);
y = zeros(1, n);
for k = 1:n
    j = k - whole;
    a = u(max(j, 1));
    b = u(max(j - 1, 1));
    y(k) = (1 - frac) * a + frac * b;
end
end

function y = filter_from_steady(f, u)
% G(z) in z^-1 from the steady state of u(1): past inputs u(1), past outputs steady_gain * u(1).
n = numel(u);
y = zeros(1, n);
u0 = u(1);
y0 = f.steady_gain * u0;
for k = 1:n
    acc = 0;
    for j = 1:numel(f.num)
        if k - j + 1 >= 1, x = u(k - j + 1); else, x = u0; end
        acc = acc + f.num(j) * x;
    end
    for j = 2:numel(f.den)
        if k - j + 1 >= 1, x = y(k - j + 1); else, x = y0; end
        acc = acc - f.den(j) * x;
    end
    y(k) = acc;
end
end

function v = linear_stage(o, u, dt)
if isempty(o.split)
    v = filter_from_steady(o.tf, u);
else
    v = o.split.gain * spool(o.split, delay(u, o.split.dead_time, 0), o, dt);
end
if ~isempty(o.soak) && ~(o.soak(3) > 0)
    v = soak(o.soak, v, dt);
end
v = v + o.offset;
end

function x = soak(sk, x, dt)
% The soak branch: x + g (S_tau(z) x - x), S_tau a unit-gain first-order lag from x's first value.
a = exp(-dt / max(sk(2), realmin));
s = x(1);
for k = 1:numel(x)
    s = a * s + (1 - a) * x(k);
    x(k) = x(k) + sk(1) * (s - x(k));
end
end

function out = spool(sp, u, o, dt)
% The spool root's time constant scaled by the operating point it is heading for (schedule) and
% while falling (decel), its state's changes limited by the rate limit; the rest of the block
% ahead of it.
if isempty(sp.rest), r = u; else, r = filter_from_steady(sp.rest, u); end
x = r(1); x_old = x; prev = x; prev_old = x;
out = zeros(1, numel(r));
for k = 1:numel(r)
    factor = 1;
    if ~isempty(sp.schedule) && sp.schedule(5) > 0
        c = sp.schedule;
        factor = balance_factor(o, sp, x, prev) * exp(-c(2) * (x - c(3)) / c(4));
    elseif ~isempty(sp.schedule)
        c = sp.schedule;
        factor = exp(-(c(1) * (prev - c(3)) + c(2) * (x - c(3))) / c(4));
    end
    if prev < x, factor = factor * sp.decel; end
    f = max(factor, realmin);
    mag = exp(sp.ln_root(1) / f);
    re = mag * cos(sp.ln_root(2) / f);
    im = mag * sin(sp.ln_root(2) / f);
    if sp.pair
        a1 = 2 * re;
        a2 = re * re + im * im;
        nxt = a1 * x - a2 * x_old + (1 - a1 + a2) * prev_old;
    else
        nxt = re * x + (1 - re) * prev;
    end
    if ~isempty(o.rate_limit)
        nxt = limit_state(o, sp, x, nxt, dt);
    end
    x_old = x; x = nxt;
    prev_old = prev; prev = r(k);
    out(k) = x;
end
end

function f = balance_factor(o, sp, x, r)
% power_balance.rs PowerBalance::factor: the spool's time constant at state x heading for r over the
% one at the reference operating point (bounded to [0.05, 20]), by the power balance read through
% the static map; 1 where the map gives no positive speed.
ref = sp.schedule(3);
v_ref = sp.gain * ref + o.offset;
smooth_ref = map_polynomial(o, (v_ref - o.v_center) / o.v_scale);
speed_ref = static_map(o, v_ref);
f = 1;
if ~(smooth_ref > 0 && speed_ref > 0)
    return;
end
at_ref = balance_tau(o, sp, ref, ref, smooth_ref, speed_ref);
tau = balance_tau(o, sp, x, r, smooth_ref, speed_ref);
if at_ref > 0 && tau > 0
    f = min(max(tau / at_ref, 0.05), 20);
end
end

function tau = balance_tau(o, sp, x, r, smooth_ref, speed_ref)
% power_balance.rs PowerBalance::time_constant: (r - x)/dx/dt up to a constant, 0 where the map
% gives no positive speed.
k = sp.schedule(5);
v = sp.gain * x + o.offset;
n = static_map(o, v) / speed_ref;
dn_dx = static_map_slope(o, v) * sp.gain / speed_ref;
tau = 0;
if ~(n > 0)
    return;
end
vr = sp.gain * r + o.offset;
[smooth, slope] = map_polynomial(o, (v - o.v_center) / o.v_scale);
p_x = max(smooth / smooth_ref, 1e-6) ^ k;
p_r = max(map_polynomial(o, (vr - o.v_center) / o.v_scale) / smooth_ref, 1e-6) ^ k;
if abs(p_r - p_x) > 1e-9 * max(abs(p_x), 1e-9)
    dp_dx = (p_r - p_x) / (r - x);
else
    dp_dx = k * max(smooth / smooth_ref, 1e-6) ^ (k - 1) * (slope / o.v_scale) * sp.gain / smooth_ref;
end
t = n * dn_dx / dp_dx;
if isfinite(t) && t > 0
    tau = t;
end
end

function nxt = limit_state(o, sp, x, nxt, dt)
% rate_limit.rs StateLimit::clamp: the state's change limited in the limited quantity's units (the
% output's, through the map's slope, or v's).
up = o.rate_limit(1) * dt;
down = o.rate_limit(2) * dt;
v = sp.gain * x + o.offset;
if o.rate_limit(3)
    rate = sp.gain * static_map_slope(o, v);
else
    rate = sp.gain;
end
if ~isfinite(rate) || abs(rate) <= realmin
    return;
end
if rate < 0
    t = up; up = down; down = t;
end
r = abs(rate);
nxt = x + min(max(nxt - x, -down / r), up / r);
end

function y = static_map(o, v)
y = map_polynomial(o, (v - o.v_center) / o.v_scale);
if ~isempty(o.kink)
    y = y + o.kink(2) * max(v - o.kink(1), 0);
end
end

function d = static_map_slope(o, v)
[~, d] = map_polynomial(o, (v - o.v_center) / o.v_scale);
d = d / o.v_scale;
if ~isempty(o.kink) && v > o.kink(1)
    d = d + o.kink(2);
end
end

function [y, d] = map_polynomial(o, x)
% static_map.rs StaticMap eval and slope: the polynomial part of f and its slope d/dx at x. Inside
% |x| <= 1 (everywhere without end_trend) the polynomial; beyond it the end's value, slope and
% curvature continue: an exponential approach where the curvature slows the map outwards, else
% their parabola.
[y, d] = poly_at(o.coeffs, x);
if ~o.end_trend
    return;
end
for e = [-1, 1]
    out = e * x > 1;
    if ~any(out(:))
        continue;
    end
    [p0, p1, p2] = poly_at(o.coeffs, e);
    t = e * (x(out) - e);
    if e * p1 * p2 < 0
        len = abs(p1 / p2);
        y(out) = p0 + e * p1 * (len * (1 - exp(-t / len)));
        d(out) = p1 * exp(-t / len);
    else
        y(out) = p0 + (e * p1 * t + 0.5 * p2 * t .* t);
        d(out) = p1 + e * p2 * t;
    end
end
end

function [p0, p1, p2] = poly_at(c, x)
% The polynomial's value, slope and curvature at x.
p0 = zeros(size(x));
p1 = zeros(size(x));
p2 = zeros(size(x));
for i = numel(c):-1:1
    p0 = p0 .* x + c(i);
end
for i = numel(c):-1:2
    p1 = p1 .* x + (i - 1) * c(i);
end
for i = numel(c):-1:3
    p2 = p2 .* x + (i - 1) * (i - 2) * c(i);
end
end

function y = output_stage(o, v, theta, delta, dt)
y = static_map(o, v);
if ~isempty(o.soak) && o.soak(3) > 0
    % A soak with an exponent k > 0 acts on the output's power y^k.
    k = o.soak(3);
    p = soak(o.soak, sign(y) .* abs(y) .^ k, dt);
    y = sign(p) .* abs(p) .^ (1 / k);
end
factor = [];
for i = 1:numel(o.output_steps)
    s = o.output_steps{i};
    if strcmp(s.kind, 'ambient')
        factor = theta .^ s.theta_exp .* delta .^ s.delta_exp;
        y = y .* factor;
    else
        y = sensor(s, y, dt);
    end
end
if ~isempty(o.read_off) && ~isempty(factor)
    % Read off in corrected quantities: y/(theta^a delta^b) = P(N/sqrt(theta)).
    y = read_off(o, y ./ factor) .* theta .^ o.read_off(8) .* delta .^ o.read_off(9);
elseif ~isempty(o.read_off)
    y = read_off(o, y);
end
end

function [y, d] = read_off(o, n)
% read_off_speed.rs ReadOffSpeed: the output at shaft speed n and its slope d/dN (a quartic in the
% scaled speed, with its end trend).
r = struct('coeffs', o.read_off(3:7), 'end_trend', true);
[y, d] = map_polynomial(r, (n - o.read_off(1)) / o.read_off(2));
d = d / o.read_off(2);
end

function out = sensor(s, y, dt)
% Sensor lag (exact for an input linear between samples), then the resonance by RK4.
n = numel(y);
lagged = y;
if s.lag_s > 1e-3
    a = exp(-dt / s.lag_s);
    ramp = 1 - s.lag_s * (1 - a) / dt;
    x = y(1);
    for k = 2:n
        x = a * x + (1 - a) * y(k - 1) + (y(k) - y(k - 1)) * ramp;
        lagged(k) = x;
    end
end
w = 2 * pi * s.freq_hz;
steps = max(ceil(w * dt / 0.25), 4);
h = dt / steps;
deriv = @(pos, vel, u) [vel, w * w * (u - pos) - 2 * s.zeta * w * vel];
pos = lagged(1);
vel = 0;
out = zeros(1, n);
out(1) = pos;
for k = 2:n
    w0 = lagged(k - 1);
    w1 = lagged(k);
    for st = 0:steps - 1
        t = st * h;
        u0 = w0 + (w1 - w0) * t / dt;
        u1 = w0 + (w1 - w0) * (t + 0.5 * h) / dt;
        u2 = w0 + (w1 - w0) * (t + h) / dt;
        k1 = deriv(pos, vel, u0);
        k2 = deriv(pos + 0.5 * h * k1(1), vel + 0.5 * h * k1(2), u1);
        k3 = deriv(pos + 0.5 * h * k2(1), vel + 0.5 * h * k2(2), u1);
        k4 = deriv(pos + h * k3(1), vel + h * k3(2), u2);
        pos = pos + h / 6 * (k1(1) + 2 * k2(1) + 2 * k3(1) + k4(1));
        vel = vel + h / 6 * (k1(2) + 2 * k2(2) + 2 * k3(2) + k4(2));
    end
    out(k) = pos;
end
end

function w = plateaus(x, dt, hold_s, tail_s)
% Windows [a, b) (0-based a, as the other runtimes): the last tail_s of every stretch where x holds
% within 1 % of its range for at least hold_s.
tol = 0.01 * max(max(x) - min(x), realmin);
need = ceil(hold_s / dt);
tail = max(floor(tail_s / dt + 0.5), 2);
w = zeros(0, 2);
start = 1;
n = numel(x);
for k = 2:n + 1
    if k == n + 1 || abs(x(k) - x(start)) > tol
        if k - start >= max(need, tail)
            w(end + 1, :) = [k - 1 - tail, k - 1]; %#ok<AGROW>
        end
        start = k;
    end
end
end

function offset = calibration_offset(o, u, v, theta, delta, y, dt)
% calibration_drift: the input offset that puts the model's response on the run's own steady
% stretches (the last half of every hold of the measured output longer than hold_s, and the last
% hold_s / 2 of every hold of the input after hold_s of settling, merged where they overlap), compared
% by their means. The response to u + b is the output stage of v + G(1) b, v the linear block's
% response to u.
hold_s = o.calibration(1);
dc = o.calibration(2);
tail_s = 0.5 * hold_s;
found = [plateaus(y, dt, hold_s, tail_s); plateaus(u, dt, hold_s + tail_s, tail_s)];
merged = zeros(0, 2);
if ~isempty(found)
    found = sortrows(found);
    merged = found(1, :);
    for k = 2:size(found, 1)
        if found(k, 1) <= merged(end, 2)
            merged(end, 2) = max(merged(end, 2), found(k, 2));
        else
            merged(end + 1, :) = found(k, :); %#ok<AGROW>
        end
    end
end
hy = hold_means(y, merged);
span = max(max(u) - min(u), realmin);
offset = 0;
if isempty(hy) || ~isfinite(span), return; end
at_holds = @(b) hold_means(output_stage(o, v + dc * b, theta, delta, dt), merged);
h = 1e-4 * span;
here = at_holds(offset);
for it = 1:30
    j = (at_holds(offset + h) - at_holds(offset - h)) / (2 * h);
    jtj = sum(j .* j);
    jtr = sum(j .* (hy - here));
    if ~(jtj > realmin), break; end
    step = min(max(jtr / jtj, -0.1 * span), 0.1 * span);
    next = at_holds(offset + step);
    while abs(step) > 1e-12 * span && ~(sum((hy - next) .^ 2) <= sum((hy - here) .^ 2))
        step = step * 0.5;
        next = at_holds(offset + step);
    end
    offset = offset + step;
    here = next;
    if abs(step) <= 1e-9 * span, break; end
end
if ~(isfinite(offset) && abs(offset) <= 0.5 * span), offset = 0; end
end

function m = hold_means(x, windows)
% The mean of x over each window [a, b) (0-based a).
m = zeros(1, size(windows, 1));
for k = 1:size(windows, 1)
    a = windows(k, 1);
    b = windows(k, 2);
    m(k) = sum(x(a + 1:b)) / (b - a);
end
end

function run_csv(m, in_file, out_file, calibrate)
if nargin < 4, calibrate = ''; end
fid = fopen(in_file, 'r');
if fid < 0, error('jetid:csv', 'cannot read %s', in_file); end
names = strtrim(strsplit(fgetl(fid), ','));
fclose(fid);
data = dlmread(in_file, ',', 1, 0);
col = @(name) data(:, find(strcmp(names, name), 1))';
t = col('time_s');
u = col(m.input);
steps = sort(diff(t));
mid = floor(numel(steps) / 2);
if mod(numel(steps), 2) == 0, dt = 0.5 * (steps(mid) + steps(mid + 1)); else, dt = steps(mid + 1); end
dt = str2double(sprintf('%.11e', dt));
if abs(dt / m.dt - 1) > 0.02
    error('jetid:dt', '%s is sampled every %g s but the model every %g s', in_file, dt, m.dt);
end
aux = struct();
if any(strcmp(names, 'ambient_temp_c')) && any(strcmp(names, 'ambient_pressure_kpa'))
    aux.ambient_temp_c = col('ambient_temp_c');
    aux.ambient_pressure_kpa = col('ambient_pressure_kpa');
end
measured = struct();
if strcmp(calibrate, 'calibrate')
    for i = 1:numel(m.outputs)
        if any(strcmp(names, m.outputs{i}.name)), measured.(m.outputs{i}.ident) = col(m.outputs{i}.name); end
    end
end
y = simulate_all(m, u, aux, measured, dt);
fid = fopen(out_file, 'w');
header = ['time_s,', m.input];
table = [t; u];
for i = 1:numel(m.outputs)
    header = [header, ',', m.outputs{i}.name]; %#ok<AGROW>
    table = [table; y.(m.outputs{i}.ident)]; %#ok<AGROW>
end
fprintf(fid, '%s\n', header);
fprintf(fid, [repmat('%.17g,', 1, size(table, 1) - 1), '%.17g\n'], table);
fclose(fid);
end
