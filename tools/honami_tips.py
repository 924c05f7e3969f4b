#!/usr/bin/env python3
"""Tip statistics of a honami_field run (docs/validation.md, honami_field), from the
vegetation_beam/tips.csv of a run folder (one row every tip_interval, one column per plant: the
tip's streamwise displacement from its base, m).

    python3 tools/honami_tips.py RUN_FOLDER [--window 4 7.5] [--window 12 20] ...

For each window [t0, t1] (s) it prints, for the plants at x = 5.0 / 7.5 / 10.0 / 12.5 / 14.5 /
14.95 m (the first plant stands at x = 5.0 m, one every 0.05 m):
  - the mean tip displacement and the drift of its 1 s moving mean from t0 to t1,
  - the rms of the fluctuation: the displacement minus its 1 s centred moving mean,
  - the lag of the bending between plants 0.5 and 1.0 m apart (plants 50, 100, 150 against
    the plants 10 and 20 further downstream): the shift, within 0.6 s, that maximises the
    cross-correlation of the two fluctuations, and the travel speed distance / lag.
Standard library only.
"""
import argparse
import csv
import math
import os
import sys

FIRST_PLANT_X = 5.0  # m
PLANT_SPACING = 0.05  # m
REPORT_X = [5.0, 7.5, 10.0, 12.5, 14.5, 14.95]
LAG_PAIRS = [(50, 10), (50, 20), (100, 10), (100, 20), (150, 10), (150, 20)]
MEAN_SPAN = 1.0  # s, moving mean taken off the displacement
MAX_LAG = 0.6  # s


def read_tips(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows or rows[0][0] != "time":
        sys.exit(f"{path}:1: expected a header starting with 'time'")
    times, columns = [], [[] for _ in rows[0][1:]]
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(rows[0]):
            sys.exit(f"{path}:{line}: {len(row)} fields where the header has {len(rows[0])}")
        times.append(float(row[0]))
        for c, value in enumerate(row[1:]):
            columns[c].append(float(value))
    return times, columns


def moving_mean(values, half):
    """Centred mean over 2 half + 1 samples (shorter at the ends)."""
    prefix = [0.0]
    for v in values:
        prefix.append(prefix[-1] + v)
    out = []
    for i in range(len(values)):
        lo, hi = max(0, i - half), min(len(values), i + half + 1)
        out.append((prefix[hi] - prefix[lo]) / (hi - lo))
    return out


def best_lag(a, b, max_shift):
    """Shift s >= 0 (samples) maximising the correlation of a[i] with b[i + s]."""
    best, best_shift = -math.inf, 0
    for s in range(0, max_shift + 1):
        n = len(a) - s
        if n < 10:
            break
        ma = sum(a[:n]) / n
        mb = sum(b[s:s + n]) / n
        num = sum((a[i] - ma) * (b[i + s] - mb) for i in range(n))
        den = math.sqrt(sum((a[i] - ma) ** 2 for i in range(n)) *
                        sum((b[i + s] - mb) ** 2 for i in range(n)))
        r = num / den if den > 0 else -math.inf
        if r > best:
            best, best_shift = r, s
    return best_shift, best


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", help="run folder of cosim run (holds vegetation_beam/tips.csv)")
    parser.add_argument("--window", nargs=2, type=float, action="append", metavar=("T0", "T1"),
                        help="averaging window, s (repeatable; default 4 7.5)")
    args = parser.parse_args()
    path = os.path.join(args.run, "vegetation_beam", "tips.csv")
    if not os.path.exists(path):
        sys.exit(f"{path}: not found (is {args.run} a honami_field run folder?)")
    times, columns = read_tips(path)
    if len(times) < 3:
        sys.exit(f"{path}: fewer than three rows")
    dt = (times[-1] - times[0]) / (len(times) - 1)
    half = int(round(0.5 * MEAN_SPAN / dt))
    means = [moving_mean(c, half) for c in columns]
    fluct = [[v - m for v, m in zip(c, mm)] for c, mm in zip(columns, means)]
    plants = [int(round((x - FIRST_PLANT_X) / PLANT_SPACING)) for x in REPORT_X]
    plants = [min(p, len(columns) - 1) for p in plants]
    for t0, t1 in args.window or [(4.0, 7.5)]:
        rows = [i for i, t in enumerate(times) if t0 - 1e-9 <= t <= t1 + 1e-9]
        if len(rows) < 3:
            sys.exit(f"window {t0}-{t1} s: fewer than three rows in {path} "
                     f"(the run covers {times[0]}-{times[-1]} s)")
        i0, i1 = rows[0], rows[-1]
        print(f"window {t0:g}-{t1:g} s ({len(rows)} rows of {dt:.3g} s)")
        print("  x [m]                      " + "".join(f"{x:>9.2f}" for x in REPORT_X))
        mean = [sum(columns[p][i0:i1 + 1]) / len(rows) for p in plants]
        drift = [means[p][i1] - means[p][i0] for p in plants]
        rms = [math.sqrt(sum(v * v for v in fluct[p][i0:i1 + 1]) / len(rows)) for p in plants]
        print("  mean tip displacement [m] " + "".join(f"{v:9.4f}" for v in mean))
        print("  drift of the 1 s mean [m] " + "".join(f"{v:9.4f}" for v in drift))
        print("  fluctuation rms [m]       " + "".join(f"{v:9.4f}" for v in rms))
        max_shift = int(round(MAX_LAG / dt))
        for p, step in LAG_PAIRS:
            q = p + step
            if q >= len(columns):
                continue
            shift, r = best_lag(fluct[p][i0:i1 + 1], fluct[q][i0:i1 + 1], max_shift)
            distance = step * PLANT_SPACING
            speed = f"{distance / (shift * dt):.2f} m/s" if shift > 0 else "-"
            print(f"  lag plant {p:3d} -> {q:3d} ({distance:.1f} m): {shift * dt:.2f} s, "
                  f"correlation {r:.2f}, speed {speed}")


if __name__ == "__main__":
    main()
