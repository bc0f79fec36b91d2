#!/usr/bin/python3
"""launch/map_world.launch as its users run it (rostest map_world.test): the demo robot drives in
the demo office map's walls, and the 2D laser's scans (/scan, 720 beams all round) are checked
against the map itself. This test reads the map's YAML and PNG image on its own (a PNG decoder of a
few lines: 8-bit grey, the rows' filters), takes the laser's pose at each scan's stamp from TF, and
for every beam finds the nearest occupied cell, as a closed square, along the beam by brute force
(each cell the beam passes, and its neighbours); the range must be that distance within 1e-5 m
(+Inf beyond range_max).
"""
import math
import os
import struct
import unittest
import zlib

import rospkg
import rospy
import rostest
import tf2_ros
import yaml
from scan_buffer import ScanBuffer

RANGE_MAX = 12.0  # m, map_world.launch's range_max
TOLERANCE = 1e-5  # m: float ranges of up to 12 m, and TF's pose at the stamp (measured: 1.3e-6)
SCANS = 3


def read_png_grey(path):
    """The rows (top first) of an 8-bit greyscale PNG, as lists of values."""
    with open(path, 'rb') as f:
        data = f.read()
    assert data[:8] == b'\x89PNG\r\n\x1a\n', path
    pos, idat, width, height = 8, b'', 0, 0
    while pos < len(data):
        (length,) = struct.unpack('>I', data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        if kind == b'IHDR':
            width, height, depth, colour, _, _, interlace = struct.unpack('>IIBBBBB', body)
            assert (depth, colour, interlace) == (8, 0, 0), 'not 8-bit grey: %s' % path
        elif kind == b'IDAT':
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    rows, previous = [], [0] * width
    for r in range(height):
        line = raw[r * (width + 1):(r + 1) * (width + 1)]
        kind, row = line[0], list(line[1:])
        for i in range(width):
            left = row[i - 1] if i > 0 else 0
            up, corner = previous[i], previous[i - 1] if i > 0 else 0
            if kind == 1:
                row[i] = (row[i] + left) & 255
            elif kind == 2:
                row[i] = (row[i] + up) & 255
            elif kind == 3:
                row[i] = (row[i] + (left + up) // 2) & 255
            elif kind == 4:
                p = left + up - corner
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - corner)
                pred = left if pa <= pb and pa <= pc else up if pb <= pc else corner
                row[i] = (row[i] + pred) & 255
        rows.append(row)
        previous = row
    return rows


class Map:
    """A map_server map's occupied cells (trinary; unknown cells are free, as the node has them)."""

    def __init__(self, yaml_path):
        with open(yaml_path) as f:
            info = yaml.safe_load(f)
        rows = read_png_grey(os.path.join(os.path.dirname(yaml_path), info['image']))
        assert info.get('mode', 'trinary') == 'trinary' and info['origin'][2] == 0, info
        self.resolution = float(info['resolution'])
        self.ox, self.oy = float(info['origin'][0]), float(info['origin'][1])
        negate, threshold = int(info['negate']), float(info['occupied_thresh'])
        self.occupied = set()
        for r, row in enumerate(rows):
            for i, value in enumerate(row):
                occupancy = value / 255.0 if negate else (255 - value) / 255.0
                if occupancy > threshold:
                    self.occupied.add((i, len(rows) - 1 - r))  # cell rows bottom up

    def cell_entry(self, cell, sx, sy, dx, dy):
        """Where the ray (sx, sy) + t (dx, dy), t >= 0, enters cell's closed square, or None."""
        lo, hi = 0.0, math.inf
        for s, d, o, c in ((sx, dx, self.ox, cell[0]), (sy, dy, self.oy, cell[1])):
            a, b = o + c * self.resolution, o + (c + 1) * self.resolution
            if d == 0:
                if not a <= s <= b:
                    return None
                continue
            t0, t1 = (a - s) / d, (b - s) / d
            lo, hi = max(lo, min(t0, t1)), min(hi, max(t0, t1))
        return lo if lo <= hi else None

    def distance(self, sx, sy, angle, reach):
        """The distance to the nearest occupied cell along the beam, or inf beyond reach. Samples
        half a cell apart: every cell the beam passes is within a cell of a sample's."""
        dx, dy = math.cos(angle), math.sin(angle)
        best, t, step = math.inf, 0.0, self.resolution / 2
        seen = set()
        while t <= min(best, reach) + 2 * self.resolution:
            ci = math.floor((sx + t * dx - self.ox) / self.resolution)
            cj = math.floor((sy + t * dy - self.oy) / self.resolution)
            for cell in ((ci + a, cj + b) for a in (-1, 0, 1) for b in (-1, 0, 1)):
                if cell in self.occupied and cell not in seen:
                    seen.add(cell)
                    entry = self.cell_entry(cell, sx, sy, dx, dy)
                    if entry is not None:
                        best = min(best, entry)
            t += step
        return best if best <= reach else math.inf


class MapWorld(unittest.TestCase):
    def test_scans_match_the_map(self):
        path = os.path.join(rospkg.RosPack().get_path('laser_raycast'), 'worlds', 'maps',
                            'demo_office.yaml')
        world = Map(path)
        self.assertGreater(len(world.occupied), 100)
        tf = tf2_ros.Buffer()
        tf2_ros.TransformListener(tf)
        scans = ScanBuffer('scan')
        # The node's beams: samples 720 from angle_min to angle_max (its parameters).
        node = rospy.get_param('/laser_raycast/sensors')[0]
        samples = int(node['samples'])
        first = scans.after(rospy.Time(0), timeout=60)
        self.assertIsNotNone(first, 'no scan on /scan')
        # A scan stamped before this listener heard its first transform cannot be looked up (the
        # node may have been scanning for a while): start from one stamped after the buffer has
        # the laser's pose.
        self.assertTrue(tf.can_transform('map', first.header.frame_id, rospy.Time(0),
                                         rospy.Duration(10)), 'no transform map -> laser')
        scan = scans.after(rospy.Time.now(), timeout=60)
        self.assertIsNotNone(scan, 'no scan on /scan after the transforms came')
        for k in range(SCANS):
            self.assertEqual(len(scan.ranges), samples)
            laser = tf.lookup_transform('map', scan.header.frame_id, scan.header.stamp,
                                        rospy.Duration(5)).transform
            q = laser.rotation
            # Level (the robot drives on the floor): the beams are horizontal.
            self.assertAlmostEqual(q.x, 0, delta=1e-9)
            self.assertAlmostEqual(q.y, 0, delta=1e-9)
            yaw = 2 * math.atan2(q.z, q.w)
            sx, sy = laser.translation.x, laser.translation.y
            hits, worst = 0, 0.0
            for i, r in enumerate(scan.ranges):
                # The node's angles, from -pi to pi, in double (the message's are floats).
                angle = -math.pi + i * (2 * math.pi / (samples - 1))
                exact = world.distance(sx, sy, yaw + angle, RANGE_MAX)
                if math.isinf(exact):
                    self.assertTrue(math.isinf(r) and r > 0, 'scan %d beam %d: %r' % (k, i, r))
                else:
                    hits += 1
                    worst = max(worst, abs(r - exact))
                    self.assertLessEqual(abs(r - exact), TOLERANCE,
                                         'scan %d beam %d at (%.6f, %.6f) yaw %.6f: %r, map %r'
                                         % (k, i, sx, sy, yaw + angle, r, exact))
            print('scan %d at (%.3f, %.3f): %d beams on walls, worst error %.3g m, %d beyond range'
                  % (k, sx, sy, hits, worst, samples - hits))
            self.assertGreater(hits, samples // 2)
            # A later scan: the robot has moved on.
            scan = scans.after(scan.header.stamp + rospy.Duration(1.0))
            self.assertIsNotNone(scan)


if __name__ == '__main__':
    rospy.init_node('map_world_client')
    rostest.rosrun('laser_raycast', 'map_world', MapWorld)
