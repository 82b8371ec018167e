#!/usr/bin/env python3
"""Writes the OBJ models of the voxel cone tracing scenes (assets/scenes/vct_*.toml):
a Cornell-like box, a two-room floor plan with a zero-thickness dividing wall (light
leaking) and a floor meeting a wall (over-occlusion in the corner)."""

import os

HERE = os.path.dirname(os.path.abspath(__file__))
MODELS = os.path.join(HERE, "..", "assets", "models")


def quad(a, b, c, d):
    """Two triangles of the quad a-b-c-d (counter-clockwise seen from the front)."""
    return [(a, b, c), (a, c, d)]


def box(lo, hi):
    """The six faces of an axis-aligned box, facing outwards."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    p = lambda x, y, z: (x, y, z)
    tris = []
    tris += quad(p(x0, y0, z1), p(x1, y0, z1), p(x1, y1, z1), p(x0, y1, z1))  # +z
    tris += quad(p(x1, y0, z0), p(x0, y0, z0), p(x0, y1, z0), p(x1, y1, z0))  # -z
    tris += quad(p(x1, y0, z1), p(x1, y0, z0), p(x1, y1, z0), p(x1, y1, z1))  # +x
    tris += quad(p(x0, y0, z0), p(x0, y0, z1), p(x0, y1, z1), p(x0, y1, z0))  # -x
    tris += quad(p(x0, y1, z1), p(x1, y1, z1), p(x1, y1, z0), p(x0, y1, z0))  # +y
    tris += quad(p(x0, y0, z0), p(x1, y0, z0), p(x1, y0, z1), p(x0, y0, z1))  # -y
    return tris


def write(name, comment, tris):
    lines = [f"# {comment}", "# Written by scripts/make_vct_assets.py."]
    for t in tris:
        for v in t:
            lines.append("v %g %g %g" % v)
    for i in range(len(tris)):
        lines.append("f %d %d %d" % (3 * i + 1, 3 * i + 2, 3 * i + 3))
    with open(os.path.join(MODELS, name), "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    # Cornell-like box: x, z in [-1, 1], y in [0, 2], open towards +z.
    write("vct_cornell_white.obj", "Cornell-like box: floor, ceiling, back wall.",
          quad((-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1))
          + quad((-1, 2, -1), (1, 2, -1), (1, 2, 1), (-1, 2, 1))
          + quad((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1)))
    write("vct_cornell_red.obj", "Cornell-like box: left wall.",
          quad((-1, 0, 1), (-1, 0, -1), (-1, 2, -1), (-1, 2, 1)))
    write("vct_cornell_green.obj", "Cornell-like box: right wall.",
          quad((1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1)))
    write("vct_cornell_blocks.obj", "Cornell-like box: a tall and a short block.",
          box((-0.7, 0, -0.6), (-0.1, 1.2, 0.0)) + box((0.15, 0, 0.05), (0.7, 0.55, 0.6)))
    write("vct_cornell_lamp.obj", "Cornell-like box: emissive panel below the ceiling.",
          quad((-0.3, 1.98, 0.3), (-0.3, 1.98, -0.3), (0.3, 1.98, -0.3), (0.3, 1.98, 0.3)))
    # Two rooms, x in [-2, 2], z in [-1, 1], walls 1 high, no ceiling; the rooms share a
    # zero-thickness wall at x = 0.
    write("vct_leak_rooms.obj", "Two rooms sharing a zero-thickness wall at x = 0.",
          quad((-2, 0, 1), (2, 0, 1), (2, 0, -1), (-2, 0, -1))
          + quad((-2, 0, -1), (2, 0, -1), (2, 1, -1), (-2, 1, -1))
          + quad((2, 0, 1), (-2, 0, 1), (-2, 1, 1), (2, 1, 1))
          + quad((-2, 0, 1), (-2, 0, -1), (-2, 1, -1), (-2, 1, 1))
          + quad((2, 0, -1), (2, 0, 1), (2, 1, 1), (2, 1, -1))
          + quad((0, 0, -1), (0, 0, 1), (0, 1, 1), (0, 1, -1)))
    # A floor x in [0, 4], z in [-2, 2], meeting a wall 1 high at x = 0.
    write("vct_corner_floor.obj", "Floor of the corner scene.",
          quad((0, 0, 2), (4, 0, 2), (4, 0, -2), (0, 0, -2)))
    write("vct_corner_wall.obj", "Wall of the corner scene.",
          quad((0, 0, -2), (0, 0, 2), (0, 1, 2), (0, 1, -2)))


if __name__ == "__main__":
    main()
