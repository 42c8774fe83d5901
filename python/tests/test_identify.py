"""The package reproduces the ``jetid`` program: the same project, run through ``jetid.identify``
from data frames and through ``jetid.batch``, gives the model, the report's metrics and the
predictions the program writes, to 1e-12."""
import os
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import jetid
from conftest import SAMPLES, assert_close, load_json, needs_realdata, read_csv_exact, run_program

PROJECTS = [
    pytest.param(SAMPLES / "sr30" / "project.toml", id="sr30"),
    pytest.param(SAMPLES / "hot_day" / "project.toml", id="hot_day"),
    pytest.param(
        SAMPLES / "jetcat_p300" / "project.toml",
        id="jetcat",
        marks=needs_realdata("jetcat_p300pro_ecu"),
    ),
]

RUN_KEYS = ("ident", "validate", "held_out", "chirp", "steady")


def read_frame(path: Path) -> pd.DataFrame:
    """A run file as a data frame, every number read back exactly."""
    return read_csv_exact(path, comment="#")


def as_run(entry, base: Path) -> jetid.Run:
    """A project file's run entry as a data frame with the entry's own load options."""
    if isinstance(entry, str):
        entry = {"path": entry}
    path = (base / entry["path"]).resolve()
    load = {k: v for k, v in entry.items() if k != "path"}
    return jetid.Run(read_frame(path), name=path.stem, **load)


def identify_from_frames(project: Path) -> jetid.Model:
    """``jetid.identify`` on the project's runs read into data frames, with its settings."""
    with open(project, "rb") as f:
        spec = tomllib.load(f)
    base = project.parent
    runs = {}
    for key in RUN_KEYS:
        if key not in spec:
            continue
        value = spec[key]
        runs[key] = [as_run(e, base) for e in value] if isinstance(value, list) else as_run(value, base)
    settings = {k: v for k, v in spec.items() if k not in RUN_KEYS and k != "name"}
    return jetid.identify(runs, **settings)


@pytest.fixture(scope="module")
def cli_results(program, tmp_path_factory):
    cache = {}

    def results(project: Path) -> Path:
        if project not in cache:
            out = tmp_path_factory.mktemp(project.parent.name + "-cli")
            run_program(program, "--batch", project, "--out", out, "--quiet")
            cache[project] = out
        return cache[project]

    return results


@pytest.mark.parametrize("project", PROJECTS)
def test_identify_from_data_frames_gives_the_batch_model(project, cli_results):
    model = identify_from_frames(project)
    assert_close(model.data, load_json(cli_results(project) / "model.json"))


@pytest.mark.parametrize("project", PROJECTS)
def test_batch_gives_the_program_report(project, cli_results, tmp_path):
    report = jetid.batch(project, tmp_path / "out")
    expected = load_json(cli_results(project) / "report.json")
    got = dict(report.data)
    for r in (got, expected):
        r.pop("timings_ms", None)
    assert_close(got, expected)
    assert_close(report.model.data, load_json(cli_results(project) / "model.json"))
    metrics = report.metrics
    assert set(metrics["model"]) >= {"gray_box", "linear"}, set(metrics["model"])
    first = metrics.iloc[0]
    assert first["rmspe_pct"] == expected["outputs"][first["output"]]["models"][first["model"]][first["run"]]["rmspe_pct"]
    assert sorted(os.listdir(tmp_path / "out")) == sorted(os.listdir(cli_results(project)))


def predict_args(project: Path):
    """The validation run of a project and the reading options the program needs for it."""
    with open(project, "rb") as f:
        spec = tomllib.load(f)
    entry = spec["validate"][0]
    entry = {"path": entry} if isinstance(entry, str) else dict(entry)
    path = (project.parent / entry.pop("path")).resolve()
    load = dict(spec.get("load", {}))
    load.update(entry)
    args = []
    for m in load.get("map", []):
        args += ["--map", m]
    if "window" in load:
        args += ["--window", load["window"]]
    if "quality" in load:
        args += ["--quality", load["quality"]]
    return path, load, args


@pytest.mark.parametrize("project", PROJECTS)
@pytest.mark.parametrize("initial_state", ["steady", "estimated"])
def test_predictions_are_the_program_predictions(project, initial_state, program, cli_results, tmp_path):
    model_path = cli_results(project) / "model.json"
    run, load, args = predict_args(project)
    if initial_state == "estimated" and not any(m.startswith("output=") for m in load.get("map", [])):
        args += [f"--map=output={o}" for o in jetid.load_model(model_path).outputs]
        load = dict(load, map=load.get("map", []) + [f"output={o}" for o in jetid.load_model(model_path).outputs])
    out = tmp_path / "pred.csv"
    run_program(program, "predict", "--model", model_path, "--input", run, "--out", out,
                "--initial-state", initial_state, *args)
    expected = read_frame(out)
    load.pop("units", None)
    got = jetid.load_model(model_path).predict(read_frame(run), initial_state, **load)
    assert list(got.columns) == list(expected.columns)
    for column in expected.columns:
        np.testing.assert_allclose(got[column], expected[column], rtol=1e-12, atol=0, err_msg=column)


def test_identified_model_predicts_as_its_saved_file(tmp_path):
    model = identify_from_frames(SAMPLES / "sr30" / "project.toml")
    model.save(tmp_path / "model.json")
    loaded = jetid.load_model(tmp_path / "model.json")
    assert_close(loaded.data, model.data, tol=0.0)
    run = read_frame(SAMPLES / "sr30" / "validation.csv")
    a, b = model.predict(run), loaded.predict(run)
    assert a.equals(b)
    assert set(model.outputs) <= set(a.columns)
