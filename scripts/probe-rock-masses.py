#!/usr/bin/env python3
"""Random jointed cubes on a base, run one by one: a probe for what rock masses the solver fails.

Each seed gives a cube 0.5-4 m across cut by one to three joint sets (random dip, dip
direction, spacing 5-50 % of the cube, friction 10-50 degrees, sometimes cohesion or a spacing
deviation) on a fixed base, DDA-3a or DDA-3p, with or without the equilibrium stage, run for
0.2 s. Prints one line per seed: exit status, wall time, summary.json's status, steps, largest
penetration, blocks, and the last line of stderr (the error, if any). A seed gives the same
scene every time.

    scripts/probe-rock-masses.py target/release/dda3d 1 30 [--timeout 120] [--keep DIR]
"""

import argparse
import json
import random
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def scene(seed: int) -> str:
    r = random.Random(seed)
    size = r.choice([0.5, 1.0, 2.0, 4.0])
    sets = ""
    for k in range(r.randint(1, 3)):
        spacing = size * r.choice([0.05, 0.1, 0.2, 0.3, 0.5])
        sets += (
            f'[[rock_masses.joint_sets]]\nname = "J{k}"\ndip = {r.uniform(0, 90):.1f}\n'
            f"dip_direction = {r.uniform(0, 360):.1f}\nspacing = {spacing:.4f}\n"
            f"friction_angle = {r.uniform(10, 50):.1f}\n"
        )
        if r.random() < 0.3:
            sets += f"cohesion = {r.choice([0, 1e3, 1e5])}\n"
        if r.random() < 0.3:
            sets += f"spacing_deviation = {spacing * 0.2:.4f}\n"
    method = r.choice(["alm", "alm", "penalty"])
    stage = r.choice(["true", "false"])
    return (
        f'[solver]\nmethod = "{method}"\nduration = 0.2\ninitial_equilibrium = {stage}\n'
        f"equilibrium_max_steps = 30\n[materials.rock]\ndensity = 2600.0\n"
        f"young_modulus = {r.choice([1e9, 1e10, 5e10])}\npoisson_ratio = 0.25\n"
        f'[[blocks]]\nname = "g"\nmaterial = "rock"\nfixed = true\n'
        f"box = {{ size = [{4 * size}, {4 * size}, {size / 2}], center = [0, 0, {-size / 4}] }}\n"
        f'[[rock_masses]]\nname = "m"\nmaterial = "rock"\n'
        f"regions = [ {{ box = {{ size = [{size}, {size}, {size}], center = [0, 0, {size / 2}] }} }} ]\n"
        f"{sets}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("binary")
    ap.add_argument("first", type=int)
    ap.add_argument("last", type=int)
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--keep", type=Path, help="write the scenes and outputs here")
    args = ap.parse_args()
    root = args.keep or Path(tempfile.mkdtemp(prefix="dda3d-probe-"))
    root.mkdir(parents=True, exist_ok=True)
    for seed in range(args.first, args.last + 1):
        path = root / f"c{seed}.toml"
        path.write_text(scene(seed))
        out = root / f"o{seed}"
        start = time.monotonic()
        try:
            p = subprocess.run(
                [args.binary, "run", str(path), "--out", str(out), "-q", "--output-interval", "0.05"],
                capture_output=True, text=True, timeout=args.timeout,
            )
            code, err = p.returncode, p.stderr.strip().splitlines()
        except subprocess.TimeoutExpired:
            code, err = "timeout", []
        wall = time.monotonic() - start
        try:
            s = json.loads((out / "summary.json").read_text())
            masses = s.get("rock_masses") or [{}]
            what = f"{s['status']} {s['steps']} steps, {s['max_penetration']:.2e} m, {masses[0].get('blocks')} blocks"
        except (OSError, ValueError, KeyError):
            what = "no summary"
        first = err[-1][:200] if err else ""
        print(f"seed {seed}: exit {code}, {wall:.1f} s, {what}  {first}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
