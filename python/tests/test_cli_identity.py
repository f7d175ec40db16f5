"""The package against the crest command line on the same inputs: the same numbers, bit for
bit where the CLI prints full precision (--json), the same bytes where both write files, and
the same error messages."""

import json
import math
import pickle

import numpy as np
import pytest

import crest
from conftest import ROOT, tiny_design

TRIAL3 = ROOT / "samples" / "synth" / "plane-trial3.cls"
TORUS = ROOT / "samples" / "synth" / "torus-r5-rc1.5.toml"
WINDOW = (0.0, 0.0, 0.27, 0.2)


def norm(text: str) -> str:
    """A message without white space and the frame of the CLI's diagnostics (which wraps
    long lines, even inside a path)."""
    return "".join(text.replace("│", " ").split())


@pytest.fixture(scope="module")
def window_map():
    return crest.simulate(
        TRIAL3, tool=TORUS, model="ice", dtheta_deg=2.0, grid_um=10.0, window=WINDOW
    )


def test_read_path_has_the_postures_of_inspect(cli_json):
    paths = crest.read_path(TRIAL3)
    j = cli_json("inspect", TRIAL3)
    assert len(paths) == len(j["paths"])
    for p, q in zip(paths, j["paths"]):
        n = p["tip"].shape[0]
        assert p["tip"].shape == (n, 3) and p["axis"].shape == (n, 3)
        assert len(p["motion"]) == n and p["line"].shape == (n,)
        assert np.allclose(np.linalg.norm(p["axis"], axis=1), 1.0, atol=1e-9)
        assert p["name"] == q["name"]
        assert n == q["postures"], (n, q)
        with_contact = int(np.sum(~np.isnan(p["contact"][:, 0])))
        assert with_contact == q["contact_postures"]
        assert sum(m == "cut" for m in p["motion"]) == q["cutting_postures"]


def test_window_writes_the_bytes_of_crest_simulate(cli, window_map, tmp_path):
    assert (window_map.nx, window_map.ny) == (28, 21)
    assert window_map.z_um.shape == (21, 28)
    assert window_map.dx_um == 10.0 and window_map.origin_mm == (0.0, 0.0)
    for ext, write in (
        ("gsf", window_map.to_gsf),
        ("sdf", window_map.to_sdf),
        ("csv", window_map.to_csv),
    ):
        ours = tmp_path / f"py.{ext}"
        theirs = tmp_path / f"cli.{ext}"
        write(ours)
        p = cli(
            "simulate", TRIAL3, "--tool", TORUS, "--model", "ice", "--dtheta-deg", "2",
            "--grid-um", "10", "--window", ",".join(map(str, WINDOW)), "-o", theirs,
        )
        assert p.returncode == 0, p.stderr
        assert ours.read_bytes() == theirs.read_bytes(), ext


def test_metrics_are_the_cli_json_to_the_bit(cli_json, window_map, tmp_path):
    sdf = tmp_path / "w.sdf"
    window_map.to_sdf(sdf)
    j = cli_json("metrics", sdf, "--level", "plane")
    ours = crest.metrics(sdf, level="plane")
    assert {"Sa", "Sq", "Sz", "Ssk", "Sku"} <= set(ours)
    assert set(ours) <= set(j)
    for k, v in ours.items():
        w = j[k]
        if w is None:
            assert math.isnan(v), k
        else:
            assert v == w, (k, v, w)  # bit for bit
    # The same on the map in memory (the SDF keeps float64 heights).
    again = window_map.metrics(level="plane")
    read_back = crest.HeightMap.read(sdf)
    assert np.array_equal(read_back.z_um, window_map.z_um, equal_nan=True)
    for k in ours:
        assert again[k] == ours[k] or (math.isnan(again[k]) and math.isnan(ours[k])), k


def test_profile_metrics_match_the_cli(cli_json, window_map, tmp_path):
    sdf = tmp_path / "w.sdf"
    window_map.to_sdf(sdf)
    j = cli_json("metrics", sdf, "--profile", "row:10", "--params", "Ra,Rz,Rq")
    ours = crest.metrics(window_map, "Ra,Rz,Rq", profile="row:10")
    assert ours == {k: j[k] for k in ("Ra", "Rz", "Rq")}


def test_cutter_from_keywords_and_file_agree_and_errors_name_line_and_column(cli, tmp_path):
    a = crest.Cutter.from_toml(TORUS)
    b = crest.Cutter.from_text(a.toml, str(TORUS))
    assert (a.radius_mm, a.teeth) == (b.radius_mm, b.teeth) == (5.0, 1)
    c = crest.Cutter(shape="ball", radius_mm=5.0, teeth=4, helix_deg=30.0)
    assert (c.radius_mm, c.teeth) == (5.0, 4)

    bad = tmp_path / "bad.toml"
    bad.write_text('shape = "ball"\nradius_mm = -5.0\nteeth = 2\nhelix_deg = 0.0\n')
    with pytest.raises(crest.CrestError) as e:
        crest.Cutter.from_toml(bad)
    first = str(e.value).splitlines()[0]
    assert first.startswith(f"{bad}:2:"), first
    assert (e.value.file, e.value.line, e.value.column) == (str(bad), 2, 13)
    p = cli("tool", "--tool", bad, "--lead-deg", "15", "--ap-mm", "0.4", "--fz-mm", "0.05")
    assert p.returncode == 2
    assert norm(first) in norm(p.stderr), (first, p.stderr)
    with pytest.raises(crest.CrestError, match="<keyword arguments>:2:"):
        crest.Cutter(shape="ball", radius_mm=-5.0, teeth=2, helix_deg=0.0)


def test_simulate_errors_are_the_cli_messages(cli, tmp_path):
    bad = tmp_path / "bad.cls"
    bad.write_text("TOOL PATH/A,TOOL,B\nGOTO/1,2\n")
    with pytest.raises(crest.CrestError) as e:
        crest.simulate(bad, tool=TORUS, window=WINDOW, rpm=1000.0, feed_mm_min=100.0)
    first = str(e.value).splitlines()[0]
    p = cli("simulate", bad, "--tool", TORUS, "--window", "0,0,0.27,0.2", "--rpm", "1000",
            "--feed-mm-min", "100", "-o", tmp_path / "x.csv")
    assert p.returncode == 2
    assert norm(first) in norm(p.stderr), (first, p.stderr)
    assert f"{bad}:2:" in first or f"{bad}:2:" in str(e.value), str(e.value)
    assert (e.value.file, e.value.line) == (str(bad), 2), str(e.value)


def test_a_bad_grid_names_the_keyword_here_and_the_flag_on_the_command_line(cli, tmp_path):
    with pytest.raises(crest.CrestError) as e:
        crest.simulate(TRIAL3, tool=TORUS, window=WINDOW, grid_um=-1.0)
    assert str(e.value).startswith("grid_um must be positive, got -1"), str(e.value)
    p = cli("simulate", TRIAL3, "--tool", TORUS, "--window", "0,0,0.27,0.2",
            "--grid-um=-1", "-o", tmp_path / "x.csv")
    assert p.returncode == 2
    assert "--grid-um must be positive, got -1" in p.stderr, p.stderr
    assert not (tmp_path / "x.csv").exists()


def test_study_tasks_merge_to_the_bytes_of_crest_study(cli, tmp_path):
    d = tiny_design(tmp_path)
    out = tmp_path / "cli"
    p = cli("study", d, "-o", out, "--json")
    assert p.returncode == 0, p.stderr
    cli_runs = json.loads(p.stdout)["runs"]

    tasks = crest.study_tasks(str(d))
    assert [t["run"] for t in tasks] == list(range(1, 7))
    # Picklable in and out: plain dicts.
    tasks = [pickle.loads(pickle.dumps(t)) for t in tasks]
    results = [pickle.loads(pickle.dumps(crest.run_task(t))) for t in reversed(tasks)]
    merged = crest.merge(results, output=tmp_path / "py")
    assert merged["runs"] == cli_runs
    for name in ("runs.csv", "effects.csv", "effects.svg", "effects-feed_mm_min.svg"):
        assert merged["files"][name] == (out / name).read_bytes(), name
        assert (tmp_path / "py" / name).read_bytes() == (out / name).read_bytes(), name

    with pytest.raises(crest.CrestError, match="3 of 6 runs are missing: 2, 4, 6"):
        crest.merge(results[1::2])


def test_monte_carlo_study_tasks_merge_to_the_bytes_of_crest_study(cli, tmp_path):
    d = tiny_design(tmp_path)
    out = tmp_path / "cli"
    p = cli("study", d, "-o", out, "--json", "--monte-carlo", "3", "--seed", "5")
    assert p.returncode == 0, p.stderr
    j = json.loads(p.stdout)
    assert j["monte_carlo"]["samples"] == 3 and j["monte_carlo"]["seed"] == 5

    tasks = crest.study_tasks(str(d), monte_carlo=3, seed=5)
    assert all(t["monte_carlo"] == {"samples": 3, "seed": 5} for t in tasks)
    # Tasks without the setting carry no key (old tasks still parse).
    assert "monte_carlo" not in crest.study_tasks(str(d))[0]
    results = [crest.run_task(t) for t in reversed(tasks)]
    assert all(len(r["bands"]) == 4 for r in results)
    merged = crest.merge(results)
    assert merged["runs"] == j["runs"]
    for name in ("runs.csv", "effects.csv"):
        assert merged["files"][name] == (out / name).read_bytes(), name
    assert b"Sz_p5,Sz_p50,Sz_p95" in merged["files"]["runs.csv"]
    with pytest.raises(crest.CrestError, match="at least one sample"):
        crest.study_tasks(str(d), monte_carlo=0)


def test_shard_files_merge_in_python(cli, tmp_path):
    d = tiny_design(tmp_path)
    for k in (1, 2):
        p = cli("study", d, "--shard", f"{k}/2", "-o", tmp_path / "shards")
        assert p.returncode == 0, p.stderr
    lines = []
    for k in (1, 2):
        lines += (tmp_path / "shards" / f"shard-{k}-of-2.jsonl").read_text().splitlines()
    merged = crest.merge(lines)
    p = cli("study", d, "-o", tmp_path / "cli")
    assert p.returncode == 0, p.stderr
    assert merged["files"]["runs.csv"] == (tmp_path / "cli" / "runs.csv").read_bytes()


def test_tool_analysis_is_the_cli_json(cli_json):
    tool = ROOT / "samples" / "tools" / "ball-r5-z4-runout.toml"
    for rule in ("exact", "paper"):
        j = cli_json("tool", "--tool", tool, "--lead-deg", "15", "--ap-mm", "0.4",
                     "--fz-mm", "0.05", "--rule", rule)
        ours = crest.Cutter.from_toml(str(tool)).analyse(15.0, 0.4, 0.05, rule=rule)
        assert ours == j  # every key, every float to the bit


def test_feed_plan_is_the_cli_json(cli_json):
    cls = ROOT / "samples" / "nx" / "nx_iso_header_units_mm.cls"
    machine = ROOT / "samples" / "machines" / "table1_ac.toml"
    j = cli_json("feed", cls, "--machine", machine)
    ours = crest.plan_feed(cls, machine)
    assert len(ours) == len(j["paths"])
    assert sum(p["total_time_s"] for p in ours) == j["total_time_s"]
    for p, q in zip(ours, j["paths"]):
        assert p["name"] == q["name"]
        feeds = [r["feed_mm_min"] for r in q["postures"]]
        assert p["feed_mm_min"].tolist() == feeds
        assert p["t_s"].tolist() == [r["t_s"] for r in q["postures"]]
        assert p["line"].tolist() == [r["line"] for r in q["postures"]]


def test_resample_is_the_cli_csv(cli, tmp_path):
    cls = ROOT / "samples" / "clsf" / "ball_lead15_contact.cls"
    out = tmp_path / "r.csv"
    args = ["--mode", "dtheta", "--fz-mm", "0.05", "--teeth", "4", "--dtheta-deg", "2"]
    p = cli("resample", cls, *args, "-o", out)
    assert p.returncode == 0, p.stderr
    ours = crest.resample(cls, mode="dtheta", fz_mm=0.05, teeth=4, dtheta_deg=2.0)
    lines = out.read_text().splitlines()
    head = lines[0].split(",")
    rows = [line.split(",") for line in lines[1:]]
    assert len(rows) == len(ours["s_mm"]) > 100
    # The CSV prints lengths with 6 decimals, unit vectors and time with 9, feed with 3.
    decimals = {"t_s": 9, "i": 9, "j": 9, "k": 9, "nx": 9, "ny": 9, "nz": 9,
                "fx": 9, "fy": 9, "fz": 9, "feed_mm_min": 3}
    for c, name in enumerate(head):
        printed = np.array([float(r[c]) if r[c] else np.nan for r in rows])
        half = 0.5 * 10.0 ** -decimals.get(name, 6)
        diff = np.abs(ours[name] - printed)
        assert np.all((diff <= half * (1 + 1e-9)) | (np.isnan(printed) & np.isnan(ours[name]))), name
    with pytest.raises(crest.CrestError, match="out of range"):
        crest.resample(cls, mode="fz", fz_mm=0.05, teeth=4, path=9)


def test_simulate_takes_a_cutter_and_writes_the_bytes_of_crest_simulate(cli, tmp_path):
    # The same tool as a Cutter object (read from the file, or built from keywords) and as
    # the tool.toml path given to the CLI: the same GSF bytes.
    cutter = crest.Cutter.from_toml(TORUS)
    args = dict(model="ice", dtheta_deg=2.0, grid_um=10.0, window=WINDOW)
    ours = tmp_path / "py.gsf"
    crest.simulate(TRIAL3, tool=cutter, **args).to_gsf(ours)
    theirs = tmp_path / "cli.gsf"
    p = cli(
        "simulate", TRIAL3, "--tool", TORUS, "--model", "ice", "--dtheta-deg", "2",
        "--grid-um", "10", "--window", ",".join(map(str, WINDOW)), "-o", theirs,
    )
    assert p.returncode == 0, p.stderr
    assert ours.read_bytes() == theirs.read_bytes()
    by_path = tmp_path / "path.gsf"
    crest.simulate(TRIAL3, tool=str(TORUS), **args).to_gsf(by_path)
    assert by_path.read_bytes() == theirs.read_bytes()
    # A cutter built from keywords (two teeth: another surface than the file's tool).
    two = crest.Cutter(shape="torus", radius_mm=5.0, corner_radius_mm=1.5, teeth=2, helix_deg=0.0)
    toml = tmp_path / "two.toml"
    toml.write_text(two.toml)
    kw = tmp_path / "kw.gsf"
    crest.simulate(TRIAL3, tool=two, **args).to_gsf(kw)
    assert kw.read_bytes() != theirs.read_bytes()
    p = cli(
        "simulate", TRIAL3, "--tool", toml, "--model", "ice", "--dtheta-deg", "2",
        "--grid-um", "10", "--window", ",".join(map(str, WINDOW)), "-o", tmp_path / "kw-cli.gsf",
    )
    assert p.returncode == 0, p.stderr
    assert kw.read_bytes() == (tmp_path / "kw-cli.gsf").read_bytes()
    with pytest.raises(TypeError, match="Cutter or the path"):
        crest.simulate(TRIAL3, tool=5, **args)


def test_height_maps_pickle_exactly(window_map, tmp_path):
    z = window_map.z_um.copy()
    z[0, 0] = np.nan  # NaN (not reached) survives too
    m = crest.HeightMap(z, 10.0, 7.5, x0_mm=0.1 + 0.2, y0_mm=-1e-17)
    back = pickle.loads(pickle.dumps(m))
    assert isinstance(back, crest.HeightMap)
    assert back.z_um.tobytes() == m.z_um.tobytes()
    assert (back.nx, back.ny, back.dx_um, back.dy_um, back.origin_mm) == (
        m.nx, m.ny, m.dx_um, m.dy_um, m.origin_mm,
    )
    m.to_gsf(tmp_path / "a.gsf")
    back.to_gsf(tmp_path / "b.gsf")
    assert (tmp_path / "a.gsf").read_bytes() == (tmp_path / "b.gsf").read_bytes()
    w = pickle.loads(pickle.dumps(window_map, protocol=pickle.HIGHEST_PROTOCOL))
    assert w.z_um.tobytes() == window_map.z_um.tobytes()


def test_part_maps_pickle_exactly():
    rng = np.random.default_rng(1)
    pts, nrm, h = rng.normal(size=(5, 3)), rng.normal(size=(5, 3)), rng.normal(size=5)
    h[2] = np.nan
    pm = crest.PartMap(pts, nrm, h, nodes_cut=4)
    back = pickle.loads(pickle.dumps(pm))
    for name in ("points", "normals", "height_um"):
        assert getattr(back, name).tobytes() == getattr(pm, name).tobytes(), name
    assert back.nodes_cut == 4
    with pytest.raises(ValueError, match="shape"):
        crest.PartMap(pts[:4], nrm, h)


def test_swept_model_and_mesh_options_are_the_cli_bytes(cli, tmp_path):
    """`model="swept"` and the speed options (`chord_tol_um`, `band_um`) reach the same code
    as the CLI's `--model swept --chord-tol-um --band-um`."""
    ball = ROOT / "samples" / "synth" / "ball-r5.toml"
    cls = tmp_path / "raster.cls"
    p = cli(
        "synth", "plane", "--tool", ball, "--stepover-mm", "0.4", "--size-mm", "3,3",
        "--point-step-mm", "0.05", "--feed-mm-min", "1000", "--rpm", "20000", "-o", cls,
    )
    assert p.returncode == 0, p.stderr
    for model, extra, kw in (
        ("swept", ["--band-um", "15"], dict(band_um=15.0)),
        ("dome", ["--chord-tol-um", "1"], dict(chord_tol_um=1.0)),
    ):
        theirs = tmp_path / f"cli-{model}.gsf"
        p = cli(
            "simulate", cls, "--tool", ball, "--model", model, "--grid-um", "10",
            "--fz-mm", "0.05", "--window=-0.5,-0.5,0.5,0.5", *extra, "-o", theirs,
        )
        assert p.returncode == 0, p.stderr
        m = crest.simulate(
            cls, tool=str(ball), model=model, grid_um=10.0, fz_mm=0.05,
            window=(-0.5, -0.5, 0.5, 0.5), **kw,
        )
        ours = tmp_path / f"py-{model}.gsf"
        m.to_gsf(ours)
        assert ours.read_bytes() == theirs.read_bytes(), model
    # The keyword is named, as Python spells it (the command line names its flag).
    with pytest.raises(crest.CrestError, match="^chord_tol_um must be between"):
        crest.simulate(cls, tool=str(ball), model="dome", window=(0, 0, 0.1, 0.1), chord_tol_um=0.0)


def test_messages_name_keywords_where_the_cli_names_options(cli, tmp_path):
    """The library names request fields; Python shows its keywords, the command line its
    options, for the same mistakes (no grid; a tool without its tooth count)."""
    ball = ROOT / "samples" / "synth" / "ball-r5.toml"
    cls = tmp_path / "raster.cls"
    p = cli(
        "synth", "plane", "--tool", ball, "--stepover-mm", "0.4", "--size-mm", "3,3",
        "--point-step-mm", "0.05", "--feed-mm-min", "1000", "--rpm", "20000", "-o", cls,
    )
    assert p.returncode == 0, p.stderr
    with pytest.raises(crest.CrestError) as e:
        crest.simulate(cls, tool=str(ball), patch_mm=(1.0, 1.0))
    msg = str(e.value)
    assert "patch_near X,Y,Z or patch_at S_MM" in msg, msg
    assert "‹" not in msg and "--" not in msg, msg
    with pytest.raises(crest.CrestError) as e:
        crest.simulate(cls, tool=str(ball), window=(0, 0, 1, 1), region=(0, 0, 0, 1, 1, 1))
    assert "region bounds a part map: give map_mm" in str(e.value), str(e.value)
    p = cli("simulate", cls, "--tool", ball, "--map-mm=-1", "--part", tmp_path / "no.stl",
            "-o", tmp_path / "x.ply")
    assert p.returncode == 2
    assert "--map-mm must be positive, got -1" in p.stderr, p.stderr
    assert "‹" not in p.stderr, p.stderr


def test_the_functions_that_simulate_read_one_keyword_list():
    # An unknown keyword, as Python names it, in every function that simulates; the
    # caller's dict is left alone.
    options = {"window": WINDOW, "grid_umm": 20.0}
    with pytest.raises(TypeError, match=r"simulate\(\) got an unexpected keyword argument 'grid_umm'"):
        crest.simulate(TRIAL3, tool=TORUS, **options)
    assert options == {"window": WINDOW, "grid_umm": 20.0}
    with pytest.raises(TypeError, match=r"map_tasks\(\) got an unexpected keyword argument 'grid_umm'"):
        crest.map_tasks(TRIAL3, tasks=2, map_mm=0.5, part=TRIAL3, grid_umm=20.0)
    # A keyword of the wrong type is named.
    with pytest.raises(TypeError, match=r"simulate\(\) argument 'rpm'"):
        crest.simulate(TRIAL3, tool=TORUS, window=WINDOW, rpm="fast")
    # The atlas places its own patches, on the programmed feed.
    for k, v in [("window", WINDOW), ("patch_near", (0.0, 0.0, 0.0)), ("feed", "predicted")]:
        with pytest.raises(TypeError, match=rf"atlas_tasks\(\) got an unexpected keyword argument '{k}'"):
            crest.atlas_tasks(TRIAL3, tasks=2, every_mm=3.0, teeth=2, rpm=10000.0, **{k: v})
    # The choices are checked with their keyword.
    with pytest.raises(crest.CrestError, match="model must be 'ice', 'dome' or 'swept', got 'wet'"):
        crest.simulate(TRIAL3, tool=TORUS, window=WINDOW, model="wet")
