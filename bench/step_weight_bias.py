#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The step scale a drive's motion prior estimates when each step's standard deviation is taken at
the length the odometry reported for it, at its true length, or at one length for all
(docs/results/hidden-effects.md). One dimension of the estimator: the fitted steps are exact, the
odometry reports each true step t with noise of 10 % of t per coordinate, the prior's deviation is
a L + b (the defaults 0.1 L + 2 mm times the factor 0.62 a clean drive fits), and the scale solves
sum w (c - f / (1 + s)) f = 0, 1 + s = sum w f^2 / sum w c.f.
    python3 bench/step_weight_bias.py [DRIVES] [SEED]     (defaults 1000, 1)"""
import math
import random
import statistics
import sys

drives = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
rng = random.Random(int(sys.argv[2]) if len(sys.argv) > 2 else 1)
step, steps, a, b = 0.03, 300, 0.1 * 0.62, 0.002 * 0.62
scales = {"reported length": [], "true length": [], "median reported length": []}
for _ in range(drives):
    reported = [(step + rng.gauss(0, 0.1 * step), rng.gauss(0, 0.1 * step)) for _ in range(steps)]
    lengths = [math.hypot(x, y) for x, y in reported]
    median = statistics.median(lengths)
    for name, at in (("reported length", lengths), ("true length", [step] * steps),
                     ("median reported length", [median] * steps)):
        num = sum(step * step / (a * l + b) ** 2 for l in at)
        den = sum(c[0] * step / (a * l + b) ** 2 for c, l in zip(reported, at))
        scales[name].append(num / den - 1.0)
for name, s in scales.items():
    print(f"weights at the {name}: mean scale {100 * statistics.mean(s):+.2f} %, sd {100 * statistics.stdev(s):.2f} %")
