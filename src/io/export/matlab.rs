//! The MATLAB/Octave rendering of a [`Plan`]: one function file whose first argument picks what it
//! does (simulate, the `tf` objects, the local linear model, CSV to CSV), the model's numbers as a
//! struct, and a runtime of the same recursions as `core::effects`, stage by stage over the run.
use super::ExportError;
use super::parts::{self, Block, Step};
use super::plan::{Filter, Linear, OutputPlan, Plan};
use super::{header, list, num};
use crate::core::identification::static_map::Beyond;

/// Longest MATLAB identifier (`namelengthmax`).
const MAX_NAME_LEN: usize = 63;

pub(super) fn render(plan: &Plan, name: &str) -> Result<String, ExportError> {
    let valid = name.len() <= MAX_NAME_LEN
        && name.starts_with(|c: char| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !valid {
        return Err(ExportError::BadMatlabName { name: name.to_owned() });
    }
    let mut text = format!("function varargout = {name}(command, varargin)\n");
    for line in header(plan, "MATLAB") {
        text.push_str(&format!("% {line}\n"));
    }
    text.push_str(&USAGE.replace("NAME", name));
    text.push_str(DISPATCH);
    text.push_str(&format!(
        "\nfunction m = model_data()\n% The numbers of every step of each output's signal path.\nm.dt = {};\nm.input = '{}';\nm.outputs = {{}};\n",
        num(plan.dt_secs),
        plan.input
    ));
    for out in &plan.outputs {
        text.push_str(&output(out));
    }
    text.push_str("end\n");
    text.push_str(RUNTIME);
    Ok(text)
}

fn row(xs: &[f64]) -> String {
    list(xs, "[", "]")
}

fn filter(prefix: &str, f: &Filter) -> String {
    format!(
        "{prefix}.num = {};\n{prefix}.den = {};\n{prefix}.steady_gain = {};\n",
        row(&f.num_zinv),
        row(&f.den_zinv),
        num(f.steady_gain)
    )
}

fn output(o: &OutputPlan) -> String {
    let mut t = format!(
        "% Output '{}' [{}].\no = struct();\no.name = '{}';\no.ident = '{}';\n",
        o.name, o.unit, o.name, o.ident
    );
    t.push_str(&filter("o.tf", &o.tf));
    let (n, d) = o.tf.positive_powers();
    t.push_str(&format!("o.tf_num_z = {};\no.tf_den_z = {};\n", row(&n), row(&d)));
    t.push_str(&format!(
        "o.offset = {};\no.v_center = {};\no.v_scale = {};\no.coeffs = {};\no.end_trend = {};\n",
        num(o.offset),
        num(o.map.v_center),
        num(o.map.v_scale),
        row(&o.map.coeffs_scaled),
        o.map.beyond == Beyond::EndTrend
    ));
    for block in parts::map_blocks(o) {
        t.push_str(&assign_block("o", &block));
    }
    t.push_str(&format!("o.input_steps = {};\n", steps(o.input_steps.iter().map(parts::input_step))));
    t.push_str(&split(&o.linear));
    for block in parts::v_blocks(o) {
        t.push_str(&assign_block("o", &block));
    }
    t.push_str(&format!(
        "o.output_steps = {};\n{}m.outputs{{end + 1}} = o;\n",
        steps(o.output_steps.iter().map(parts::output_step)),
        assign_block("o", &parts::read_off(o))
    ));
    t
}

/// `target.key = [numbers];`, or `= [];` without the block.
fn assign_block(target: &str, block: &Block) -> String {
    let values = block.values().map(|values| values.join(", ")).unwrap_or_default();
    format!("{target}.{} = [{values}];\n", block.key)
}

/// Steps as a cell array of structs `struct('kind', 'KIND', 'name', number, …)`.
fn steps(steps: impl Iterator<Item = Step>) -> String {
    let steps: Vec<String> = steps
        .map(|s| {
            let fields: String =
                s.fields.iter().map(|(name, value)| format!(", '{name}', {value}")).collect();
            format!("struct('kind', '{}'{fields})", s.kind)
        })
        .collect();
    format!("{{{}}}", steps.join(", "))
}

/// `o.split`: the struct of a split linear block, or `[]` for a direct one.
fn split(linear: &Linear) -> String {
    let Linear::Split(s) = linear else { return "o.split = [];\n".to_owned() };
    let mut t = format!(
        "sp = struct();\nsp.dead_time = {};\nsp.ln_root = [{}, {}];\nsp.pair = {};\nsp.gain = {};\nsp.decel = {};\n",
        s.dead_time,
        num(s.ln_root.0),
        num(s.ln_root.1),
        if s.pair { "true" } else { "false" },
        num(s.gain),
        num(s.decel)
    );
    match &s.rest {
        Some(rest) => t.push_str(&filter("rest", rest)),
        None => t.push_str("rest = [];\n"),
    }
    t.push_str("sp.rest = rest;\n");
    t.push_str(&assign_block("sp", &parts::schedule(s)));
    t.push_str("o.split = sp;\n");
    t
}

const USAGE: &str = r"%
% NAME('simulate', u, aux, measured, dt) -> struct with one field per output: the outputs simulated
%   from the input vector u. aux: struct with fields ambient_temp_c and ambient_pressure_kpa (for
%   outputs corrected for inlet conditions), or []; measured: struct of measured outputs (fields as in the result), used only
%   by calibration_drift's per-run offset, or []; dt: the run's sample time (default: the model's).
% NAME('tf') -> struct with one tf object G(z) per output (tf(num, den, Ts)).
% NAME('operating_point', output, u_star) -> the local linear model K G(z)/G(1), K = f'(v*) G(1)
%   (times P'(f(v*)) for an output read off the shaft speed).
% NAME('csv', 'IN.csv', 'OUT.csv' [, 'calibrate']) -> what `jetid predict` writes for IN.csv.
% tf objects need the Control System Toolbox (Octave: pkg load control); the simulation does not.
";

const DISPATCH: &str = r"m = model_data();
switch command
    case 'simulate'
        varargout{1} = simulate_all(m, varargin{:});
    case 'tf'
        g = struct();
        for i = 1:numel(m.outputs)
            o = m.outputs{i};
            g.(o.ident) = tf(o.tf_num_z, o.tf_den_z, m.dt);
        end
        varargout{1} = g;
    case 'operating_point'
        o = find_output(m, varargin{1});
        g1 = o.tf.steady_gain;
        v_star = g1 * varargin{2} + o.offset;
        k = static_map_slope(o, v_star) * g1;
        if ~isempty(o.read_off)
            [~, slope] = read_off(o, static_map(o, v_star));
            k = k * slope;
        end
        varargout{1} = tf(o.tf_num_z, o.tf_den_z, m.dt) * (k / g1);
    case 'csv'
        run_csv(m, varargin{:});
    otherwise
        error('jetid:command', 'unknown command ''%s'' (simulate, tf, operating_point, csv)', command);
end
end
";

const RUNTIME: &str = include_str!("matlab/runtime.m");
