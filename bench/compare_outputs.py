#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Compares two output trees of bench/identical_outputs.sh (--keep BEFORE, --keep AFTER).

Files must be byte-identical, with one allowance: JSON files whose only differences are
covariance-derived numbers (keys naming a covariance, variance, correlation or standard error) equal to
`--digits` significant digits (default 10). Ceres orders the columns of a covariance by the
addresses of the parameter blocks, so before the joint refinement kept its blocks in one array
the last digits of standard errors and covariances depended on where the allocator put each
block (off-diagonal centre covariances, small differences of larger terms, to about 10 digits);
see docs/results/test-suite.md. Every other number must be identical.
Prints every file that differs and, for the tolerated ones, the JSON paths of the numbers.
Exit 0 when every file is identical or tolerated, 1 otherwise.
"""
import argparse
import json
import math
import os
import re
import sys


COVARIANCE = re.compile(r"covariance|variance|correlation|standard_error|_se(_|$|\\b)")


def walk(a, b, path, out, digits):
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            return False
        return all(walk(a[k], b[k], f"{path}.{k}", out, digits) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return False
        return all(walk(x, y, f"{path}[{i}]", out, digits) for i, (x, y) in enumerate(zip(a, b)))
    if isinstance(a, float) and isinstance(b, float):
        if a == b:
            return True
        if not COVARIANCE.search(path):
            return False
        scale = max(abs(a), abs(b))
        if math.isfinite(scale) and abs(a - b) <= scale * 10 ** (1 - digits):
            out.append(path)
            return True
        return False
    return a == b and type(a) is type(b)


def files(root):
    for d, _, names in os.walk(root):
        for n in names:
            yield os.path.relpath(os.path.join(d, n), root)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("before")
    p.add_argument("after")
    p.add_argument("--digits", type=int, default=10)
    a = p.parse_args()
    names = sorted(set(files(a.before)) | set(files(a.after)))
    same = tolerated = 0
    failed = []
    for n in names:
        fa, fb = os.path.join(a.before, n), os.path.join(a.after, n)
        if not (os.path.isfile(fa) and os.path.isfile(fb)):
            failed.append(f"{n}: only in {'before' if os.path.isfile(fa) else 'after'}")
            continue
        ba, bb = open(fa, "rb").read(), open(fb, "rb").read()
        if ba.replace(a.before.encode(), b"WORK") == bb.replace(a.after.encode(), b"WORK"):
            same += 1
            continue
        paths = []
        try:
            ok = n.endswith(".json") and walk(json.loads(ba), json.loads(bb), "", paths, a.digits)
        except ValueError:
            ok = False
        if ok:
            tolerated += 1
            shown = ", ".join(paths[:4]) + (f" and {len(paths) - 4} more" if len(paths) > 4 else "")
            print(f"equal to {a.digits} digits: {n}: {shown}")
        else:
            failed.append(f"{n}: differs")
    for f in failed:
        print(f"DIFFERENT: {f}")
    print(f"{same} files byte-identical, {tolerated} equal to {a.digits} significant digits, {len(failed)} different")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
