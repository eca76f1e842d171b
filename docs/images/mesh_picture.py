#!/usr/bin/env python3
"""Draws a ROAM mesh written by `ridge mesh --out FILE.glb` seen from above, as a PNG, with
gnuplot. Usage: mesh_picture.py MESH.glb OUT.png [EYE_X,EYE_Z] [TITLE]
Reads the .glb itself (GLB header, JSON chunk, binary chunk): positions are patch-local and
placed by each node's translation."""
import json, os, struct, subprocess, sys, tempfile

glb, png = sys.argv[1], sys.argv[2]
eye = [float(v) for v in sys.argv[3].split(",")] if len(sys.argv) > 3 else None
title = sys.argv[4] if len(sys.argv) > 4 else os.path.basename(glb)
data = open(glb, "rb").read()
magic, version, length = struct.unpack_from("<III", data, 0)
assert magic == 0x46546C67, "not a .glb"
jlen, jtype = struct.unpack_from("<II", data, 12)
doc = json.loads(data[20:20 + jlen])
blen, btype = struct.unpack_from("<II", data, 20 + jlen)
binary = data[28 + jlen:28 + jlen + blen]


def accessor(i, fmt, n):
    a = doc["accessors"][i]
    bv = doc["bufferViews"][a["bufferView"]]
    off = bv.get("byteOffset", 0) + a.get("byteOffset", 0)
    return struct.unpack_from("<" + fmt * (a["count"] * n), binary, off)


segs = []
for node in doc["nodes"]:
    tx, ty, tz = node.get("translation", [0, 0, 0])
    prim = doc["meshes"][node["mesh"]]["primitives"][0]
    pos = accessor(prim["attributes"]["POSITION"], "f", 3)
    idx = accessor(prim["indices"], "I", 1)
    for t in range(0, len(idx), 3):
        p = [(pos[3 * idx[t + k]] + tx, pos[3 * idx[t + k] + 2] + tz) for k in range(3)]
        segs.append(p + [p[0]])
with tempfile.NamedTemporaryFile("w", suffix=".dat", delete=False) as f:
    for s in segs:
        for x, z in s:
            f.write(f"{x} {z}\n")
        f.write("\n")
    dat = f.name
script = f"""
set terminal png size 800,800 font 'sans,10'
set output '{png}'
set size ratio -1
set autoscale fix
set title '{title} ({len(segs)} triangles)'
set xlabel 'x (m)'; set ylabel 'z (m)'
set yrange [*:*] reverse
unset key
plot '{dat}' with lines lw 0.3 lc rgb '#1f4e79'""" + (
    f", '-' with points pt 7 ps 1.5 lc rgb '#c00000'\n{eye[0]} {eye[1]}\ne\n" if eye else "\n")
subprocess.run(["gnuplot"], input=script, text=True, check=True)
os.unlink(dat)
