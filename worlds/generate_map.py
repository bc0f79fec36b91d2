#!/usr/bin/env python3
"""Writes map_server maps of rooms: the demo map world (worlds/maps/demo_office.png and .yaml, the
default), or a large one for measuring (--cells N --out DIR/NAME).

A map is a grid of square rooms (--room cells a side) behind an outer wall, with walls 3 cells thick
between them, a door 18 cells wide in each inner wall, random furniture (rectangles) in every room, a
diagonal wall in every fifth room (a staircase of cells, the case that makes boxes of single rows),
and --speckle, the share of free cells left occupied at random as a SLAM map has them. Black
(occupied) and white (free) pixels, with the unknown grey (205) outside the outer wall. PNG for the
.png name, binary PGM for .pgm. Pure Python, no dependencies; a seed gives the same file.
"""
import argparse
import os
import random
import struct
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
FREE, OCCUPIED, UNKNOWN = 254, 0, 205


def make_rooms(cells, room, speckle, seed):
    """The map's rows (bytearrays), the top row first."""
    rng = random.Random(seed)
    margin = 4  # unknown cells around the outer wall
    rows = [bytearray([UNKNOWN]) * cells for _ in range(cells)]
    inside = range(margin, cells - margin)

    def fill(x0, y0, x1, y1, value):
        # y counts from the bottom of the map, as map_server's cells do.
        x0, x1 = max(x0, 0), min(x1, cells)
        for y in range(max(y0, 0), min(y1, cells)):
            rows[cells - 1 - y][x0:x1] = bytes([value]) * (x1 - x0)

    fill(margin, margin, cells - margin, cells - margin, OCCUPIED)
    fill(margin + 3, margin + 3, cells - margin - 3, cells - margin - 3, FREE)
    lo, hi = inside.start + 3, inside.stop - 3
    lines = list(range(lo + room, hi - 3, room))
    for x in lines:  # inner walls along y, a door between each pair of crossings
        fill(x, lo, x + 3, hi, OCCUPIED)
        for y in [lo] + [l + 3 for l in lines]:
            top = min([l for l in lines if l > y] + [hi])
            if top - y > 30:
                door = rng.randrange(y + 6, top - 24)
                fill(x, door, x + 3, door + 18, FREE)
    for y in lines:  # inner walls along x
        fill(lo, y, hi, y + 3, OCCUPIED)
        for x in [lo] + [l + 3 for l in lines]:
            right = min([l for l in lines if l > x] + [hi])
            if right - x > 30:
                door = rng.randrange(x + 6, right - 24)
                fill(door, y, door + 18, y + 3, FREE)
    starts = [lo] + [l + 3 for l in lines]
    count = 0
    for y0 in starts:
        for x0 in starts:
            count += 1
            size = min(room - 3, hi - max(x0, y0))
            if size < 20:
                continue
            for _ in range(rng.randrange(2, 6)):  # furniture away from the doors
                w, h = rng.randrange(4, size // 3), rng.randrange(4, size // 3)
                x, y = rng.randrange(x0 + 8, x0 + size - 8 - w), rng.randrange(y0 + 8, y0 + size - 8 - h)
                fill(x, y, x + w, y + h, OCCUPIED)
            if count % 5 == 0:  # a diagonal wall across the room's middle third
                for k in range(size // 3):
                    x, y = x0 + size // 3 + k, y0 + size // 3 + k
                    fill(x, y, x + 3, y + 1, OCCUPIED)
    if speckle > 0:
        for _ in range(int(speckle * (hi - lo) ** 2)):
            x, y = rng.randrange(lo, hi), rng.randrange(lo, hi)
            row = rows[cells - 1 - y]
            if row[x] == FREE:
                row[x] = OCCUPIED
    return rows


def write_png(path, rows):
    width, height = len(rows[0]), len(rows)
    raw = b"".join(b"\x00" + bytes(row) for row in rows)  # filter type 0 on every row

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def write_pgm(path, rows):
    with open(path, "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (len(rows[0]), len(rows)))
        for row in rows:
            f.write(row)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=os.path.join(HERE, "maps", "demo_office.png"),
                        help="the image to write (.png or .pgm); the YAML goes beside it")
    parser.add_argument("--cells", type=int, default=200, help="cells a side (default 200)")
    parser.add_argument("--room", type=int, default=96, help="cells a side of a room (default 96)")
    parser.add_argument("--resolution", type=float, default=0.05, help="m a cell (default 0.05)")
    parser.add_argument("--speckle", type=float, default=0.0,
                        help="share of free cells made occupied at random (default 0)")
    parser.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    args = parser.parse_args()
    if args.cells < 50 or args.room < 40:
        sys.exit("generate_map.py: --cells must be >= 50 and --room >= 40")
    rows = make_rooms(args.cells, args.room, args.speckle, args.seed)
    image = args.out
    os.makedirs(os.path.dirname(os.path.abspath(image)), exist_ok=True)
    (write_png if image.endswith(".png") else write_pgm)(image, rows)
    half = args.cells * args.resolution / 2
    with open(os.path.splitext(image)[0] + ".yaml", "w") as f:
        f.write("# Written by worlds/generate_map.py --cells %d --room %d --resolution %g "
                "--speckle %g --seed %d\n" % (args.cells, args.room, args.resolution, args.speckle,
                                              args.seed))
        f.write("image: %s\nresolution: %g\norigin: [%g, %g, 0.0]\nnegate: 0\n"
                "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n"
                % (os.path.basename(image), args.resolution, -half, -half))


if __name__ == "__main__":
    main()
