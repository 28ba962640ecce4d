#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Continuous motion measured on simulated driving sequences (docs/RESULTS.md, "Continuous motion").

For each seed: `lidarcal simulate` a driving scene, `lidarcal detect --truth` (association), then
`lidarcal calibrate` twice, with the motion prior (the default for a robot that never stops) and
with --motion-prior off (every pose tied to its own odometry pose, as stop and go does).

Per seed it prints one row:
  recall   sightings carrying the main id of their landmark / observable sightings (`detect --truth`:
           at least 3 returns on the pole, not partly hidden); the main id of a true landmark is
           the id most of its detections carry, so a track that loses its id counts as missed
  purity   1 - (sightings whose id's majority landmark is another one) / sightings with an id
  ids      landmark ids found (the scene has 6 poles)
  landmark RMS (m): the ids' mean world positions from the odometry poses (detect) and the joint
           refinement's centres, against the true centres (stop 0's frame: odometry starts at the
           true pose)
  pose RMS (m, position): odometry (commanded) poses, refined with --motion-prior off, refined
           with the motion prior, against the true poses; heading RMS (deg) likewise
  model RMS (mm): RMS over the fitted range of f_fit(d) - f_true(d) (the range model's error)

Usage: bench/continuous_motion.py LIDARCAL SCENE.json WORKDIR [SEEDS...]   (default seeds 1-5)
Standard library only; deterministic (same binary, scene and seeds: same numbers).
"""
import csv
import json
import math
import re
import subprocess
import sys
from pathlib import Path


def run(*args):
    subprocess.run([str(a) for a in args], check=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def run_out(*args):
    return subprocess.run([str(a) for a in args], check=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True).stdout


def to_world(pose, x, y):
    c, s = math.cos(pose["yaw_rad"]), math.sin(pose["yaw_rad"])
    return pose["x_m"] + c * x - s * y, pose["y_m"] + s * x + c * y


def nearest(landmarks, x, y):
    best = min(range(len(landmarks)), key=lambda k: math.hypot(landmarks[k]["x_m"] - x, landmarks[k]["y_m"] - y))
    return best, math.hypot(landmarks[best]["x_m"] - x, landmarks[best]["y_m"] - y)


def rms(values):
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else float("nan")


def poly(alpha, d):
    return sum(a * d ** k for k, a in enumerate(alpha))


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def one_seed(exe, scene, work, seed):
    d = work / f"seed{seed}"
    d.mkdir(parents=True, exist_ok=True)
    run(exe, "-q", "simulate", "--scene", scene, "-o", d / "sim", "--seed", seed, "--overwrite")
    truth = json.loads((d / "sim/truth.json").read_text())
    true_lm = truth["landmarks"]
    stop_of_scan = {}
    for k, s in enumerate(truth["stops"]):
        for i in range(s["first_scan"], s["first_scan"] + s["scans"]):
            stop_of_scan[i] = k
    mount = truth["scene"]["sensor"].get("mount_yaw_deg", 0.0) * math.pi / 180.0
    report = run_out(exe, "-q", "detect", d / "sim/scans", "-o", d / "det", "--overwrite", "--truth", d / "sim/truth.json")
    row = next(l for l in report.splitlines() if re.match(r"^\| \d+ \| \d+ \| \d+ \| [0-9.]+ \| \d+ \|", l))
    observable = int(row.split("|")[5])
    # Each detection's true landmark, from its centre placed with the true pose.
    dets = []
    with open(d / "det/landmarks.csv") as f:
        for r in csv.DictReader(f):
            scan = int(re.search(r"(\d+)", r["file"]).group(1))
            actual = dict(truth["stops"][stop_of_scan[scan]]["actual"])
            actual["yaw_rad"] += mount
            wx, wy = to_world(actual, float(r["centre_x_m"]), float(r["centre_y_m"]))
            k, dist = nearest(true_lm, wx, wy)
            dets.append((int(r["landmark"]), k if dist < 0.15 else -1))
    ids = sorted({i for i, _ in dets if i > 0})
    main_id = {}
    for k in range(len(true_lm)):
        counts = {}
        for i, t in dets:
            if t == k and i > 0:
                counts[i] = counts.get(i, 0) + 1
        if counts:
            main_id[k] = max(sorted(counts), key=lambda i: counts[i])
    right = sum(1 for i, t in dets if t >= 0 and i > 0 and main_id.get(t) == i)
    truth_of_id = {}
    for i in ids:
        counts = {}
        for j, t in dets:
            if j == i:
                counts[t] = counts.get(t, 0) + 1
        truth_of_id[i] = max(sorted(counts), key=lambda t: counts[t])
    with_id = [(i, t) for i, t in dets if i > 0]
    wrong = sum(1 for i, t in with_id if t != truth_of_id[i] or t < 0)
    # Landmark positions from the odometry poses (detect's table: mean of each id's detections).
    before = []
    for line in report.splitlines():
        m = re.match(r"^\| (\d+) \| (-?[0-9.]+) \| (-?[0-9.]+) \|", line)
        if m and int(m.group(1)) in ids and main_id.get(truth_of_id[int(m.group(1))]) == int(m.group(1)):
            t = true_lm[truth_of_id[int(m.group(1))]]
            before.append(math.hypot(float(m.group(2)) - t["x_m"], float(m.group(3)) - t["y_m"]))
    out = {"seed": seed, "scans": len(truth["stops"]), "observable": observable,
           "recall": right / observable if observable else float("nan"),
           "purity": 1.0 - wrong / len(with_id) if with_id else float("nan"), "ids": len(ids),
           "landmark_rms_odometry_m": rms(before)}
    out["pose_rms_odometry_m"] = rms([math.hypot(s["commanded"]["x_m"] - s["actual"]["x_m"],
                                                 s["commanded"]["y_m"] - s["actual"]["y_m"]) for s in truth["stops"]])
    out["heading_rms_odometry_deg"] = math.degrees(rms([wrap(s["commanded"]["yaw_rad"] - s["actual"]["yaw_rad"])
                                                        for s in truth["stops"]]))
    for tag, extra in (("off", ["--motion-prior", "off"]), ("motion", [])):
        model_file = d / f"model_{tag}.json"
        run(exe, "-q", "calibrate", d / "sim/scans", "-o", model_file, "--overwrite", *extra)
        m = json.loads(model_file.read_text())
        poses = m["stops"]
        out[f"pose_rms_{tag}_m"] = rms([math.hypot(p["x_m"] - s["actual"]["x_m"], p["y_m"] - s["actual"]["y_m"])
                                        for p, s in zip(poses, truth["stops"])])
        out[f"heading_rms_{tag}_deg"] = math.degrees(rms([wrap(p["yaw_rad"] - s["actual"]["yaw_rad"] - mount)
                                                         for p, s in zip(poses, truth["stops"])]))
        out[f"landmark_rms_{tag}_m"] = rms([nearest(true_lm, l["x_m"], l["y_m"])[1] for l in m["landmarks"]])
        lo, hi = m["fitted_range"]["d_min_m"], m["fitted_range"]["d_max_m"]
        grid = [lo + (hi - lo) * k / 100.0 for k in range(101)]
        out[f"model_rms_{tag}_mm"] = 1000.0 * rms([poly(m["bias"]["alpha"], x) - poly(truth["model"]["bias_alpha"], x)
                                                   for x in grid])
        out[f"motion_prior_{tag}"] = bool(m["diagnostics"].get("motion_prior", False))
    return out


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    exe, scene, work = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
    seeds = [int(s) for s in sys.argv[4:]] or [1, 2, 3, 4, 5]
    work.mkdir(parents=True, exist_ok=True)
    rows = [one_seed(exe, scene, work, s) for s in seeds]
    print("| seed | scans | observable | recall | purity | ids | landmark RMS odometry / refined off / motion (m) "
          "| pose RMS odometry / off / motion (m) | heading RMS odometry / off / motion (deg) "
          "| model RMS off / motion (mm) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['seed']} | {r['scans']} | {r['observable']} | {r['recall']:.3f} | {r['purity']:.3f} | {r['ids']} "
              f"| {r['landmark_rms_odometry_m']:.3f} / {r['landmark_rms_off_m']:.3f} / {r['landmark_rms_motion_m']:.3f} "
              f"| {r['pose_rms_odometry_m']:.3f} / {r['pose_rms_off_m']:.3f} / {r['pose_rms_motion_m']:.3f} "
              f"| {r['heading_rms_odometry_deg']:.2f} / {r['heading_rms_off_deg']:.2f} / {r['heading_rms_motion_deg']:.2f} "
              f"| {r['model_rms_off_mm']:.2f} / {r['model_rms_motion_mm']:.2f} |")
    (work / "results.json").write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
