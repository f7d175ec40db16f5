"""Make the "measurement" of reports/compare from a simulated .x3p, as a microscope would
see it: a mounting tilt, noise and missing points. Python's standard library only.

    python3 perturb.py IN.x3p OUT.x3p

The heights of crest's .x3p are float64 metres in bindata/data.bin (x fastest, NaN =
missing); main.xml carries their MD5 and md5checksum.hex the MD5 of main.xml, both
rewritten here.
"""
import hashlib
import math
import random
import re
import struct
import sys
import zipfile

src, dst = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(src) as z:
    xml = z.read("main.xml").decode()
    data = z.read("bindata/data.bin")
nx = int(re.search(r"<SizeX>(\d+)</SizeX>", xml).group(1))
ny = int(re.search(r"<SizeY>(\d+)</SizeY>", xml).group(1))
z = list(struct.unpack("<%dd" % (nx * ny), data))
rnd = random.Random(34)
for r in range(ny):
    for c in range(nx):
        k = r * nx + c
        # Tilt 0.5 µm/mm along x, -0.3 µm/mm along y (2 µm nodes), noise σ 0.05 µm.
        h = z[k] + (0.5 * c - 0.3 * r) * 2e-3 * 1e-6 + rnd.gauss(0.0, 0.05e-6)
        # 1 % of the points lost at random, and a drop-out streak (a steep flank).
        if rnd.random() < 0.01 or (120 <= r < 126 and 60 <= c < 200):
            h = math.nan
        z[k] = h
data = struct.pack("<%dd" % len(z), *z)
xml = re.sub(
    r"<MD5ChecksumPointData>[0-9a-fA-F]*</MD5ChecksumPointData>",
    "<MD5ChecksumPointData>%s</MD5ChecksumPointData>" % hashlib.md5(data).hexdigest().upper(),
    xml,
)
with zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as out:
    out.writestr("main.xml", xml)
    out.writestr("md5checksum.hex", hashlib.md5(xml.encode()).hexdigest() + " *main.xml\n")
    out.writestr("bindata/data.bin", data)
