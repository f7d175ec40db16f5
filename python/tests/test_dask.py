"""A designed experiment and a part map mapped over two Dask worker processes merge to the
bytes of `crest study` and `crest simulate --map-mm` on one machine."""

import json

import pytest

import crest
from conftest import MAP_ARGS, MAP_KW, plane_part, tiny_design

distributed = pytest.importorskip("dask.distributed")


@pytest.fixture(scope="module")
def client():
    """A client of a LocalCluster of two worker processes (one thread each)."""
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        client.wait_for_workers(2)
        yield client


def test_two_worker_processes_give_the_single_process_study(cli, client, tmp_path):
    d = tiny_design(tmp_path)
    out = tmp_path / "cli"
    p = cli("study", d, "-o", out, "--json")
    assert p.returncode == 0, p.stderr

    tasks = crest.study_tasks(str(d))
    futures = client.map(crest.run_task, tasks, pure=False)
    results = client.gather(futures)
    # Both workers took part.
    who = client.run(lambda: 1)
    assert len(who) == 2

    merged = crest.merge(results)
    assert merged["runs"] == json.loads(p.stdout)["runs"]
    for name in ("runs.csv", "effects.csv", "effects.svg", "effects-feed_mm_min.svg"):
        assert merged["files"][name] == (out / name).read_bytes(), name


def test_two_worker_processes_give_the_single_process_part_map(cli, client, tmp_path):
    cls, stl = plane_part(cli, tmp_path)
    single = tmp_path / "single.ply"
    p = cli("simulate", cls, "--part", stl, *MAP_ARGS, "-o", single)
    assert p.returncode == 0, p.stderr

    tasks = crest.map_tasks(str(cls), tasks=4, part=str(stl), **MAP_KW)
    # Tasks 1 and 3 on one worker process, 2 and 4 on the other (so that both take part
    # whatever the scheduler would prefer).
    workers = sorted(client.scheduler_info()["workers"])
    assert len(workers) == 2
    futures = [
        client.submit(crest.run_task, t, workers=[workers[i % 2]], pure=False)
        for i, t in enumerate(tasks)
    ]
    results = client.gather(futures)
    ran_on = {w for ws in client.who_has(futures).values() for w in ws}
    assert ran_on == set(workers), ran_on

    merged = crest.merge(results, output=tmp_path / "merged.ply")
    assert (tmp_path / "merged.ply").read_bytes() == single.read_bytes()
    assert isinstance(merged, crest.PartMap)
