#!/usr/bin/env python3
"""Composes assets/rockfall_sequence.png (the README's picture) from the frames of
`cargo run --release -- render scenes/rock_column_rockfall.toml`: the frames at 0, 0.3, 0.6, 1.0,
1.5 and 2.0 s (30 frames per simulated second), halved, in a 3 x 2 grid. Needs Pillow.

Usage: scripts/rockfall-sequence.py [FRAMES_DIR] [OUT_PNG] [FPS] [T1,T2,...]

FPS (default 30) is the frame rate the frames were rendered at, and the times (default the
six above) pick the frames; any six times make the same 3 x 2 grid (e.g. the jointed slope's
sheet: `scripts/rockfall-sequence.py out/.../frames assets/jointed_slope_sequence.png 2
0,1,2,2.5,3,4`).
"""
import sys
from pathlib import Path

from PIL import Image

frames = Path(sys.argv[1] if len(sys.argv) > 1 else "out/rockfall-on-a-jointed-rock-column/frames")
out = Path(sys.argv[2] if len(sys.argv) > 2 else "assets/rockfall_sequence.png")
fps = float(sys.argv[3]) if len(sys.argv) > 3 else 30.0
times = [float(t) for t in sys.argv[4].split(",")] if len(sys.argv) > 4 else [0.0, 0.3, 0.6, 1.0, 1.5, 2.0]
tiles = [Image.open(frames / f"frame_{round(t * fps):05d}.png").convert("RGB") for t in times]
w, h = tiles[0].width // 2, tiles[0].height // 2
sheet = Image.new("RGB", (3 * w, 2 * h))
for k, tile in enumerate(tiles):
    sheet.paste(tile.resize((w, h), Image.LANCZOS), ((k % 3) * w, (k // 3) * h))
sheet.save(out)
print(f"wrote {out} ({sheet.width}x{sheet.height}) from {frames}")
