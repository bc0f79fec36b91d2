#!/usr/bin/env python3
"""Writes the surface-attribute test meshes (test_surface_reflectance.cpp) into this directory:
checker.png (8 x 8 texels, white where column + row is even, row 0 at the top), a wall textured
with it (checker_wall.obj/.mtl: x = 2, y and z in [-1, 1], u = (y + 1) / 2, v = (z + 1) / 2), a
vertex-coloured triangle (rgb_triangle.ply: x = 3, red (-1, -1), green (1, -1), blue (0, 1) in
(y, z)), and a wall with vertex normals tilted 45 degrees about z (tilted_normals.obj)."""
import struct
import zlib

N = 8


def png(path, rows):
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))
    raw = b"".join(b"\0" + bytes(v for pixel in row for v in pixel) for row in rows)
    header = struct.pack(">IIBBBBB", len(rows[0]), len(rows), 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) +
                chunk(b"IEND", b""))


png("checker.png", [[(255, 255, 255) if (c + r) % 2 == 0 else (0, 0, 0) for c in range(N)]
                    for r in range(N)])
with open("checker_wall.mtl", "w") as f:
    f.write("newmtl checker\nKd 0.5 0.5 0.5\nmap_Kd checker.png\n")
with open("checker_wall.obj", "w") as f:
    f.write("mtllib checker_wall.mtl\n"
            "v 2 -1 -1\nv 2 1 -1\nv 2 1 1\nv 2 -1 1\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
            "usemtl checker\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
with open("rgb_triangle.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "3 -1 -1 255 0 0\n3 1 -1 0 255 0\n3 0 1 0 0 255\n3 0 1 2\n")
with open("tilted_normals.obj", "w") as f:
    f.write("v 2 -1 -1\nv 2 1 -1\nv 2 1 1\nv 2 -1 1\n"
            "vn -1 1 0\n"
            "f 1//1 2//1 3//1\nf 1//1 3//1 4//1\n")
