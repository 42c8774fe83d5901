"""Shared fixtures of the Python package's tests: where the repository, its sample runs, the real
data and the ``jetid`` program are, and how to compare what the package and the program write."""
import json
import math
import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SAMPLES = REPO / "sample_runs"
REALDATA = REPO.parent / "shared" / "realdata"
#: Numbers the package and the program compute by the same code agree to rounding; the issue's bar.
TOLERANCE = 1e-12


def jetid_program() -> Path:
    """The ``jetid`` program the package is compared with: $JETID_BIN, else the newest build in
    target/ (``cargo build`` makes one)."""
    if os.environ.get("JETID_BIN"):
        return Path(os.environ["JETID_BIN"])
    built = [p for p in (REPO / "target" / d / "jetid" for d in ("release", "debug")) if p.is_file()]
    if not built:
        pytest.fail("no jetid program to compare with: build it (cargo build) or set JETID_BIN")
    return max(built, key=lambda p: p.stat().st_mtime)


@pytest.fixture(scope="session")
def program() -> Path:
    return jetid_program()


def run_program(program: Path, *args, cwd=None) -> subprocess.CompletedProcess:
    result = subprocess.run([str(program), *map(str, args)], capture_output=True, text=True, cwd=cwd)
    if result.returncode != 0:
        raise AssertionError(f"jetid {' '.join(map(str, args))} failed:\n{result.stderr}")
    return result


def needs_realdata(folder: str):
    """Skip, saying why, when the shared real-data folder is absent."""
    return pytest.mark.skipif(
        not (REALDATA / folder).is_dir(), reason=f"needs ../shared/realdata/{folder} beside the repository"
    )


def assert_close(a, b, path="", tol=TOLERANCE):
    """Two JSON values equal: the same keys and strings, numbers to ``tol`` relative (absolute near 0)."""
    if isinstance(a, dict) and isinstance(b, dict):
        assert sorted(a) == sorted(b), f"{path}: keys differ: {sorted(set(a) ^ set(b))}"
        for k in a:
            assert_close(a[k], b[k], f"{path}.{k}", tol)
    elif isinstance(a, list) and isinstance(b, list):
        assert len(a) == len(b), f"{path}: lengths {len(a)} and {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_close(x, y, f"{path}[{i}]", tol)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        if math.isnan(a) or math.isnan(b):
            assert math.isnan(a) and math.isnan(b), f"{path}: {a} against {b}"
        else:
            assert abs(a - b) <= tol * max(1.0, abs(a), abs(b)), f"{path}: {a!r} against {b!r}"
    else:
        assert a == b, f"{path}: {a!r} against {b!r}"


def read_csv_exact(path, **options):
    """A CSV file as a data frame with every number read back exactly (pandas 3 always does; before
    it, only with the round-trip parser)."""
    import pandas as pd

    if int(pd.__version__.split(".")[0]) < 3:
        options.setdefault("float_precision", "round_trip")
    return pd.read_csv(path, **options)


def load_json(path: Path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


@pytest.fixture(scope="session")
def sr30_cli(program, tmp_path_factory) -> Path:
    """``jetid --batch`` on the bundled sr30 project, once for the session."""
    out = tmp_path_factory.mktemp("sr30-cli")
    run_program(program, "--batch", SAMPLES / "sr30" / "project.toml", "--out", out, "--quiet")
    return out
