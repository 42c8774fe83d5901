"""The fleet from Python and on a Dask cluster: ``jetid.fleet`` and the table gathered from one
task per run on a LocalCluster of worker processes are ``jetid fleet``'s fleet.csv, row for row."""
import math

import pandas as pd
import pytest

import jetid
from conftest import SAMPLES, needs_realdata, read_csv_exact, run_program

TEXT = ["engine", "run", "date", "output", "effects", "flag"]


def normalized(frame: pd.DataFrame) -> pd.DataFrame:
    """Text cells as text (an empty CSV cell and a missing value alike ""), numbers as floats."""
    frame = frame.copy()
    for column in frame.columns:
        if column in TEXT:
            frame[column] = frame[column].map(lambda v: "" if v is None or (isinstance(v, float) and math.isnan(v)) else str(v))
        else:
            frame[column] = frame[column].astype("float64")
    return frame.reset_index(drop=True)


def program_table(program, manifest, out) -> pd.DataFrame:
    """``jetid fleet``'s fleet.csv, every number read back exactly."""
    run_program(program, "fleet", manifest, "--out", out)
    frame = read_csv_exact(out / "fleet.csv", dtype={c: str for c in TEXT},
                        keep_default_na=False, na_values=[""])
    return normalized(frame)


def assert_same_table(got: pd.DataFrame, expected: pd.DataFrame):
    got = normalized(got)
    assert list(got.columns) == list(expected.columns)
    assert len(got) == len(expected) > 0
    pd.testing.assert_frame_equal(got, expected, rtol=1e-12, check_exact=False)


@pytest.fixture(scope="module")
def simulated_fleet(tmp_path_factory):
    """A simulated fleet of 200 runs: 20 engines of 10 runs, some of them faulty."""
    folder = tmp_path_factory.mktemp("fleet200")
    jetid.cli("simulate-fleet", "--engines", 20, "--runs", 10, "--seed", 3, "--run-secs", 100, "--out", folder)
    return folder / "manifest.toml"


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as local:
        with distributed.Client(local) as client:
            yield client


def test_fleet_is_the_program_table(simulated_fleet, program, tmp_path):
    expected = program_table(program, simulated_fleet, tmp_path / "cli")
    assert_same_table(jetid.fleet(simulated_fleet, tmp_path / "py"), expected)
    assert (tmp_path / "py" / "fleet.parquet").is_file()
    flagged = expected[expected.flag != ""]
    assert 0 < flagged.run.nunique() < 200, "a fleet with faults flags some runs and not all"


def test_dask_fleet_is_the_program_table(simulated_fleet, program, cluster, tmp_path):
    from jetid.distributed import fleet as dask_fleet

    seen = []
    table = dask_fleet(simulated_fleet, cluster, progress=lambda done, total: seen.append((done, total)))
    assert seen[-1] == (200, 200)
    assert len(cluster.scheduler_info()["workers"]) == 2
    assert_same_table(table, program_table(program, simulated_fleet, tmp_path / "cli"))


@needs_realdata("jetcat_p300pro_ecu")
def test_dask_fleet_is_the_program_table_on_the_jetcat(program, cluster, tmp_path):
    from jetid.distributed import fleet as dask_fleet

    manifest = SAMPLES / "fleet" / "jetcat.toml"
    expected = program_table(program, manifest, tmp_path / "cli")
    assert_same_table(dask_fleet(manifest, cluster), expected)
    flagged = set(expected[expected.flag != ""].run)
    assert {"C", "E"} <= flagged, flagged


def test_per_run_steps_refuse_what_the_manifest_lacks(simulated_fleet):
    engines = jetid.fleet_engines(simulated_fleet)
    assert len(engines) == 20 and all(len(runs) == 10 for _, runs in engines)
    engine, runs = engines[0]
    reference = jetid.fleet_reference(simulated_fleet, engine)
    with pytest.raises(jetid.JetidError, match="no engine 'nobody'"):
        jetid.fleet_reference(simulated_fleet, "nobody")
    with pytest.raises(jetid.JetidError, match="has no run 'r99'"):
        jetid.score_run(simulated_fleet, engine, "r99", reference)
    score = jetid.score_run(simulated_fleet, engine, runs[0], reference)
    import pickle

    again = pickle.loads(pickle.dumps(score))
    assert again.json == score.json and again.engine == engine
    with pytest.raises(jetid.JetidError, match="no score was given"):
        jetid.fleet_table(simulated_fleet, {engine: reference}, [score])
    with pytest.raises(jetid.JetidError, match="an engine's reference"):
        jetid.score_run(simulated_fleet, engine, runs[0], "{}")
