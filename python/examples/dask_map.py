"""Simulate a crest part map over Dask workers and write the PLY `crest simulate` writes.

    python python/examples/dask_map.py PATH.cls PART.stl TOOL.toml MAP_MM OUT.ply \
        [--tasks N] [--workers N] [--address URL] [--region X0,Y0,Z0,X1,Y1,Z1]
        [--grid-um G] [--fz-mm F] [--model M]

The map is cut into N tile tasks (task k: cells k, k+N, …); every worker must see the path,
part and tool files at the paths given (absolute in the tasks). Without --address a
LocalCluster of the given number of worker processes (one thread each) is started; with it,
an existing scheduler is used. For Slurm use dask_jobqueue.SLURMCluster instead of
LocalCluster (docs/cluster.md): the rest of the script is the same.
"""

import argparse
import time

import crest
from dask.distributed import Client, LocalCluster


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("path")
    ap.add_argument("part")
    ap.add_argument("tool")
    ap.add_argument("map_mm", type=float)
    ap.add_argument("output")
    ap.add_argument("--tasks", type=int, default=16)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--address", default=None)
    ap.add_argument("--region", default=None, help="X0,Y0,Z0,X1,Y1,Z1 (mm)")
    ap.add_argument("--grid-um", type=float, default=None)
    ap.add_argument("--fz-mm", type=float, default=None)
    ap.add_argument("--model", default="ice")
    args = ap.parse_args()

    tasks = crest.map_tasks(
        args.path, tasks=args.tasks, map_mm=args.map_mm, part=args.part, tool=args.tool,
        region=tuple(float(v) for v in args.region.split(",")) if args.region else None,
        grid_um=args.grid_um, fz_mm=args.fz_mm, model=args.model,
    )
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
    part_map = crest.merge(results, output=args.output)
    print(
        f"{len(tasks)} tasks on {args.workers if not args.address else args.address}: "
        f"cluster {ready - started:.2f} s, tasks {done - ready:.2f} s; "
        f"{len(part_map.height_um)} points, {part_map.nodes_cut} cut; wrote {args.output}"
    )


if __name__ == "__main__":
    main()
