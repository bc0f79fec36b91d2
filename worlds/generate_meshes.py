#!/usr/bin/env python3
"""Writes the demo room's meshes into worlds/meshes/ (run it again after changing a dimension).

The meshes are closed, with vertices shared between neighbouring triangles, in metres:
- room_walls.stl (binary STL): four walls 0.1 m thick and 2.4 m high around an 8 m x 6 m floor, with a
  1 m wide doorway in the south wall. Each wall is split into a grid so that rows of vertices lie at the
  laser's height (0.25 m), the case where ray casters that are not watertight leak.
- table.stl (ASCII STL): a 1.6 m x 0.9 m table top at 0.75 m on four 0.06 m square legs.
- sofa.obj (OBJ): an L-shaped seat block with a back rest.
- pot.obj (OBJ): a plant pot, a 32-sided truncated cone.
Pure Python, no dependencies. The output is deterministic: the same dimensions give the same files.
"""
import argparse
import math
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "meshes")


class Mesh:
    def __init__(self):
        self.vertices = []
        self.index = {}
        self.triangles = []

    def vertex(self, p):
        key = tuple(round(c, 9) for c in p)
        if key not in self.index:
            self.index[key] = len(self.vertices)
            self.vertices.append(key)
        return self.index[key]

    def tri(self, a, b, c):
        self.triangles.append((self.vertex(a), self.vertex(b), self.vertex(c)))

    def quad(self, a, b, c, d):
        """Counter-clockwise seen from the front."""
        self.tri(a, b, c)
        self.tri(a, c, d)

    def box(self, lo, hi, zs=None):
        """A closed box; its side faces are split at the heights in zs (vertex rows)."""
        x0, y0, z0 = lo
        x1, y1, z1 = hi
        levels = sorted({z0, z1, *(z for z in (zs or []) if z0 < z < z1)})
        corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        for k in range(4):
            (ax, ay), (bx, by) = corners[k], corners[(k + 1) % 4]
            for za, zb in zip(levels, levels[1:]):
                self.quad((ax, ay, za), (bx, by, za), (bx, by, zb), (ax, ay, zb))
        self.quad((x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1))  # top, facing +z
        self.quad((x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0))  # bottom, facing -z

    def normal(self, t):
        a, b, c = (self.vertices[i] for i in t)
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        length = math.sqrt(sum(x * x for x in n)) or 1.0
        return [x / length for x in n]


def write_binary_stl(mesh, path, name):
    with open(path, "wb") as f:
        f.write(name.encode().ljust(80, b" ")[:80])
        f.write(struct.pack("<I", len(mesh.triangles)))
        for t in mesh.triangles:
            f.write(struct.pack("<3f", *mesh.normal(t)))
            for i in t:
                f.write(struct.pack("<3f", *mesh.vertices[i]))
            f.write(struct.pack("<H", 0))


def write_ascii_stl(mesh, path, name):
    with open(path, "w") as f:
        f.write("solid %s\n" % name)
        for t in mesh.triangles:
            f.write("  facet normal %.6f %.6f %.6f\n    outer loop\n" % tuple(mesh.normal(t)))
            for i in t:
                f.write("      vertex %.6f %.6f %.6f\n" % mesh.vertices[i])
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid %s\n" % name)


def write_obj(mesh, path, comment):
    with open(path, "w") as f:
        f.write("# %s\n" % comment)
        for v in mesh.vertices:
            f.write("v %.6f %.6f %.6f\n" % v)
        for t in mesh.triangles:
            f.write("f %d %d %d\n" % tuple(i + 1 for i in t))


def room_walls():
    m = Mesh()
    h, th = 2.4, 0.1
    rows = [0.25, 0.5, 1.0, 1.5, 2.0]  # vertex rows, one at the laser's height
    # The inner floor is 8 m x 6 m centred at the origin; the walls stand outside it. The south wall is
    # two boxes around a doorway at x in [1, 2].
    m.box((-4.0 - th, -3.0 - th, 0), (1.0, -3.0, h), rows)
    m.box((2.0, -3.0 - th, 0), (4.0 + th, -3.0, h), rows)
    m.box((-4.0 - th, 3.0, 0), (4.0 + th, 3.0 + th, h), rows)
    m.box((-4.0 - th, -3.0, 0), (-4.0, 3.0, h), rows)
    m.box((4.0, -3.0, 0), (4.0 + th, 3.0, h), rows)
    return m


def table():
    m = Mesh()
    lx, ly, top, th, leg = 1.6, 0.9, 0.75, 0.04, 0.06
    m.box((-lx / 2, -ly / 2, top - th), (lx / 2, ly / 2, top))
    for sx in (-1, 1):
        for sy in (-1, 1):
            cx, cy = sx * (lx / 2 - 0.08), sy * (ly / 2 - 0.08)
            m.box((cx - leg / 2, cy - leg / 2, 0), (cx + leg / 2, cy + leg / 2, top - th), [0.25])
    return m


def sofa():
    m = Mesh()
    m.box((0.0, 0.0, 0.0), (2.0, 0.9, 0.42), [0.25])    # seat
    m.box((0.0, 0.9, 0.0), (2.0, 1.1, 0.85), [0.25])    # back rest
    m.box((0.0, -0.9, 0.0), (0.9, 0.0, 0.42), [0.25])   # chaise
    return m


def pot(sides=32, r_bottom=0.16, r_top=0.22, height=0.45):
    m = Mesh()
    ring = lambda r, z: [(r * math.cos(2 * math.pi * k / sides), r * math.sin(2 * math.pi * k / sides), z)
                         for k in range(sides)]
    lo, hi = ring(r_bottom, 0.0), ring(r_top, height)
    for k in range(sides):
        j = (k + 1) % sides
        m.quad(lo[k], lo[j], hi[j], hi[k])
        m.tri((0.0, 0.0, height), hi[k], hi[j])
        m.tri((0.0, 0.0, 0.0), lo[j], lo[k])
    return m


class ArgumentParser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit status 2
        self.exit(2, "%s: %s (see --help)\n" % (self.prog, message))


def parse_args(argv):
    parser = ArgumentParser(prog="generate_meshes.py", description=__doc__.split("\n\n")[0],
                            epilog=__doc__.split("\n", 2)[2],
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", metavar="DIR", default=OUT,
                        help="directory to write the four meshes into, created if missing "
                        "(default: %(default)s, which worlds/demo_room.urdf uses)")
    return parser.parse_args(argv)


def main(argv):
    args = parse_args(argv)
    try:
        os.makedirs(args.out, exist_ok=True)
        out = lambda name: os.path.join(args.out, name)
        write_binary_stl(room_walls(), out("room_walls.stl"), "laser_raycast demo room walls")
        write_ascii_stl(table(), out("table.stl"), "table")
        write_obj(sofa(), out("sofa.obj"), "laser_raycast demo sofa (metres)")
        write_obj(pot(), out("pot.obj"), "laser_raycast demo plant pot (metres)")
    except OSError as e:
        sys.stderr.write("generate_meshes.py: cannot write %s: %s\n"
                         % (e.filename or args.out, e.strerror))
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
