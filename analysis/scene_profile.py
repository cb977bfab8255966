#!/usr/bin/env python3
"""Radial number density of a scene file (text x,y,z[,d]) around the box centre, against the
law of docs/scenes.md, and the distribution of cell occupancy at cell width D.

usage: /usr/bin/python3 analysis/scene_profile.py SCENE.csv --core 0.3 --diameter 0.005 --out FIG.png
"""
import argparse
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("--core", type=float, default=0.3)
    parser.add_argument("--diameter", type=float, default=0.005)
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    try:
        points = pd.read_csv(args.scene, comment="#").to_numpy()[:, :3]
    except (OSError, ValueError) as error:
        sys.exit(f"scene_profile: cannot read {args.scene}: {error}")
    n = len(points)
    radius = 0.5
    r = np.linalg.norm(points - 0.5, axis=1) / radius
    edges = np.linspace(0, 1, 101)
    counts, _ = np.histogram(r, bins=edges)
    shell_volume = 4.0 / 3.0 * np.pi * (edges[1:] ** 3 - edges[:-1] ** 3) * radius**3
    density = counts / shell_volume
    s = 0.5 * (edges[1:] + edges[:-1])
    c = args.core
    # F(s) = (s (1 + c) / (s + c))^2  =>  dN/dV = N F'(s) / (4 pi s^2 R^3)
    law = n * 2 * s * (1 + c) ** 2 * c / (s + c) ** 3 / (4 * np.pi * s**2 * radius**3)

    per_axis = int(np.floor(1.0 / (args.diameter * (1 + 2**-40))))  # as kernels/cell_grid.hpp
    cells = np.minimum((points * per_axis).astype(int), per_axis - 1)
    _, occupancy = np.unique(cells[:, 0] * 10**6 + cells[:, 1] * 10**3 + cells[:, 2], return_counts=True)

    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    left.loglog(s, density, "o", ms=3, label="generated")
    left.loglog(s, law, "-", label=f"law, c = {c}")
    left.set_xlabel("r / R (R = 0.5)")
    left.set_ylabel("particles per unit volume")
    left.set_title(f"clustered scene, N = {n}")
    left.legend()
    right.hist(occupancy, bins=np.logspace(0, np.log10(occupancy.max() + 1), 40), log=True)
    right.set_xscale("log")
    right.set_xlabel("particles per occupied cell (width D)")
    right.set_ylabel("cells")
    right.set_title(f"max occupancy {occupancy.max()}")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)


if __name__ == "__main__":
    main()
