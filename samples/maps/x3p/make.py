#!/usr/bin/env python3
"""Makes the .x3p fixtures of crest's x3p reader tests and their expected heights.

Two files are written by surfalize's own x3p writer (float64 `D` and float32 `F`); three are
written here, by hand, independently of crest and of surfalize's writer, for the point types
and layouts surfalize does not write: int16 `I` with a validity mask and a z increment and
offset, int32 `L`, and heights listed in the XML (`DataList`). The expected heights of every
file are those surfalize *reads* (`Surface.load`), in µm, written to `expected.json`
(null for a point that is not measured), with the spacing in µm.

    python3 -m venv /tmp/sfz && /tmp/sfz/bin/pip install surfalize==0.19.2
    /tmp/sfz/bin/python samples/maps/x3p/make.py
"""
import hashlib
import io
import json
import math
import os
import zipfile

import numpy as np
from surfalize import Surface

HERE = os.path.dirname(os.path.abspath(__file__))
NX, NY = 7, 5
DX, DY = 0.5, 0.8  # µm

# A tilted sine with one missing point, µm.
x = np.arange(NX) * DX
y = np.arange(NY) * DY
Z = 2.0 * np.sin(2 * np.pi * x[None, :] / 2.1) + 0.37 * y[:, None] - 1.25
Z[2, 3] = np.nan


def write_surfalize(name, dtype):
    Surface(Z.copy(), DX, DY).save(os.path.join(HERE, name), dtype=dtype)


def main_xml(datatype, z_inc, z_off, data_part):
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2">
 <Record1>
  <Revision>ISO5436 - 2000</Revision>
  <FeatureType>SUR</FeatureType>
  <Axes>
   <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>{DX * 1e-6!r}</Increment><Offset>0.001</Offset></CX>
   <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>{DY * 1e-6!r}</Increment><Offset>-0.002</Offset></CY>
   <CZ><AxisType>A</AxisType><DataType>{datatype}</DataType><Increment>{z_inc!r}</Increment><Offset>{z_off!r}</Offset></CZ>
  </Axes>
 </Record1>
 <Record2><Date>2026-12-06T12:00:00+00:00</Date><Instrument><Manufacturer>hand</Manufacturer><Model>fixture</Model><Serial>0</Serial><Version>1</Version></Instrument><CalibrationDate>2026-12-06T12:00:00+00:00</CalibrationDate><ProbingSystem><Type>Software</Type><Identification>make.py</Identification></ProbingSystem><Comment>crest test fixture</Comment></Record2>
 <Record3>
  <MatrixDimension><SizeX>{NX}</SizeX><SizeY>{NY}</SizeY><SizeZ>1</SizeZ></MatrixDimension>
{data_part}
 </Record3>
 <Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4>
</p:ISO5436_2>
""".encode()


def write_by_hand(name, xml, entries):
    with zipfile.ZipFile(os.path.join(HERE, name), "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("main.xml", xml)
        for n, b in entries:
            z.writestr(n, b)
        z.writestr("md5checksum.hex", hashlib.md5(xml).hexdigest() + " *main.xml\n")


def integer_file(name, datatype, np_type, z_inc, z_off):
    raw = np.round((np.nan_to_num(Z) * 1e-6 - z_off) / z_inc).astype(np_type)
    valid = ~np.isnan(Z).ravel()
    bits = np.packbits(valid, bitorder="little").tobytes()
    data = raw.astype("<" + np.dtype(np_type).str[1:]).tobytes()
    part = f"""  <DataLink><PointDataLink>bindata/data.bin</PointDataLink><MD5ChecksumPointData>{hashlib.md5(data).hexdigest()}</MD5ChecksumPointData><ValidPointsLink>bindata/valid.bin</ValidPointsLink></DataLink>"""
    write_by_hand(name, main_xml(datatype, z_inc, z_off, part),
                  [("bindata/data.bin", data), ("bindata/valid.bin", bits)])


def datalist_file(name):
    datums = "\n".join(
        "   <Datum/>" if math.isnan(v) else f"   <Datum>{float(v) * 1e-6!r}</Datum>" for v in Z.ravel())
    part = f"  <DataList>\n{datums}\n  </DataList>"
    write_by_hand(name, main_xml("D", 1.0, 0.0, part), [])


write_surfalize("surfalize-d.x3p", "D")
write_surfalize("surfalize-f.x3p", "F")
integer_file("hand-i16-mask.x3p", "I", np.int16, 1e-9, 2e-7)
integer_file("hand-i32-mask.x3p", "L", np.int32, 1e-12, -1e-7)
datalist_file("hand-datalist.x3p")

expected = {}
for f in sorted(os.listdir(HERE)):
    if f.endswith(".x3p"):
        s = Surface.load(os.path.join(HERE, f))
        expected[f] = {
            "nx": int(s.data.shape[1]),
            "ny": int(s.data.shape[0]),
            "dx_um": float(s.step_x),
            "dy_um": float(s.step_y),
            "z_um": [None if math.isnan(v) else float(v) for v in s.data.ravel()],
        }
with open(os.path.join(HERE, "expected.json"), "w") as f:
    json.dump(expected, f, indent=1)
    f.write("\n")
