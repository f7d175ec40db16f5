"""A designed experiment mapped over two Dask worker processes merges to the bytes of
`crest study` on one machine."""

import json

import pytest

import crest
from conftest import tiny_design

distributed = pytest.importorskip("dask.distributed")


def test_two_worker_processes_give_the_single_process_study(cli, tmp_path):
    d = tiny_design(tmp_path)
    out = tmp_path / "cli"
    p = cli("study", d, "-o", out, "--json")
    assert p.returncode == 0, p.stderr

    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
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
