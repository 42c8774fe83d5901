"""A fleet on a Dask cluster: one task per engine's reference, one task per run, the table
gathered on the client; it equals `jetid fleet MANIFEST`'s fleet.csv row for row.

    python examples/python/fleet_dask.py MANIFEST [--workers N] [--scheduler ADDRESS] [--out table.parquet]

Without --scheduler a LocalCluster of N worker processes (one thread each) runs on this machine.
With --scheduler the client joins a running cluster (dask-jobqueue on a batch system, the Dask
Kubernetes operator, `dask scheduler` plus `dask worker` by hand): every worker needs the jetid
package and the manifest's paths (a shared file system). See the README's "From Python".
"""
import argparse
import time

import jetid
from jetid.distributed import fleet


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("manifest")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of the local cluster")
    parser.add_argument("--scheduler", help="address of a running scheduler (tcp://host:8786)")
    parser.add_argument("--out", help="write the table as parquet (needs pyarrow)")
    args = parser.parse_args()

    from dask.distributed import Client, LocalCluster

    if args.scheduler:
        client, cluster = Client(args.scheduler), None
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        started = time.perf_counter()
        last = [0.0]

        def progress(done: int, total: int) -> None:
            if time.perf_counter() - last[0] > 1 or done == total:
                last[0] = time.perf_counter()
                print(f"[{last[0] - started:6.1f} s] {done} of {total} runs scored", flush=True)

        table = fleet(args.manifest, client, progress=progress)
        elapsed = time.perf_counter() - started
        workers = len(client.scheduler_info()["workers"])
        flagged = table[table.flag != ""][["engine", "run"]].drop_duplicates()
        runs = len(table[["engine", "run"]].drop_duplicates())
        print(f"{runs} runs of {table.engine.nunique()} engines on {workers} workers in {elapsed:.1f} s; "
              f"{len(flagged)} runs flagged")
        print(table[table.flag != ""][["engine", "run", "output", "flag"]].to_string(index=False))
        if args.out:
            table.to_parquet(args.out)
            print(f"wrote {args.out}")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


if __name__ == "__main__":
    main()
