"""Time a 64-run crest study: in one process (tasks one after another) against Dask
LocalClusters of 1 and 2 worker processes, plus Dask's own cost per task (no-op tasks).
Checks that every merge gives the bytes of the single-process one.

    python reports/dask-study/bench.py reports/dask-study/design-64.toml
"""

import sys
import time

import crest
from dask.distributed import Client, LocalCluster


def noop(task):
    return task["run"]


def cpu():
    return time.process_time()


def main() -> None:
    design = sys.argv[1]
    tasks = crest.study_tasks(design)
    t0, c0 = time.perf_counter(), cpu()
    serial = [crest.run_task(t) for t in tasks]
    t_serial, c_serial = time.perf_counter() - t0, cpu() - c0
    ref = crest.merge(serial)["files"]
    print(f"tasks {len(tasks)}; one process, in order: {t_serial:.2f} s "
          f"({t_serial / len(tasks) * 1e3:.0f} ms per run), CPU {c_serial:.2f} s")
    for workers in (1, 2):
        t0 = time.perf_counter()
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            t_up = time.perf_counter() - t0
            t1 = time.perf_counter()
            client.gather(client.map(noop, tasks, pure=False))
            t_noop = time.perf_counter() - t1
            before = client.run(cpu)
            t1 = time.perf_counter()
            results = client.gather(client.map(crest.run_task, tasks, pure=False))
            t_run = time.perf_counter() - t1
            after = client.run(cpu)
            c_run = sum(after[w] - before[w] for w in after)
        merged = crest.merge(results)["files"]
        same = all(merged[k] == ref[k] for k in ref)
        print(f"dask {workers} worker(s): start {t_up:.2f} s, 64 no-op tasks {t_noop:.3f} s "
              f"({t_noop / len(tasks) * 1e3:.1f} ms/task), study {t_run:.2f} s, "
              f"speed-up {t_serial / t_run:.2f}x, "
              f"overhead/task {(t_run - t_serial / workers) / (len(tasks) / workers) * 1e3:.0f} ms; "
              f"worker CPU {c_run:.2f} s ({(c_run - c_serial) / len(tasks) * 1e3:+.1f} ms/task vs one process); "
              f"merged bytes identical: {same}")


if __name__ == "__main__":
    main()
