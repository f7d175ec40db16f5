"""Run a crest designed experiment over Dask workers and write the files `crest study` writes.

    python python/examples/dask_study.py DESIGN.toml OUT_DIR [--workers N] [--address URL]

Without --address a LocalCluster of N worker processes (one thread each) is started; with
it, an existing scheduler is used. For Slurm use dask_jobqueue.SLURMCluster instead of
LocalCluster (docs/cluster.md): the rest of the script is the same.
"""

import argparse
import time

import crest
from dask.distributed import Client, LocalCluster


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("design")
    ap.add_argument("output")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--address", default=None)
    args = ap.parse_args()

    tasks = crest.study_tasks(args.design)
    started = time.perf_counter()
    if args.address:
        cluster = None
        client = Client(args.address)
    else:
        cluster = LocalCluster(
            n_workers=args.workers, threads_per_worker=1, processes=True,
            dashboard_address=None,
        )
        client = Client(cluster)
    ready = time.perf_counter()
    try:
        results = client.gather(client.map(crest.run_task, tasks, pure=False))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    done = time.perf_counter()
    study = crest.merge(results, output=args.output)
    failed = [r["run"] for r in results if r["error"]]
    print(
        f"{len(tasks)} runs on {args.workers if not args.address else args.address}: "
        f"cluster {ready - started:.2f} s, tasks {done - ready:.2f} s, "
        f"{len(failed)} failed; wrote {', '.join(sorted(study['files']))} into {args.output}"
    )


if __name__ == "__main__":
    main()
