"""Shared fixtures: the repository root and the `crest` command line the package is compared
with (CREST_BIN, else target/release/crest or target/debug/crest of the repository)."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def crest_bin() -> str:
    env = os.environ.get("CREST_BIN")
    if env:
        return env
    for profile in ("release", "debug"):
        p = ROOT / "target" / profile / "crest"
        if p.exists():
            return str(p)
    raise RuntimeError(
        "no crest binary: build it (cargo build) or set CREST_BIN to compare with the CLI"
    )


@pytest.fixture(scope="session")
def cli():
    """Run the crest CLI; returns the CompletedProcess (check=False)."""
    exe = crest_bin()

    def run(*args, cwd=ROOT):
        return subprocess.run(
            [exe, *map(str, args)], cwd=cwd, capture_output=True, text=True
        )

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    def run(*args, cwd=ROOT):
        p = cli(*args, "--json", cwd=cwd)
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout)

    return run


def tiny_design(dir: pathlib.Path, title: str = "tiny") -> pathlib.Path:
    """A six-run design (two tilts × three feeds) on a coarse grid: quick, and with a
    three-level factor so every chart of `crest study` is drawn."""
    tool = ROOT / "samples" / "tools" / "torus-r5-rc1.5.toml"
    text = f"""title = "{title}"
surface = "plane"
tool = "{tool}"
rpm = 15000.0
grid_um = 4.0
dtheta_deg = 1.0
responses = ["Sz", "Sq", "Sa", "Ssk"]
[factors]
tilt_deg = [5.0, 10.0]
stepover_mm = [0.05]
feed_mm_min = [2000.0, 3000.0, 4000.0]
"""
    p = dir / f"{title}.toml"
    p.write_text(text)
    return p


BALL = ROOT / "samples" / "synth" / "ball-r5.toml"

# The options of a small part map: a 0.6 × 0.6 mm region of a plane at 4 µm, four cells.
MAP_ARGS = [
    "--tool", BALL, "--model", "dome", "--grid-um", "10", "--fz-mm", "0.05",
    "--map-mm", "0.004", "--region=-0.3,-0.3,-0.5,0.3,0.3,0.5",
]
MAP_KW = dict(
    map_mm=0.004, tool=str(BALL), model="dome", grid_um=10.0, fz_mm=0.05,
    region=(-0.3, -0.3, -0.5, 0.3, 0.3, 0.5),
)


def plane_part(cli, dir: pathlib.Path):
    """A 4 × 4 mm plane part and its path (`crest synth plane`): (cls, stl) paths."""
    cls, stl = dir / "plane.cls", dir / "plane.stl"
    p = cli(
        "synth", "plane", "--tool", BALL, "--stepover-mm", "0.4", "--stepover-along-surface",
        "--size-mm", "4,4", "--point-step-mm", "0.05", "--feed-mm-min", "1000",
        "--rpm", "20000", "--part-tol-um", "0.01", "-o", cls, "--part-stl", stl,
    )
    assert p.returncode == 0, p.stderr
    return cls, stl
