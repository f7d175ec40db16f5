"""A part map split into tile tasks (`crest.map_tasks`), each task pickled and run on its
own, merges to the PLY bytes of `crest simulate --map-mm` on one process."""

import pickle

import numpy as np

import crest
from conftest import MAP_ARGS, MAP_KW, plane_part


def test_map_tasks_merge_to_the_single_process_ply(cli, tmp_path):
    cls, stl = plane_part(cli, tmp_path)
    single = tmp_path / "single.ply"
    p = cli("simulate", cls, "--part", stl, *MAP_ARGS, "-o", single)
    assert p.returncode == 0, p.stderr

    tasks = crest.map_tasks(str(cls), tasks=3, part=str(stl), **MAP_KW)
    assert [t["kind"] for t in tasks] == ["map-tiles"] * 3
    results = [pickle.loads(pickle.dumps(crest.run_task(pickle.loads(pickle.dumps(t)))))
               for t in tasks]
    merged = crest.merge(list(reversed(results)), output=tmp_path / "merged.ply")
    assert (tmp_path / "merged.ply").read_bytes() == single.read_bytes()
    assert isinstance(merged, crest.PartMap)
    assert merged.points.shape == (22500, 3)
    assert merged.nodes_cut == int(np.isfinite(merged.height_um).sum())

    # A missing task is named.
    try:
        crest.merge(results[:2])
    except crest.CrestError as e:
        assert "1 of 3 shards are missing: 3" in str(e)
    else:
        raise AssertionError("a missing shard was accepted")
