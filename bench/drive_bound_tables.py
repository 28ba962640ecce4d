#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The tables of docs/results/odometry.md ("Odometry, mounting and range in one fit") from the
JSON files bench/drive_bound wrote: python3 bench/drive_bound_tables.py RUN.json [RUN.json ...]"""
import json
import sys

SHOWN = {  # name: (label, unit, factor from SI)
    "left_radius_m": ("left wheel radius r_L", "mm", 1e3),
    "right_radius_m": ("right wheel radius r_R", "mm", 1e3),
    "axle_m": ("axle b", "mm", 1e3),
    "laser_x_m": ("laser x l_x", "mm", 1e3),
    "laser_y_m": ("laser y l_y", "mm", 1e3),
    "laser_theta_rad": ("laser heading l_theta", "deg", 57.29577951308232),
    "range_offset_m": ("range offset a_0", "mm", 1e3),
}


def rows(run, fit):
    return {r["parameter"]: r for r in run[fit]["parameters"]}


def bound_table(run):
    joint = rows(run, "joint")
    print("| parameter | bound SD | RMSE | mean error | efficiency (bound / MSE) | 95 % coverage |")
    print("|---|---|---|---|---|---|")
    for name, r in joint.items():
        label, unit, f = SHOWN[name]
        print(f"| {label} ({unit}) | {r['bound_sd'] * f:.4f} | {r['rmse'] * f:.4f} | "
              f"{r['mean_error'] * f:+.4f} | {r['efficiency']:.3f} | {100 * r['coverage_95']:.1f} % |")


def held_table(run):
    joint, held = rows(run, "joint"), rows(run, "range_held_exact")
    print("| parameter | joint: mean error (bound SDs) | joint: coverage | range held exact: mean "
          "error (bound SDs) | held: RMSE | held: coverage | bound SD grows, offset unknown |")
    print("|---|---|---|---|---|---|---|")
    for name, h in held.items():
        label, unit, f = SHOWN[name]
        j = joint[name]
        print(f"| {label} ({unit}) | {j['mean_error'] * f:+.4f} ({j['mean_error'] / j['bound_sd']:+.2f}) | "
              f"{100 * j['coverage_95']:.1f} % | {h['mean_error'] * f:+.4f} "
              f"({h['mean_error'] / h['bound_sd']:+.2f}) | {h['rmse'] * f:.4f} | "
              f"{100 * h['coverage_95']:.1f} % | {100 * (j['bound_sd'] / h['bound_sd'] - 1):+.1f} % |")


for path in sys.argv[1:]:
    run = json.load(open(path))
    print(f"\n{run['seeds']} drives (seeds {run['first_seed']}-{run['first_seed'] + run['seeds'] - 1}), "
          f"field of view {run.get('field_of_view_deg', 360):g} deg; joint fits {run['joint']['fits']} "
          f"({run['joint']['failed']} failed), range held exact {run['range_held_exact']['fits']} "
          f"({run['range_held_exact']['failed']} failed)\n")
    bound_table(run)
    print()
    held_table(run)
