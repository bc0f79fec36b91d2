#!/usr/bin/python3
"""Run-time scene editing from the command line (rostest node_edit.test, after edit_client.py).

Calls the node's four services as README's "Changing the world" shows, through `rosservice call`
with YAML arguments, in a child process each, and checks what it prints (the response as YAML)
and the first scan stamped after each call returns: the package's obstacle_box (a 0.5 m cube)
spawned 2 m in front of the sensor is seen at 1.75 m, moved aside it is gone, listed, deleted and
the ranges are again those from before the spawn, bit for bit; a bad request is answered
success: false with a message naming the problem, and the node scans on.
"""
import math
import subprocess
import unittest

import rospy
import rostest
import yaml
from scan_buffer import ScanBuffer

NODE = '/laser_raycast/'
WALL = 4.9  # m, the near face of test/data/edit_room.urdf's wall
ANGLES = [-0.4, -0.2, 0.0, 0.2, 0.4]  # the node's 5 beams


def rosservice(service, args=None):
    """`rosservice call /laser_raycast/SERVICE ARGS`: the response it prints, as a dict."""
    command = ['rosservice', 'call', NODE + service]
    if args is not None:
        command.append(args)
    done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=60, check=False)
    if done.returncode != 0:
        raise AssertionError('%s: exit status %d: %s' % (' '.join(command), done.returncode,
                                                         done.stderr))
    return yaml.safe_load(done.stdout)


class EditRosservice(unittest.TestCase):
    def setUp(self):
        self.buffer = ScanBuffer('scan')
        for name in ('spawn_model', 'delete_model', 'set_model_pose', 'list_models'):
            rospy.wait_for_service(NODE + name, timeout=30)

    def scan_after(self, stamp):
        """The first scan stamped after stamp."""
        scan = self.buffer.after(stamp)
        if scan is None:
            self.fail('no scan stamped after %s' % stamp)
        return scan

    def assert_wall(self, scan, what):
        for a, r in zip(ANGLES, scan.ranges):
            self.assertAlmostEqual(r, WALL / math.cos(a), delta=1e-5, msg=what)

    def test_spawn_move_list_delete(self):
        before = self.scan_after(rospy.get_rostime())
        self.assert_wall(before, 'before spawning')

        res = rosservice('spawn_model', "{name: cli_box, "
                         "file: 'package://laser_raycast/urdf/obstacle_box.urdf', "
                         "pose: {position: {x: 2.0, y: 0.0, z: 0.0}, orientation: {w: 1.0}}}")
        self.assertIs(res['success'], True, res)
        self.assertIn('cli_box', res['message'])
        scan = self.scan_after(rospy.get_rostime())
        # The middle beam meets the near face at 2 - 0.25 m; the beams at +-0.2 rad pass the cube
        # (at 1.75 m they are 0.35 m to the side).
        self.assertAlmostEqual(scan.ranges[2], 1.75, delta=1e-5)
        for i in (0, 1, 3, 4):
            self.assertAlmostEqual(scan.ranges[i], WALL / math.cos(ANGLES[i]), delta=1e-5)

        # Moved 3 m to the left, out of every beam.
        res = rosservice('set_model_pose', "{name: cli_box, "
                         "pose: {position: {x: 2.0, y: 3.0}, orientation: {w: 1.0}}}")
        self.assertIs(res['success'], True, res)
        self.assert_wall(self.scan_after(rospy.get_rostime()), 'cube moved aside')

        res = rosservice('list_models')
        self.assertEqual(len(res['names']), len(res['sources']))
        self.assertIn('cli_box', res['names'])
        self.assertIn('room', res['names'])

        res = rosservice('delete_model', '{name: cli_box}')
        self.assertIs(res['success'], True, res)
        after = self.scan_after(rospy.get_rostime())
        self.assertEqual(list(after.ranges), list(before.ranges))
        self.assertNotIn('cli_box', rosservice('list_models')['names'])

    def test_bad_requests(self):
        # Both urdf and file.
        res = rosservice('spawn_model', "{name: cli_both, urdf: '<robot name=\"b\"/>', "
                         "file: 'package://laser_raycast/urdf/obstacle_box.urdf'}")
        self.assertIs(res['success'], False, res)
        self.assertIn('exactly one', res['message'])
        # A URDF that is not XML.
        res = rosservice('spawn_model', "{name: cli_bad, urdf: '<robot name=\"b\"><link'}")
        self.assertIs(res['success'], False, res)
        self.assertIn("spawn_model 'cli_bad'", res['message'])
        # Unknown names.
        res = rosservice('delete_model', '{name: cli_nobody}')
        self.assertIs(res['success'], False, res)
        self.assertIn('cli_nobody', res['message'])
        res = rosservice('set_model_pose', "{name: cli_nobody, pose: {orientation: {w: 1.0}}}")
        self.assertIs(res['success'], False, res)
        self.assertIn('cli_nobody', res['message'])
        names = rosservice('list_models')['names']
        self.assertNotIn('cli_both', names)
        self.assertNotIn('cli_bad', names)
        # The node scans on.
        self.assert_wall(self.scan_after(rospy.get_rostime()), 'after the bad requests')


if __name__ == '__main__':
    rospy.init_node('edit_rosservice')
    rostest.rosrun('laser_raycast', 'node_edit_rosservice', EditRosservice)
