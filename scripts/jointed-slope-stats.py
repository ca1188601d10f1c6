#!/usr/bin/env python3
"""How far the blocks of scenes/jointed_slope.toml have moved, from a run's blocks.csv.

Usage: jointed-slope-stats.py RUN_DIR TIME [TIME ...]

The free blocks are those of the "upper" rock mass whose centroid at t = 0 lies above J1's
lowest daylighting plane (dip 35°, dip direction 270°, through x = 5.7, z = 9.5), as in the
scene's comments and tests/joint_sets.rs. For each time it prints how many free blocks moved
more than 10 cm, their median and extreme displacements, and the largest displacement of any
other block and how many others moved more than 1 cm.
"""
import collections
import csv
import math
import statistics
import sys


def main():
    run, times = sys.argv[1], [float(t) for t in sys.argv[2:]]
    pos = collections.defaultdict(dict)
    with open(f"{run}/blocks.csv", newline="") as f:
        for r in list(csv.reader(f))[1:]:
            pos[r[1]][float(r[0])] = [float(x) for x in r[2:5]]
    s, c = math.sin(math.radians(35)), math.cos(math.radians(35))

    def above_j1(p):
        return (p[0] - 5.7) * -s + (p[2] - 9.5) * c > 0

    free = [n for n in pos if n.startswith("upper/") and above_j1(pos[n][0.0])]
    others = [n for n in pos if n not in free]
    steps = sorted(pos[free[0]])
    print(f"{len(free)} free blocks, {len(others)} others")
    for want in times:
        t = min(steps, key=lambda x: abs(x - want))
        moved = lambda n: math.dist(pos[n][t], pos[n][0.0])
        df = sorted(moved(n) for n in free)
        do = sorted((moved(n), n) for n in others)
        print(
            f"t = {t:.2f} s: free blocks past 10 cm {sum(x > 0.1 for x in df)}, "
            f"median {statistics.median(df):.2f} m, least {df[0]:.3f} m, most {df[-1]:.2f} m; "
            f"others: most {do[-1][0]:.3f} m ({do[-1][1]}), past 1 cm {sum(x > 0.01 for x, _ in do)}"
        )


if __name__ == "__main__":
    main()
