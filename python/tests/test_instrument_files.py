"""The instruments' own height-map files against an independent reader, surfalize (issue 34).

surfalize writes .sur (plain and compressed), .sdf, .al3d and .x3p from a known array with
missing points; crest reads them (crest.read_map) to surfalize's own heights of the same
file: integer formats exactly, float formats to 1e-9 relative, spacing to 1e-12, the same
missing nodes. What crest writes (.x3p, .sdf) reads back in surfalize with the same heights.
For the formats surfalize reads but cannot write (.gwy, .plu, .plux, .opd, .vk4) the test
writes small files with `struct` from the formats' layouts and reads them with both."""

import io
import struct
import subprocess
import zipfile

import numpy as np
import pytest

import crest
from conftest import crest_bin

surfalize = pytest.importorskip("surfalize")
pytestmark = pytest.mark.filterwarnings("ignore:The surface has different pixel size")
Surface = surfalize.Surface

# A known surface: 5 rows × 7 columns with missing points, µm.
Z = np.array(
    [
        [0.5, -1.25, 2.0, 3.0, np.nan, 4.5, 0.125],
        [1.0, 1.5, -2.5, 0.0, 0.75, -0.5, 2.25],
        [np.nan, 0.25, 1.75, -1.0, 3.5, 1.125, -0.375],
        [2.5, -3.0, 0.625, 1.25, -0.25, np.nan, 0.875],
        [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
    ]
)
DX, DY = 0.5, 0.25


def assert_same(crest_map, surface, exact):
    """crest's map against surfalize's surface of the same file."""
    want = np.asarray(surface.data, dtype=np.float64)
    got = crest_map.z_um
    assert got.shape == want.shape
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
    ok = ~np.isnan(want)
    if exact:
        np.testing.assert_array_equal(got[ok], want[ok])
    else:
        np.testing.assert_allclose(got[ok], want[ok], rtol=1e-9, atol=0)
    assert abs(crest_map.dx_um - surface.step_x) <= 1e-12
    assert abs(crest_map.dy_um - surface.step_y) <= 1e-12


def surfalize_writes(tmp_path, name, **kwargs):
    path = tmp_path / name
    Surface(Z.copy(), DX, DY).save(path, **kwargs)
    return path


@pytest.mark.parametrize("compressed", [False, True])
def test_sur_written_by_surfalize(tmp_path, compressed):
    path = surfalize_writes(tmp_path, "a.sur", compressed=compressed)
    m = crest.read_map(path)
    assert_same(m, Surface.load(path), exact=True)
    # And the heights are the array's, to the float32 spacing_z and offset_z.
    ok = ~np.isnan(Z)
    np.testing.assert_allclose(m.z_um[ok], Z[ok], atol=1e-5)
    assert isinstance(m, crest.HeightMap)


def test_sdf_al3d_x3p_written_by_surfalize(tmp_path):
    for name in ("a.sdf", "a.al3d", "a.x3p"):
        path = surfalize_writes(tmp_path, name)
        m = crest.read_map(path)
        assert_same(m, Surface.load(path), exact=False)
        ok = ~np.isnan(Z)
        # float32 metres (al3d) keep ~7 digits of the µm heights.
        np.testing.assert_allclose(m.z_um[ok], Z[ok], rtol=1e-6, atol=1e-9)


def test_what_crest_writes_reads_in_surfalize(tmp_path):
    sdf = tmp_path / "c.sdf"
    crest.HeightMap(Z.copy(), DX, DY).to_sdf(sdf)
    x3p = tmp_path / "c.x3p"
    p = subprocess.run(
        [crest_bin(), "convert", str(sdf), "-o", str(x3p)], capture_output=True, text=True
    )
    assert p.returncode == 0, p.stderr
    for path in (sdf, x3p):
        s = Surface.load(path)
        want = Z
        got = np.asarray(s.data, dtype=np.float64)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
        ok = ~np.isnan(want)
        np.testing.assert_allclose(got[ok], want[ok], rtol=1e-9, atol=1e-12)
        assert abs(s.step_x - DX) <= 1e-12 and abs(s.step_y - DY) <= 1e-12


def test_the_command_line_reads_them_too(tmp_path):
    path = surfalize_writes(tmp_path, "a.sur")
    out = tmp_path / "a.csv"
    p = subprocess.run(
        [crest_bin(), "convert", str(path), "-o", str(out)], capture_output=True, text=True
    )
    assert p.returncode == 0, p.stderr
    assert out.exists()


# ---- files written here from the layouts, read by both ----


def gwy_comp(name, ty, payload):
    return name.encode() + b"\0" + ty + payload


def gwy_obj(name, comps):
    body = b"".join(comps)
    return name.encode() + b"\0" + struct.pack("<I", len(body)) + body


def gwy_str(s):
    return s.encode() + b"\0"


def gwy_field(z, xreal, yreal, uxy, uz):
    ny, nx = z.shape
    unit = lambda u: gwy_obj("GwySIUnit", [gwy_comp("unitstr", b"s", gwy_str(u))])
    data = struct.pack("<I", z.size) + z.astype("<f8").tobytes()
    return gwy_obj(
        "GwyDataField",
        [
            gwy_comp("xres", b"i", struct.pack("<i", nx)),
            gwy_comp("yres", b"i", struct.pack("<i", ny)),
            gwy_comp("xreal", b"d", struct.pack("<d", xreal)),
            gwy_comp("yreal", b"d", struct.pack("<d", yreal)),
            gwy_comp("si_unit_xy", b"o", unit(uxy)),
            gwy_comp("si_unit_z", b"o", unit(uz)),
            gwy_comp("data", b"D", data),
        ],
    )


def test_gwy(tmp_path):
    metres = np.nan_to_num(Z) * 1e-6
    mask = np.isnan(Z).astype("f8")
    body = [
        gwy_comp("/0/data", b"o", gwy_field(metres, 7 * 0.5e-6, 5 * 0.25e-6, "m", "m")),
        gwy_comp("/0/data/title", b"s", gwy_str("Height")),
        gwy_comp("/0/mask", b"o", gwy_field(mask, 7 * 0.5e-6, 5 * 0.25e-6, "m", "")),
    ]
    path = tmp_path / "a.gwy"
    path.write_bytes(b"GWYP" + gwy_obj("GwyContainer", body))
    m = crest.read_map(path)
    assert_same(m, Surface.load(path), exact=False)
    assert_same(crest.read_map(path, channel="Height"), Surface.load(path), exact=False)


def test_plu(tmp_path):
    ny, nx = Z.shape
    head = bytearray(500)
    head[0:19] = b"01/02/2024 10:20:30"
    struct.pack_into("<3I7f", head, 388, ny, nx, 1, 1.0, 0.5, 0.25, 0.0, 0.0, 1.0, 0.0)
    data = np.where(np.isnan(Z), 1000001.0, Z).astype("<f4")
    path = tmp_path / "a.plu"
    path.write_bytes(bytes(head) + data.tobytes())
    assert_same(crest.read_map(path), Surface.load(path), exact=False)


def test_plux(tmp_path):
    ny, nx = Z.shape
    xml = (
        "<?xml version='1.0'?><xml><GENERAL><DATE>01/02/2024 10:20:30</DATE>"
        f"<IMAGE_SIZE_X>{nx}</IMAGE_SIZE_X><IMAGE_SIZE_Y>{ny}</IMAGE_SIZE_Y>"
        "<FOV_X>0.5</FOV_X><FOV_Y>0.25</FOV_Y></GENERAL></xml>"
    )
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("index.xml", xml)
        z.writestr("LAYER_0.raw", Z.astype("<f4").tobytes())
    path = tmp_path / "a.plux"
    path.write_bytes(buf.getvalue())
    assert_same(crest.read_map(path), Surface.load(path), exact=False)


def test_opd(tmp_path):
    ny, nx = Z.shape
    # Heights in waves × Mult / wavelength: stored nx lines of ny int16 values, turned a quarter.
    wavelength, mult = 632.8, 4
    ints = np.where(np.isnan(Z), 32767, np.round(Z * 100)).astype("<i2")
    stored = np.rot90(ints, k=-1)  # shape (nx, ny): rot90 of it gives ints back
    assert np.array_equal(np.rot90(stored), ints)
    blocks = [
        (b"RAW_DATA", 3, struct.pack("<3H", nx, ny, 2) + stored.tobytes()),
        (b"Wavelength", 7, struct.pack("<f", wavelength)),
        (b"Mult", 6, struct.pack("<h", mult)),
        (b"Pixel_size", 7, struct.pack("<f", 0.0005)),
        (b"Aspect", 7, struct.pack("<f", 0.5)),
        (b"Title", 5, b"made by hand\0\0\0\0"),
    ]
    out = b"\x01\x00" + struct.pack("<16shlH", b"Directory", 1, 24 * (len(blocks) + 1), 0)
    for name, ty, data in blocks:
        out += struct.pack("<16shlH", name, ty, len(data), 0)
    out += b"".join(d for _, _, d in blocks)
    path = tmp_path / "a.opd"
    path.write_bytes(out)
    m = crest.read_map(path)
    assert_same(m, Surface.load(path), exact=False)
    assert m.nx == nx and m.ny == ny


def test_vk4(tmp_path):
    ny, nx = Z.shape
    conds, strings = 84, 84 + 304
    layer = strings + 8
    out = bytearray(layer + 796 + 2 * Z.size)
    out[0:4] = b"VK4_"
    struct.pack_into("<I", out, 12, conds)
    struct.pack_into("<I", out, 36, layer)
    struct.pack_into("<I", out, 76, strings)
    struct.pack_into("<7I", out, conds, 304, 2024, 1, 2, 10, 20, 30)
    struct.pack_into("<3I", out, conds + 168, 138000, 139000, 1000)
    struct.pack_into("<5I", out, layer, nx, ny, 16, 0, 2 * Z.size)
    vals = np.nan_to_num(Z + 4.0).round(3) * 1000
    out[layer + 796 :] = vals.astype("<u2").tobytes()
    path = tmp_path / "a.vk4"
    path.write_bytes(bytes(out))
    m = crest.read_map(path)
    assert_same(m, Surface.load(path), exact=True)
