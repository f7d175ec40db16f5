# The two 2000 x 2000 maps of the `crest compare` benchmark (reports/benchmarks.md, issue 34):
# pred.gsf, a ball-end surface (feed marks 100 um along x, scallops 300 um across, 1 um
# nodes), and meas.gsf, the same surface turned 3 deg, moved (17.3, -41.7) um, with noise
# sigma 0.05 um and 2 % missing nodes. Standard library only:  python3 bench_maps.py DIR
import math, random, struct, sys
n = 2000; dx = 1e-6
R = 5000.0
def surf(x, y):
    u = x % 100.0; u = min(u, 100.0 - u)
    v = y % 300.0; v = min(v, 300.0 - v)
    return (u*u + v*v) / (2*R)
def write(path, rot_deg, shift, noise, missing, seed):
    rnd = random.Random(seed)
    c, s = math.cos(math.radians(rot_deg)), math.sin(math.radians(rot_deg))
    vals = []
    for j in range(n):
        for i in range(n):
            x, y = i - n/2, j - n/2
            xr, yr = c*x - s*y + shift[0], s*x + c*y + shift[1]
            z = surf(xr, yr) + (rnd.gauss(0, noise) if noise else 0.0)
            if missing and rnd.random() < missing:
                z = float('nan')
            vals.append(z * 1e-6)
    head = "Gwyddion Simple Field 1.0\nXRes = %d\nYRes = %d\nXReal = %g\nYReal = %g\nXYUnits = m\nZUnits = m\n" % (n, n, n*dx, n*dx)
    b = head.encode()
    b += b"\0" * (4 - len(b) % 4)
    with open(path, "wb") as f:
        f.write(b)
        f.write(struct.pack("<%df" % len(vals), *vals))
write(sys.argv[1] + "/pred.gsf", 0.0, (0, 0), 0.0, 0.0, 1)
write(sys.argv[1] + "/meas.gsf", 3.0, (17.3, -41.7), 0.05, 0.02, 2)
