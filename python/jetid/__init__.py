"""jetid from Python: turbojet test-bench runs to control-oriented gray-box (Wiener) models.

The same Rust core as the ``jetid`` program, with numpy and pandas in and out:

* :func:`batch` runs ``jetid --batch`` on a project and returns its :class:`Report`;
* :func:`identify` builds the model of runs held in data frames (or files), as the batch builds
  its model.json, and returns a :class:`Model` that predicts, diagnoses, takes an effect, gives
  its operating points and python-control objects, and saves itself;
* :func:`load_model` reads a saved model.json;
* :func:`fleet` is ``jetid fleet``; :func:`fleet_reference`, :func:`score_run` and
  :func:`fleet_table` are its steps, for a distributed engine that scores one run per task
  (:mod:`jetid.distributed` runs them on Dask);
* :func:`cli` runs any ``jetid`` command in this process.

Errors jetid reports are raised as :class:`JetidError` with the command line's message. The GIL is
released while the core computes, so other Python threads run meanwhile.
"""
from __future__ import annotations

import json
import os
import tempfile
import types
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import pandas as pd

from . import _jetid
from ._jetid import JetidError

__version__: str = _jetid.__version__

__all__ = [
    "JetidError",
    "Model",
    "Report",
    "Run",
    "RunScore",
    "batch",
    "cli",
    "effect_ids",
    "fleet",
    "fleet_engines",
    "fleet_reference",
    "fleet_table",
    "identify",
    "load_model",
    "score_run",
]

#: A run: a data frame, a mapping of column names to arrays, or the path of a run file.
RunData = Union[pd.DataFrame, Mapping[str, Any], str, "os.PathLike[str]"]

#: The roles of :func:`identify`'s runs and the project keys they fill.
ROLES: Dict[str, str] = {
    "ident": "ident",
    "identification": "ident",
    "validate": "validate",
    "validation": "validate",
    "held_out": "held_out",
    "chirp": "chirp",
    "steady": "steady",
}

#: Keys of a project's ``[load]`` table, also taken as keyword arguments of :func:`identify`.
LOAD_KEYS = ("map", "sample_time", "window", "quality", "resample", "invalid", "units")


def cli(*args: Any) -> None:
    """Run ``jetid ARGS...`` in this process, e.g. ``cli("simulate", "--test", "ident", "--out", "x.csv")``.

    The same parsing, checks and messages as the ``jetid`` program; a failure raises
    :class:`JetidError` with the message the program prints after ``error:``.
    """
    _jetid.cli([os.fspath(a) if isinstance(a, os.PathLike) else str(a) for a in args])


def effect_ids() -> List[str]:
    """The catalog effects' names (what :meth:`Model.add_effect` and ``add_effects`` take)."""
    return list(_jetid.effect_ids())


# --- runs ------------------------------------------------------------------------------------


def _columns(data: Union[pd.DataFrame, Mapping[str, Any]]) -> List[Tuple[str, bytes]]:
    """Numeric columns as (name, little-endian float64 bytes); text columns are left out, as the
    reader leaves a run file's text columns out."""
    if isinstance(data, pd.DataFrame):
        items = [(str(c), data[c]) for c in data.columns]
    else:
        items = [(str(k), v) for k, v in data.items()]
    out = []
    for name, values in items:
        array = np.asarray(values)
        if array.dtype.kind not in "biuf":
            continue
        out.append((name, np.ascontiguousarray(array, dtype="<f8").tobytes()))
    if not out:
        raise JetidError("the run holds no numeric column (text columns are left out)")
    return out


def _frame(columns: Sequence[Tuple[str, bytes]]) -> pd.DataFrame:
    return pd.DataFrame({name: np.frombuffer(raw, dtype="<f8").copy() for name, raw in columns})


class Run:
    """A run with its name and load options of its own: what a project file's run table says
    (``{ path = "runA.csv", window = "935:2603" }``), for a run held in memory or in a file.

    ``data`` is a data frame, a mapping of column names to arrays, or a file path; ``load`` takes
    the ``[load]`` keys (``window``, ``map``, ``quality``, ``sample_time``, …), which override the
    project's own for this run.
    """

    def __init__(self, data: RunData, name: Optional[str] = None, **load: Any) -> None:
        self.data = data
        self.name = name
        self.load = load

    def __repr__(self) -> str:
        return f"<jetid.Run {self.name or '(unnamed)'} {self.load or ''}>"


class _Runs:
    """Runs named for a project: files by their paths, tables in memory by their names."""

    def __init__(self) -> None:
        self.tables: List[Tuple[str, List[Tuple[str, bytes]]]] = []

    def entry(self, data: Any, default_name: str) -> Any:
        """The project file's entry of the run ``data``: a path, or a table with its options."""
        name, load = default_name, {}
        if isinstance(data, Run):
            name, load, data = data.name or default_name, dict(data.load), data.data
        elif isinstance(data, tuple) and len(data) == 2 and isinstance(data[0], str):
            name, data = data
        if isinstance(data, (str, os.PathLike)):
            path = os.fspath(data)
        else:
            if isinstance(data, pd.DataFrame) and isinstance(data.attrs.get("name"), str):
                name = data.attrs["name"]
            if any(existing == name for existing, _ in self.tables):
                raise JetidError(f"two runs are called '{name}': pass (name, data) pairs to name them apart")
            self.tables.append((name, _columns(data)))
            path = name
        return dict(path=path, **load) if load else path


def _items(value: Any) -> Tuple[List[Any], bool]:
    """The runs of one role: a list of runs, or one run (a ``(name, data)`` pair is one run)."""
    pair = isinstance(value, tuple) and len(value) == 2 and isinstance(value[0], str)
    many = isinstance(value, (list, tuple)) and not pair
    return (list(value) if many else [value]), many


def _project(runs: Mapping[str, Any], settings: Mapping[str, Any], named: _Runs) -> Dict[str, Any]:
    project: Dict[str, Any] = {}
    for role, value in runs.items():
        key = ROLES.get(role)
        if key is None:
            raise JetidError(f"unknown run role '{role}' (roles: {', '.join(sorted(set(ROLES)))})")
        items, many = _items(value)
        names = [named.entry(item, role if len(items) == 1 else f"{role}_{i + 1}") for i, item in enumerate(items)]
        project[key] = names if key in ("validate", "held_out") or (key == "ident" and many) else names[0]
        if key in ("chirp", "steady") and len(names) != 1:
            raise JetidError(f"the {role} run is one run, got {len(names)}")
    load = dict(settings.get("load", {}))
    for key, value in settings.items():
        if key in LOAD_KEYS:
            load[key] = value
        elif key != "load":
            project[key] = value
    if load:
        project["load"] = load
    return project


# --- models ----------------------------------------------------------------------------------


class Model:
    """A gray-box model of every output: what model.json holds, with the runs it was identified
    from when :func:`identify` built it (then :meth:`diagnose` and :meth:`add_effect` work)."""

    def __init__(self, model_json: str, session: Any = None, source: str = "model.json") -> None:
        self._json = model_json
        self._session = session
        self._source = source
        self.data: Dict[str, Any] = json.loads(model_json)
        """model.json as a dict."""

    def __repr__(self) -> str:
        outputs = ", ".join(self.outputs)
        return f"<jetid.Model of {outputs} from {self.input} every {self.dt_secs} s>"

    @property
    def outputs(self) -> List[str]:
        """The modelled outputs, in order."""
        return [o["name"] for o in self.data["outputs"]]

    @property
    def input(self) -> str:
        """The input signal's name."""
        return self.data["input"]["name"]

    @property
    def dt_secs(self) -> float:
        """The sample time, s."""
        return float(self.data["dt_secs"])

    @property
    def notes(self) -> List[str]:
        """What reading the runs and building the model said (empty for a loaded model)."""
        return list(self._session.notes()) if self._session is not None else []

    def to_json(self) -> str:
        """model.json's text."""
        return self._json

    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Write model.json to ``path`` (the file ``jetid predict`` and ``jetid export`` read)."""
        _jetid.save_model(self._json, os.fspath(path))

    def predict(
        self,
        data: RunData,
        initial_state: str = "steady",
        *,
        name: str = "run",
        strict: bool = False,
        **load: Any,
    ) -> pd.DataFrame:
        """What ``jetid predict`` writes for the run ``data``: time_s, the input and every output.

        ``initial_state`` is ``"steady"`` (the steady state of the first input sample) or
        ``"estimated"`` (fitted to the first seconds of the measured outputs, which the run must
        hold). ``load`` takes a project's ``[load]`` keys (``map``, ``sample_time``, ``window``, …).
        An input outside the identified range is said with a warning, or refused with
        ``strict=True``.
        """
        if isinstance(data, (str, os.PathLike)):
            name, table = os.fspath(data), None
        else:
            table = _columns(data)
        columns, coverage = _jetid.predict(self._json, name, table, json.dumps(load), initial_state, strict)
        if coverage:
            import warnings

            warnings.warn(coverage, stacklevel=2)
        return _frame(columns)

    def _needs_session(self, what: str) -> Any:
        if self._session is None:
            raise JetidError(
                f"{what} needs the runs the model was identified from; a model loaded from a file has none: "
                "build it with jetid.identify"
            )
        return self._session

    def diagnose(self, validation: Optional[Union[RunData, Sequence[RunData]]] = None) -> pd.DataFrame:
        """What each output's model still lacks: every structural refinement and catalog effect
        tried, best first (report.json's ``diagnosis``), judged on the identification's validation
        runs or on ``validation``. One row per output and trial; ``.attrs["notes"]`` holds the
        notes."""
        session = self._needs_session("diagnose")
        if validation is None:
            result = session.diagnose()
        else:
            named = _Runs()
            items, _ = _items(validation)
            paths = [named.entry(v, f"validation_{i + 1}") for i, v in enumerate(items)]
            if any(not isinstance(p, str) for p in paths):
                raise JetidError("diagnose reads its validation runs with the model's load options: pass data, not jetid.Run")
            result = session.diagnose(paths, named.tables)
        by_output = json.loads(result)
        rows = [dict(output=r["output"], **entry) for r in by_output for entry in r["entries"]]
        frame = pd.DataFrame(rows)
        frame.attrs["notes"] = [n for r in by_output for n in r["notes"]]
        return frame

    def add_effect(self, effect: str) -> "Model":
        """A new model with the catalog effect ``effect`` added after the model's own effects and
        refitted (``jetid --batch --add-effect EFFECT``); this model is left as it is."""
        session = self._needs_session("add_effect")
        new = session.add_effect(effect)
        return Model(new.model_json(), new, self._source)

    def operating_points(self) -> pd.DataFrame:
        """Each output's local linear models across the identified range (and at the steady run's
        plateau), with their 95 % intervals where the model holds a covariance: report.json's
        ``operating_points``, one row per output and point. ``.attrs["continuous"]`` holds each
        output's continuous-time linear block, ``.attrs["notes"]`` what could not be computed. A
        loaded model carries no runs: its points span its whole input range."""
        if self._session is not None:
            result = json.loads(self._session.operating_points())
        else:
            result = json.loads(_jetid.model_operating_points(self._json))
        rows = [dict(output=r["output"], **p) for r in result for p in r["points"]]
        frame = pd.json_normalize(rows) if rows else pd.DataFrame()
        frame.attrs["continuous"] = {r["output"]: r["continuous"] for r in result}
        frame.attrs["notes"] = [n for r in result for n in r["notes"]]
        return frame

    def to_control(self) -> types.ModuleType:
        """The model as ``jetid export --format python`` writes it, imported: ``TF[output]`` is the
        linear block as a ``control.TransferFunction``, ``operating_point(output, u)`` the local
        model there, ``simulate(u, aux, measured)`` the whole model, ``DT`` the sample time (needs
        numpy; python-control when ``TF`` or ``operating_point`` is used)."""
        code = _jetid.export_python(self._json, self._source)
        module = types.ModuleType("jetid_model")
        module.__file__ = f"<jetid export of {self._source}>"
        exec(compile(code, module.__file__, "exec"), module.__dict__)
        return module


def load_model(path: Union[str, "os.PathLike[str]"]) -> Model:
    """The model.json at ``path``, checked as ``jetid predict`` checks it."""
    return Model(_jetid.load_model(os.fspath(path)), None, os.fspath(path))


def identify(runs: Mapping[str, Any], **settings: Any) -> Model:
    """Identify every output from ``runs`` as ``jetid --batch`` builds model.json.

    ``runs`` maps a role (``ident``, ``validate``, ``held_out``, ``chirp``, ``steady``; also
    ``identification`` and ``validation``) to a run or, for ``ident`` (joined end to end),
    ``validate`` and ``held_out``, a list of runs. A run is a data frame, a mapping of column names
    to arrays, a ``(name, data)`` pair, or a file path; it is read exactly as a run file with its
    columns would be (the default roles: ``time_s``, ``fuel_flow_gph``, the outputs by name).
    Runs are named by role unless named (a pair, or ``df.attrs["name"]``).

    ``settings`` are a project file's keys: ``outputs``, ``add_effects``, ``auto_effects``,
    ``steps_from``, ``clusters_from``, ``output={name: {na, nb, static_order, …}}``, and the
    ``[load]`` keys (``map``, ``sample_time``, ``window``, ``quality``, ``resample``,
    ``invalid``, ``units``) directly or as ``load={…}``.
    """
    named = _Runs()
    project = _project(runs, settings, named)
    session = _jetid.identify(json.dumps(project), named.tables)
    return Model(session.model_json(), session, "jetid.identify")


# --- the batch -------------------------------------------------------------------------------


class Report:
    """What ``jetid --batch`` wrote: report.json as a dict (:attr:`data`), the model and, when an
    ``out`` folder was given, where the files are (figures included)."""

    def __init__(self, data: Dict[str, Any], model: Model, out: Optional[str]) -> None:
        self.data = data
        self.model = model
        self.out = out

    def __repr__(self) -> str:
        return f"<jetid.Report of {', '.join(self.data.get('outputs', {}))}>"

    def __getitem__(self, key: str) -> Any:
        return self.data[key]

    @property
    def notes(self) -> List[str]:
        """report.json's ``diagnostics``: what the batch said in words."""
        return list(self.data.get("diagnostics", []))

    @property
    def metrics(self) -> pd.DataFrame:
        """Every model's metrics on every scored run: one row per output, model and run."""
        rows = []
        for output, report in self.data["outputs"].items():
            for kind, by_run in report["models"].items():
                for run, metrics in by_run.items():
                    rows.append(dict(output=output, model=kind, run=run, **metrics))
        return pd.DataFrame(rows)


def batch(
    project: Optional[Union[str, "os.PathLike[str]"]] = None,
    out: Optional[Union[str, "os.PathLike[str]"]] = None,
    *args: str,
    quiet: bool = True,
) -> Report:
    """``jetid --batch [PROJECT] --out OUT [ARGS...]``: the whole pipeline, the same files.

    Without ``out`` the files go to a temporary folder that is removed afterwards (the report and
    the model are returned). ``args`` are further command-line options (``"--add-effect",
    "thermal_soak"``); ``quiet=False`` prints the stage lines on stderr.
    """
    with tempfile.TemporaryDirectory(prefix="jetid-") as scratch:
        folder = os.fspath(out) if out is not None else os.path.join(scratch, "out")
        argv = ["--batch"] + ([os.fspath(project)] if project is not None else []) + ["--out", folder]
        argv += ["--quiet"] if quiet else []
        _jetid.cli(argv + [str(a) for a in args])
        with open(os.path.join(folder, "report.json"), encoding="utf-8") as f:
            data = json.load(f)
        model = load_model(os.path.join(folder, "model.json"))
    return Report(data, model, folder if out is not None else None)


# --- the fleet -------------------------------------------------------------------------------


# The fleet table's text columns; `diagnosed` is a bool, the rest are numbers.
_FLEET_TEXT = {"engine", "run", "date", "output", "effects", "flag"}


def _table(result: str) -> pd.DataFrame:
    parsed = json.loads(result)
    frame = pd.DataFrame(parsed["rows"], columns=parsed["columns"])
    for column in parsed["columns"]:
        if column == "diagnosed":
            frame[column] = frame[column].astype(bool)
        elif column not in _FLEET_TEXT:
            frame[column] = frame[column].astype("float64")
    return frame


def fleet(manifest: Union[str, "os.PathLike[str]"], out: Optional[Union[str, "os.PathLike[str]"]] = None) -> pd.DataFrame:
    """``jetid fleet MANIFEST``: every run of every engine against its reference, as fleet.csv's
    table (one row per run and output; NaN where the CSV cell is empty). With ``out`` the files
    (fleet.csv, fleet.parquet, report.md, trend figures) are written there too."""
    out_path = os.fspath(out) if out is not None else None
    return _table(_jetid.fleet(os.fspath(manifest), out_path))


def fleet_engines(manifest: Union[str, "os.PathLike[str]"]) -> List[Tuple[str, List[str]]]:
    """Every engine of the manifest with its runs' names, in the manifest's (trend) order."""
    parsed = json.loads(_jetid.fleet_engines(os.fspath(manifest)))
    return [(e["engine"], list(e["runs"])) for e in parsed["engines"]]


def fleet_reference(manifest: Union[str, "os.PathLike[str]"], engine: str) -> str:
    """Engine ``engine``'s reference (its model.json read, or its project identified), as text to
    hand to :func:`score_run` (one task per engine on a distributed engine)."""
    return _jetid.fleet_reference(os.fspath(manifest), engine)


class RunScore:
    """One run scored against its engine's reference: its errors, health deltas with intervals
    and starvation stretches (:attr:`data`), as :func:`score_run` returns it. Picklable: it holds
    text."""

    def __init__(self, engine: str, run: str, json_text: str) -> None:
        self.engine = engine
        self.run = run
        self.json = json_text

    def __repr__(self) -> str:
        return f"<jetid.RunScore of engine {self.engine!r}, run {self.run!r}>"

    def __reduce__(self) -> Tuple[Any, Tuple[str, str, str]]:
        return (RunScore, (self.engine, self.run, self.json))

    @property
    def data(self) -> Dict[str, Any]:
        return json.loads(self.json)


def score_run(
    manifest: Union[str, "os.PathLike[str]"], engine: str, run: str, reference: Optional[str] = None
) -> RunScore:
    """Run ``run`` of engine ``engine`` scored against the engine's reference (from
    :func:`fleet_reference`; built here when not given): the per-run function a distributed engine
    calls, one task per run. :func:`fleet_table` gathers the scores."""
    manifest = os.fspath(manifest)
    if reference is None:
        reference = fleet_reference(manifest, engine)
    return RunScore(engine, run, _jetid.fleet_score(manifest, engine, run, reference))


def fleet_table(
    manifest: Union[str, "os.PathLike[str]"], references: Mapping[str, str], scores: Iterable[RunScore]
) -> pd.DataFrame:
    """The table of :func:`fleet` from every engine's reference and every run's score, in any
    order: each engine's normal band is judged across its runs, the runs it screens diagnosed
    against the reference (here, one after another: a few per cent of the runs), then the rows and
    flags made as ``jetid fleet`` makes them."""
    triples = [(s.engine, s.run, s.json) for s in scores]
    return _table(_jetid.fleet_rows(os.fspath(manifest), list(references.items()), triples))
