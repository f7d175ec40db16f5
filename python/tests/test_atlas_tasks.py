"""A roughness atlas split into patch tasks (`crest.atlas_tasks`), each task pickled and run
on its own, merges to the table `crest atlas` writes on one process."""

import pickle

import crest
from conftest import ROOT


def test_atlas_tasks_merge_to_the_single_process_table(cli, tmp_path):
    cls = ROOT / "samples" / "synth" / "plane-trial3.cls"
    args = ["--teeth", "2", "--rpm", "10000", "--every-mm", "3", "--grid-um", "20"]
    single = tmp_path / "single.csv"
    p = cli("atlas", cls, *args, "-o", single)
    assert p.returncode in (0, 1), p.stderr

    tasks = crest.atlas_tasks(str(cls), tasks=2, every_mm=3.0, teeth=2, rpm=10000.0,
                              grid_um=20.0)
    assert [t["kind"] for t in tasks] == ["atlas-patches"] * 2
    results = [pickle.loads(pickle.dumps(crest.run_task(pickle.loads(pickle.dumps(t)))))
               for t in tasks]
    merged = crest.merge(list(reversed(results)), output=tmp_path / "merged.csv")
    assert (tmp_path / "merged.csv").read_bytes() == single.read_bytes()
    assert merged["files"]["atlas.csv"] == single.read_bytes()
    assert len(merged["rows"]) == len(single.read_text().splitlines()) - 1
