#!/usr/bin/python3
"""Draws one frame's fragments seen along an axis, each piece in its own colour: the crack pattern
of a pane or a wall just after it broke.

    /usr/bin/python3 tools/fragments_front_view.py OUT/fragments.0002.vdb front.png [--along y]

Needs Debian's python3-openvdb and python3-matplotlib (under /usr/bin/python3).
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pyopenvdb as vdb

AXES = {"x": 0, "y": 1, "z": 2}


def fragment_centres(path):
    """Per fragment grid, the world positions of its voxel centres (m)."""
    try:
        metadata = vdb.readAllGridMetadata(path)
    except (OSError, ValueError) as error:
        sys.exit(f"{path}: cannot be read as a .vdb ({error})")
    for meta in metadata:
        # The density grid sums every fragment; fracture_faces_* are the pieces' broken faces.
        if meta.name == "density" or meta.name.startswith("fracture_faces"):
            continue
        grid = vdb.read(path, meta.name)
        centres = [grid.transform.indexToWorld(item.min) for item in grid.citerOnValues() if item.count == 1]
        if centres:
            yield np.array(centres)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("frame", help="a run's fragments.NNNN.vdb")
    parser.add_argument("picture", help="the PNG to write")
    parser.add_argument("--along", choices=AXES, default="y", help="the axis the view looks along (default y)")
    args = parser.parse_args()
    seen = [axis for name, axis in AXES.items() if name != args.along]
    colours = np.random.default_rng(1)
    figure, ax = plt.subplots(figsize=(7, 7))
    pieces = 0
    for centres in fragment_centres(args.frame):
        pieces += 1
        ax.scatter(centres[:, seen[0]], centres[:, seen[1]], s=1.2, color=colours.random(3), marker="s", linewidths=0)
    if pieces == 0:
        sys.exit(f"{args.frame}: no fragment grids")
    names = [name for name in AXES if name != args.along]
    ax.set_aspect("equal")
    ax.set_xlabel(f"{names[0]} (m)")
    ax.set_ylabel(f"{names[1]} (m)")
    ax.set_title(f"{os.path.basename(args.frame)}: {pieces} pieces, seen along {args.along}")
    figure.savefig(args.picture, dpi=110)


if __name__ == "__main__":
    main()
