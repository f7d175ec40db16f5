"""A part map split into tile tasks (`crest.map_tasks`), each task pickled and run on its
own, merges to the PLY bytes of `crest simulate --map-mm` on one process."""

import pickle

import numpy as np

import crest
from conftest import ROOT

BALL = ROOT / "samples" / "synth" / "ball-r5.toml"


def test_map_tasks_merge_to_the_single_process_ply(cli, tmp_path):
    cls, stl = tmp_path / "plane.cls", tmp_path / "plane.stl"
    p = cli(
        "synth", "plane", "--tool", BALL, "--stepover-mm", "0.4", "--stepover-along-surface",
        "--size-mm", "4,4", "--point-step-mm", "0.05", "--feed-mm-min", "1000",
        "--rpm", "20000", "--part-tol-um", "0.01", "-o", cls, "--part-stl", stl,
    )
    assert p.returncode == 0, p.stderr
    single = tmp_path / "single.ply"
    p = cli(
        "simulate", cls, "--tool", BALL, "--part", stl, "--model", "dome", "--grid-um", "10",
        "--fz-mm", "0.05", "--map-mm", "0.004", "--region=-0.3,-0.3,-0.5,0.3,0.3,0.5",
        "-o", single,
    )
    assert p.returncode == 0, p.stderr

    tasks = crest.map_tasks(
        str(cls), tasks=3, map_mm=0.004, part=str(stl), tool=str(BALL), model="dome",
        grid_um=10.0, fz_mm=0.05, region=(-0.3, -0.3, -0.5, 0.3, 0.3, 0.5),
    )
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
