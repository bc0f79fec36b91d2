#!/usr/bin/python3
"""A warehouse and a 60 s drive through it, for measuring simulate_bag's speed (README,
"Re-simulating a recorded bag"). Writes into DIR (not the repository: scans.bag is ~290 MB):

  rack.stl        one bay of pallet racking, 3,828 triangles: C-profile uprights, braced side
                  frames, beams, wire decking and cartons on four levels
  warehouse.urdf  a closed building of 64 x 44 x 8 m (walls, floor and roof are boxes) with 312
                  bays of rack.stl in 16 rows along 8 aisles and a cross aisle (1.19M triangles),
                  120 drums (cylinders) on 60 pallets and 30 pallet stacks (boxes) by the end walls
  drive.bag       /tf_static (base_link -> velodyne, 1.2 m up) and /tf at 100 Hz for 60 s:
                  base_link driving at 1 m/s down an aisle (56 m), then turning towards the next,
                  its heading swaying by 1 degree either side every 4 s as a robot's controller
                  holds its line (never two TF samples with one heading)
  config.yaml     the node's parameters: a rotating VLP-16 (its preset, 10 Hz) on velodyne

Then:  rosrun laser_raycast simulate_bag --input DIR/drive.bag --output DIR/scans.bag \\
           --config DIR/config.yaml
"""
import math
import os
import struct
import sys

import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from tf2_msgs.msg import TFMessage

# The building's inside and the bays (m).
HALF_X, HALF_Y, HEIGHT, WALL = 32.0, 22.0, 8.0, 0.3
BAY_LENGTH, BAY_DEPTH, RACK_HEIGHT = 2.7, 1.1, 4.0
BAYS_PER_SECTION, CROSS_AISLE = 10, 3.0
ROW_PAIRS, FLUE, AISLE = 8, 0.1, 3.2
LEVELS = (0.15, 1.15, 2.15, 3.15)
SPEED, TF_RATE, DURATION, SENSOR_Z = 1.0, 100.0, 60.0, 1.2
# The heading's sway about the path (rad, s): a robot that follows a line corrects its heading all
# the time; a drive of exactly one heading would flatter the caster (no sample's rotation differs).
SWAY, SWAY_PERIOD = math.radians(1.0), 4.0


def box(centre, size, yaw=0.0, roll=0.0):
    """The 12 triangles of a box, outward faces, turned by roll about x then yaw about z."""
    hx, hy, hz = (s / 2 for s in size)
    corners = [(sx * hx, sy * hy, sz * hz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]

    def place(p):
        x, y, z = p
        y, z = y * math.cos(roll) - z * math.sin(roll), y * math.sin(roll) + z * math.cos(roll)
        x, y = x * math.cos(yaw) - y * math.sin(yaw), x * math.sin(yaw) + y * math.cos(yaw)
        return (x + centre[0], y + centre[1], z + centre[2])

    c = [place(p) for p in corners]
    # Corner index = 4 sx + 2 sy + sz (0: minus, 1: plus); each face as two counter-clockwise
    # triangles seen from outside.
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    for a, b, d, e in faces:
        tris.append((c[a], c[b], c[d]))
        tris.append((c[a], c[d], c[e]))
    return tris


def rack():
    """One bay: origin on the floor at its centre, x along the aisle, y across, front at +y."""
    t = []
    ux, uy = BAY_LENGTH / 2 - 0.05, BAY_DEPTH / 2 - 0.05
    # Uprights: C-profiles of a web and two flanges, open towards the bay.
    for sx in (-1, 1):
        for sy in (-1, 1):
            x, y = sx * ux, sy * uy
            t += box((x + sx * 0.034, y, RACK_HEIGHT / 2), (0.0025, 0.09, RACK_HEIGHT))
            for f in (-1, 1):
                t += box((x, y + f * 0.044, RACK_HEIGHT / 2), (0.07, 0.0025, RACK_HEIGHT))
    # Side frames: horizontal and diagonal tubes between the front and back uprights.
    for sx in (-1, 1):
        for i in range(5):
            t += box((sx * ux, 0, 0.3 + 0.9 * i), (0.03, 2 * uy, 0.03))
        for i in range(4):
            roll = math.atan2(0.9, 2 * uy) * (1 if i % 2 else -1)
            length = math.hypot(0.9, 2 * uy)
            t += box((sx * ux, 0, 0.75 + 0.9 * i), (0.03, length, 0.03), roll=roll)
    for z in LEVELS:
        # Two beams, three support channels, wire decking across the depth every 4 cm.
        for sy in (-1, 1):
            t += box((0, sy * uy, z), (2 * ux, 0.05, 0.12))
        for x in (-0.9, 0.0, 0.9):
            t += box((x, 0, z + 0.07), (0.04, 2 * uy, 0.02))
        wires = int(2 * ux / 0.04)
        for i in range(wires):
            t += box((-ux + 0.04 * (i + 0.5), 0, z + 0.085), (0.005, 2 * uy, 0.005))
        # Three cartons on each deck but the top one's.
        if z < LEVELS[-1]:
            for k, x in enumerate((-0.85, 0.0, 0.85)):
                h = 0.5 + 0.1 * ((k + int(z)) % 3)
                t += box((x, 0.05 * (k - 1), z + 0.09 + h / 2), (0.75, 0.9, h))
    return t


def write_stl(path, tris):
    with open(path, "wb") as f:
        f.write(b"\0" * 80)
        f.write(struct.pack("<I", len(tris)))
        for a, b, c in tris:
            f.write(struct.pack("<3f", 0, 0, 0))
            for p in (a, b, c):
                f.write(struct.pack("<3f", *p))
            f.write(b"\0\0")


def bays():
    """(x, y, yaw) of each bay: rows back to back in pairs, single rows against the long walls."""
    out = []
    pitch = (2 * HALF_Y - 2 * BAY_DEPTH - AISLE) / ROW_PAIRS
    rows = [(-HALF_Y + BAY_DEPTH / 2 + 0.1, 0.0)]
    for p in range(1, ROW_PAIRS):
        centre = -HALF_Y + BAY_DEPTH + 0.1 + p * pitch - AISLE / 2 + (pitch - AISLE) / 2
        rows.append((centre - BAY_DEPTH / 2 - FLUE / 2, math.pi))
        rows.append((centre + BAY_DEPTH / 2 + FLUE / 2, 0.0))
    rows.append((HALF_Y - BAY_DEPTH / 2 - 0.1, math.pi))
    for y, yaw in rows:
        for side in (-1, 1):
            for i in range(BAYS_PER_SECTION):
                x = side * (CROSS_AISLE / 2 + BAY_LENGTH * (i + 0.5))
                out.append((x, y, yaw))
    return out[: len(out) - 8]  # a staging area by the last wall


def aisles():
    """The y of each aisle's centre line: midway between two neighbouring rows that do not stand
    back to back (those are a bay's depth and the flue apart)."""
    rows = sorted(set(round(y, 6) for _, y, _ in bays()))
    return [(a + b) / 2 for a, b in zip(rows, rows[1:]) if b - a > BAY_DEPTH + FLUE + 1e-6]


def urdf(rack_path):
    v = []

    def visual(xyz, rpy, geometry):
        v.append('    <visual><origin xyz="%.4f %.4f %.4f" rpy="%.4f %.4f %.4f"/>'
                 '<geometry>%s</geometry></visual>' % (xyz + rpy + (geometry,)))

    for x, y, yaw in bays():
        visual((x, y, 0), (0, 0, yaw), '<mesh filename="file://%s"/>' % rack_path)
    sx, sy = 2 * HALF_X + 2 * WALL, 2 * HALF_Y + 2 * WALL
    visual((0, 0, -WALL / 2), (0, 0, 0), '<box size="%g %g %g"/>' % (sx, sy, WALL))
    visual((0, 0, HEIGHT + WALL / 2), (0, 0, 0), '<box size="%g %g %g"/>' % (sx, sy, WALL))
    for s in (-1, 1):
        visual((s * (HALF_X + WALL / 2), 0, HEIGHT / 2), (0, 0, 0),
               '<box size="%g %g %g"/>' % (WALL, sy, HEIGHT))
        visual((0, s * (HALF_Y + WALL / 2), HEIGHT / 2), (0, 0, 0),
               '<box size="%g %g %g"/>' % (sx, WALL, HEIGHT))
    # Drums on pallets and stacks of pallets along the end walls.
    for s in (-1, 1):
        for i in range(30):
            x, y = s * (HALF_X - 1.0), -HALF_Y + 3 + 1.3 * i
            visual((x, y, 0.072), (0, 0, 0), '<box size="0.8 1.2 0.144"/>')
            for dy in (-0.3, 0.3):
                visual((x, y + dy, 0.144 + 0.44), (0, 0, 0),
                       '<cylinder radius="0.29" length="0.88"/>')
            if i % 2 == 0:
                visual((x - s * 1.2, y, 0.36), (0, 0, 0), '<box size="0.8 1.2 0.72"/>')
    return ('<?xml version="1.0"?>\n<robot name="warehouse">\n  <link name="map">\n%s\n'
            '  </link>\n</robot>\n' % "\n".join(v))


def pose_at(s, y0, y1):
    """base_link at s m along the path: down the aisle at y0 in +x, a U-turn to y1, back in -x."""
    straight = 2 * (HALF_X - 4.0)
    radius = abs(y1 - y0) / 2
    x0 = -(HALF_X - 4.0)
    if s <= straight:
        return x0 + s, y0, 0.0
    s -= straight
    arc = math.pi * radius
    if s <= arc:
        a = s / radius
        return x0 + straight + radius * math.sin(a), y0 + radius * (1 - math.cos(a)), a
    return x0 + straight - (s - arc), y1, math.pi


def swayed(s, x, y, yaw):
    """The pose at s m along the path, its heading turned by the sway and moved sideways by what
    that heading makes of the distance (v sin(sway), integrated: 1.1 cm either side)."""
    w = 2 * math.pi / SWAY_PERIOD
    t = s / SPEED
    side = -SPEED * SWAY / w * math.cos(w * t)
    return x - side * math.sin(yaw), y + side * math.cos(yaw), yaw + SWAY * math.sin(w * t)


def transform(stamp, parent, child, x, y, z, yaw):
    t = TransformStamped()
    t.header.stamp = stamp
    t.header.frame_id = parent
    t.child_frame_id = child
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = x, y, z
    t.transform.rotation.z, t.transform.rotation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return t


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = os.path.abspath(sys.argv[1])
    os.makedirs(out, exist_ok=True)
    rack_path = os.path.join(out, "rack.stl")
    tris = rack()
    write_stl(rack_path, tris)
    with open(os.path.join(out, "warehouse.urdf"), "w") as f:
        f.write(urdf(rack_path))
    with open(os.path.join(out, "config.yaml"), "w") as f:
        f.write("fixed_frame: map\nmodels: [{file: %s}]\n"
                "sensors:\n  - {name: lidar, frame_id: velodyne, topic: points, "
                "sensor_model: VLP-16, sweep: rotating}\n" % os.path.join(out, "warehouse.urdf"))
    y0, y1 = aisles()[3], aisles()[4]
    start = rospy.Time(1700000000)
    with rosbag.Bag(os.path.join(out, "drive.bag"), "w") as bag:
        bag.write("/tf_static", TFMessage([transform(start, "base_link", "velodyne", 0, 0,
                                                     SENSOR_Z, 0)]), start)
        for i in range(int(DURATION * TF_RATE) + 1):
            t = start + rospy.Duration(i / TF_RATE)
            x, y, yaw = swayed(SPEED * i / TF_RATE, *pose_at(SPEED * i / TF_RATE, y0, y1))
            bag.write("/tf", TFMessage([transform(t, "map", "base_link", x, y, 0, yaw)]), t)
    print("%d triangles a bay, %d bays: %d triangles; %s" %
          (len(tris), len(bays()), len(tris) * len(bays()), out))


if __name__ == "__main__":
    main()
