"""jetid from Python, top to bottom: identify the bundled SR-30 runs from data frames, diagnose
the model, add the effect the diagnosis ranks first, design the README's PI speed controller on an
operating point, and track the health of a small simulated fleet.

Run from the repository root after `pip install .`:  python examples/python/walkthrough.py
(CI runs it.) It writes into a temporary folder and prints what it found.
"""
import tempfile
from pathlib import Path

import control
import numpy as np
import pandas as pd

import jetid

SAMPLES = Path(__file__).resolve().parents[2] / "sample_runs" / "sr30"


def read(name: str) -> pd.DataFrame:
    return pd.read_csv(SAMPLES / f"{name}.csv")


def rmspe(measured: pd.Series, predicted: pd.Series) -> float:
    """Root-mean-square error as a percentage of the measured range."""
    return 100 * float(np.sqrt(np.mean((measured - predicted) ** 2)) / (measured.max() - measured.min()))


# 1. Identify: the runs by role, as data frames; the settings are a project file's keys.
runs = {name: read(name) for name in ("ident", "validation", "chirp", "steady")}
model = jetid.identify(
    {"ident": runs["ident"], "validate": [("validation", runs["validation"])],
     "chirp": runs["chirp"], "steady": runs["steady"]},
    outputs=["shaft_speed_rpm", "thrust_n"],
)
print(model)
predicted = model.predict(runs["validation"], "estimated", map=["output=shaft_speed_rpm", "output=thrust_n"])
for output in model.outputs:
    print(f"  {output}: validation RMSPE {rmspe(runs['validation'][output], predicted[output]):.3f} %")

# 2. Diagnose: every refinement and catalog effect tried, best first.
diagnosis = model.diagnose()
print("\nDiagnosis (best three per output):")
print(diagnosis.groupby("output").head(3)[["output", "effect", "kind", "rmspe_before_pct", "rmspe_after_pct",
                                             "significant"]].to_string(index=False))

# 3. Add the catalog effect ranked first on the shaft speed, and see what it does on validation.
speed = diagnosis[(diagnosis.output == "shaft_speed_rpm") & diagnosis.effect.isin(jetid.effect_ids())]
top = speed.iloc[0]
extended = model.add_effect(top.effect)
after = extended.predict(runs["validation"], "estimated", map=["output=shaft_speed_rpm", "output=thrust_n"])
print(f"\nWith {top.effect} (significant: {top.significant}):")
for output in model.outputs:
    before_pct = rmspe(runs["validation"][output], predicted[output])
    after_pct = rmspe(runs["validation"][output], after[output])
    print(f"  {output}: {before_pct:.3f} % -> {after_pct:.3f} %")

# 4. The README's PI speed controller on the local model at 4 gal/h.
points = model.operating_points()
print("\nOperating points of the shaft speed:")
print(points[points.output == "shaft_speed_rpm"][["u", "y", "gain"]].to_string(index=False))
m = model.to_control()
g = m.operating_point("shaft_speed_rpm", 4.0)            # local model at 4 gal/h, sample time m.DT
K = control.dcgain(g)                                    # local gain, rpm per gal/h
tau = max(-m.DT / np.log(abs(p)) for p in g.poles())     # slowest time constant there, s
wc = 1.0                                                 # crossover wanted, rad/s
kp, ki = wc * tau / K, wc / K                            # PI zero on the slowest pole: L ~ wc/s
z = control.tf([1, 0], [1], m.DT)
pi = kp + ki * m.DT * z / (z - 1)                        # backward-Euler PI
info = control.step_info(control.feedback(pi * g, 1))
print(f"\nPI at 4 gal/h: K = {K:.0f} rpm per gal/h, tau = {tau:.2f} s, kp = {kp:.2e}, ki = {ki:.2e}: "
      f"rise {info['RiseTime']:.2f} s, overshoot {info['Overshoot']:.1f} %, settling {info['SettlingTime']:.2f} s")

# 5. A small fleet: three simulated engines of four runs each, scored against their references.
with tempfile.TemporaryDirectory() as folder:
    jetid.cli("simulate-fleet", "--engines", 3, "--runs", 4, "--seed", 5, "--run-secs", 120,
              "--fault-rate", 0.2, "--out", folder)
    table = jetid.fleet(Path(folder) / "manifest.toml")
runs_scored = table[["engine", "run"]].drop_duplicates()
print(f"\nFleet: {len(runs_scored)} runs of {table.engine.nunique()} engines")
print(table[["engine", "run", "output", "rmspe_pct", "input_gain", "tau_scale"]].to_string(index=False))
flagged = table[table.flag != ""][["engine", "run", "flag"]].drop_duplicates(["engine", "run"])
print(f"{len(flagged)} runs flagged:" if len(flagged) else "no run flagged")
for row in flagged.itertuples():
    print(f"  {row.engine} {row.run}: {row.flag}")
