#!/usr/bin/env python3
"""Writes the camera paths (PATH.json, docs/cli.md "Camera paths") used by tests and benchmarks on the built-in
default terrain (2048 m x 2048 m, heights about 0..260 m):
  flyover.json   360 frames, a circle of radius 600 m at 380 m, looking ahead and down
  drive.json     600 frames, 2 m above the ground along a winding road at 20 m/s
  fast_yaw.json  360 frames, standing 40 m above the ground turning 3 degrees per frame
  zoom.json      360 frames, slow flight; field of view snaps 70 -> 8 degrees at frame 120, back at 240
  down.json      240 frames, looking straight down while descending from 1500 m to 60 m
  fast_pass.json 240 frames, 1,000 km/h (4.63 m per frame) at 300 m, about 40 m above the highest sample
Usage: make_paths.py RIDGE OUT_DIR   (RIDGE: the ridge binary, used to sample ground heights)"""
import json, math, os, subprocess, sys

ridge, out = sys.argv[1], sys.argv[2]
DT = 1 / 60


def ground(points):
    csv = "\n".join(f"{x},{z}" for x, z in points) + "\n"
    r = subprocess.run([ridge, "query", "--default-terrain", "--points", "-"], input=csv,
                       capture_output=True, text=True, check=True)
    return [float(line.split(",")[2]) for line in r.stdout.strip().splitlines()]


def frame(eye, target, fov=60, up=(0, 1, 0)):
    return {"eye": [round(v, 4) for v in eye], "target": [round(v, 4) for v in target],
            "up": list(up), "fov_y": fov, "viewport": [1280, 720], "dt": DT}


def write(name, frames):
    with open(os.path.join(out, name), "w") as f:
        json.dump({"version": 1, "frames": frames}, f, separators=(",", ":"))


C = 1024.0
fly = []
for k in range(360):
    a = 2 * math.pi * k / 360
    ex, ez = C + 600 * math.cos(a), C + 600 * math.sin(a)
    hx, hz = -math.sin(a), math.cos(a)
    fly.append(frame((ex, 380, ez), (ex + 100 * hx, 330, ez + 100 * hz)))
write("flyover.json", fly)

road = []
for k in range(601):
    t = k / 600
    road.append((200 + 1600 * t, C + 300 * math.sin(2 * math.pi * t * 1.5)))
hs = ground(road)
drive = []
for k in range(600):
    (x, z), (nx, nz) = road[k], road[k + 1]
    drive.append(frame((x, hs[k] + 2, z), (nx + 10 * (nx - x), hs[k + 1] + 1.5, nz + 10 * (nz - z))))
write("drive.json", drive)

h0 = ground([(C, C)])[0]
yaw = []
for k in range(360):
    a = math.radians(3 * k)
    yaw.append(frame((C, h0 + 40, C), (C + 100 * math.cos(a), h0 + 10, C + 100 * math.sin(a))))
write("fast_yaw.json", yaw)

zoom = []
for k in range(360):
    ex = 300 + 2 * k
    fov = 8 if 120 <= k < 240 else 70
    zoom.append(frame((ex, 320, 300), (ex + 300, 200, 900), fov))
write("zoom.json", zoom)

down = []
for k in range(240):
    y = 1500 - (1500 - 60 - 260) * k / 239
    down.append(frame((C + k, y, C), (C + k, 0, C), 60, (0, 0, 1)))
write("down.json", down)

fast = []
step = 1000 / 3.6 * DT  # metres per frame at 1,000 km/h
ux, uz = 1 / math.hypot(1, 0.6), 0.6 / math.hypot(1, 0.6)
for k in range(240):
    ex, ez = 100 + step * k * ux, 200 + step * k * uz
    fast.append(frame((ex, 300, ez), (ex + 100 * ux, 250, ez + 100 * uz)))
write("fast_pass.json", fast)
