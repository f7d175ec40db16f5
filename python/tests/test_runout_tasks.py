"""A run-out sweep split into case tasks (`crest.runout_tasks`), each task pickled and run on
its own, merges to the bytes `crest runout` writes on one process; so do the shard files of
`crest runout --shard K/N`."""

import json
import pickle

import crest
from conftest import ROOT

STUDY = ROOT / "samples" / "studies" / "runout.toml"


def test_runout_tasks_merge_to_the_bytes_of_crest_runout(cli, tmp_path):
    out = tmp_path / "cli"
    p = cli("runout", STUDY, "-o", out, "--json")
    assert p.returncode == 0, p.stderr
    single = json.loads(p.stdout)
    names = sorted(x.name for x in out.iterdir())
    assert len(names) == 7

    tasks = crest.runout_tasks(str(STUDY))
    assert len(tasks) == single["cases"] == 78     # one task per case by default
    assert {t["kind"] for t in tasks} == {"runout-cases"}
    results = [pickle.loads(pickle.dumps(crest.run_task(pickle.loads(pickle.dumps(t)))))
               for t in tasks]
    assert [[c["case"] for c in r["cases"]] for r in results] == [[i] for i in range(78)]
    merged = crest.merge(list(reversed(results)), output=tmp_path / "merged")
    assert merged["rows"] == single["rows"]
    assert (merged["rule"], merged["x"], merged["tool"]) == (
        single["rule"], single["x"], single["tool"])
    assert sorted(merged["files"]) == names
    for name in names:
        assert merged["files"][name] == (out / name).read_bytes(), name
        assert (tmp_path / "merged" / name).read_bytes() == (out / name).read_bytes(), name

    # Fewer, larger tasks: task k holds cases k-1, k-1+5, …
    five = crest.runout_tasks(str(STUDY), tasks=5)
    results = [crest.run_task(t) for t in five]
    assert [c["case"] for c in results[1]["cases"]] == list(range(1, 78, 5))
    assert crest.merge(results)["files"] == merged["files"]

    # A missing task is named.
    try:
        crest.merge(results[:4])
    except crest.CrestError as e:
        assert "1 of 5 shards are missing: 5" in str(e)
    else:
        raise AssertionError("a missing shard was accepted")


def test_runout_shard_files_merge_in_python(cli, tmp_path):
    out = tmp_path / "cli"
    assert cli("runout", STUDY, "-o", out).returncode == 0
    lines = []
    for k in (1, 2):
        p = cli("runout", STUDY, "--shard", f"{k}/2", "-o", tmp_path / "shards")
        assert p.returncode == 0, p.stderr
        lines += (tmp_path / "shards" / f"shard-{k}-of-2.jsonl").read_text().splitlines()
    merged = crest.merge(lines)
    for name, data in merged["files"].items():
        assert data == (out / name).read_bytes(), name
