"""The fleet on a Dask cluster: one task per engine's reference, one task per run, the table
gathered on the client.

``fleet(manifest, client)`` returns the table ``jetid fleet`` writes, row for row: the tasks call
:func:`jetid.fleet_reference` and :func:`jetid.score_run`, whose results cross between processes as
text (numbers round-trip exactly), and :func:`jetid.fleet_table` judges each engine's runs against
its band on the client. The workers read the runs' files themselves, so every worker must see the
manifest's paths (a shared file system on a real cluster) and have the ``jetid`` package installed.
"""
from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Union

import pandas as pd

import jetid


def _score(manifest: str, engine: str, run: str, reference: str) -> jetid.RunScore:
    return jetid.score_run(manifest, engine, run, reference)


def fleet(
    manifest: Union[str, "os.PathLike[str]"],
    client: Any,
    *,
    progress: Optional[Any] = None,
) -> pd.DataFrame:
    """Every run of every engine of ``manifest`` scored on the Dask cluster of ``client`` (a
    ``dask.distributed.Client``): one task per engine builds its reference, one task per run scores
    it against that reference, and the client gathers the table. ``progress``, when given, is
    called with (tasks done, tasks in all) as the runs finish."""
    from dask.distributed import as_completed

    path = os.path.abspath(os.fspath(manifest))
    engines = jetid.fleet_engines(path)
    references = {
        engine: client.submit(jetid.fleet_reference, path, engine, key=f"jetid-reference-{i}", pure=False)
        for i, (engine, _) in enumerate(engines)
    }
    futures: List[Any] = []
    for i, (engine, runs) in enumerate(engines):
        for k, run in enumerate(runs):
            key = f"jetid-score-{i}-{k}"
            futures.append(client.submit(_score, path, engine, run, references[engine], key=key, pure=False))
    scores: List[jetid.RunScore] = []
    for done, future in enumerate(as_completed(futures), start=1):
        scores.append(future.result())
        if progress is not None:
            progress(done, len(futures))
    gathered: Dict[str, str] = client.gather(references)
    return jetid.fleet_table(path, gathered, scores)
