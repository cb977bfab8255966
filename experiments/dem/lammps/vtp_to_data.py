#!/usr/bin/env python3
"""LAMMPS data file (atom_style sphere) from a contactlab DEM frame (.vtp): the bed contactlab
settled, so both codes are timed on the same particles. Contact history is not carried (LAMMPS
rebuilds it in in.bench-data's warm-up run).
usage: vtp_to_data.py bed_NNNNN.vtp data.bed [density=2500] [footprint=0.045]"""
import re, sys
src, out = sys.argv[1], sys.argv[2]
rho = float(sys.argv[3]) if len(sys.argv) > 3 else 2500.0
L = float(sys.argv[4]) if len(sys.argv) > 4 else 0.045
text = open(src).read()
def block(pattern):
    m = re.search(pattern + r'[^>]*>\n(.*?)</DataArray>', text, re.S)
    return [l.split() for l in m.group(1).strip().split('\n')]
pts = block(r'<Points>\n<DataArray')
radius = block(r'Name="radius"')
vel = block(r'Name="velocity"')
omega = block(r'Name="angular_velocity"')
ids = block(r'Name="id"')
zhi = max(float(p[2]) for p in pts) + 0.01
with open(out, 'w') as f:
    f.write(f"contactlab settled bed from {src}\n\n{len(pts)} atoms\n1 atom types\n\n")
    f.write(f"0 {L!r} xlo xhi\n0 {L!r} ylo yhi\n0 {zhi!r} zlo zhi\n\nAtoms # sphere\n\n")
    for k, p in enumerate(pts):
        x, y, z = (float(v) for v in p)
        f.write(f"{int(ids[k][0]) + 1} 1 {2 * float(radius[k][0])!r} {rho!r} {x % L!r} {y % L!r} {z!r}\n")
    f.write("\nVelocities\n\n")
    for k in range(len(pts)):
        f.write(f"{int(ids[k][0]) + 1} {' '.join(vel[k])} {' '.join(omega[k])}\n")
print(f"wrote {out}: {len(pts)} atoms, zhi = {zhi}")
