#!/usr/bin/python3
"""Run-time scene editing from a Python client (rostest node_edit.test, after test_node_edit).

Spawns the package's obstacle_box (a 0.5 m cube) 2.5 m in front of the sensor through the node's
~spawn_model, checks the first scan stamped after the call sees its near face at 2.25 m, moves it
aside with ~set_model_pose, lists and deletes it, and checks the scan is again the one before the
spawn, bit for bit.
"""
import math
import unittest

import rospy
import rostest
from geometry_msgs.msg import Pose
from scan_buffer import ScanBuffer

from laser_raycast.srv import DeleteModel, ListModels, SetModelPose, SpawnModel

NODE = '/laser_raycast/'
WALL = 4.9  # m, the near face of test/data/edit_room.urdf's wall
ANGLES = [-0.4, -0.2, 0.0, 0.2, 0.4]  # the node's 5 beams


def pose_at(x, y):
    pose = Pose()
    pose.position.x = x
    pose.position.y = y
    pose.orientation.w = 1.0
    return pose


class EditClient(unittest.TestCase):
    def setUp(self):
        self.buffer = ScanBuffer('scan')
        for name in ('spawn_model', 'delete_model', 'set_model_pose', 'list_models'):
            rospy.wait_for_service(NODE + name, timeout=30)
        self.spawn = rospy.ServiceProxy(NODE + 'spawn_model', SpawnModel)
        self.delete = rospy.ServiceProxy(NODE + 'delete_model', DeleteModel)
        self.move = rospy.ServiceProxy(NODE + 'set_model_pose', SetModelPose)
        self.list = rospy.ServiceProxy(NODE + 'list_models', ListModels)

    def scan_after(self, stamp):
        """The first scan stamped after stamp."""
        scan = self.buffer.after(stamp)
        if scan is None:
            self.fail('no scan stamped after %s' % stamp)
        return scan

    def test_spawn_move_delete(self):
        before = self.scan_after(rospy.get_rostime())
        for a, r in zip(ANGLES, before.ranges):
            self.assertAlmostEqual(r, WALL / math.cos(a), delta=1e-5)

        res = self.spawn(name='py_box', file='package://laser_raycast/urdf/obstacle_box.urdf',
                         pose=pose_at(2.5, 0.0))
        self.assertTrue(res.success, res.message)
        scan = self.scan_after(rospy.get_rostime())
        self.assertAlmostEqual(scan.ranges[2], 2.25, delta=1e-5)
        self.assertAlmostEqual(scan.ranges[3], WALL / math.cos(0.2), delta=1e-5)

        self.assertIn('py_box', self.list().names)
        # Aside, out of every beam: the wall again.
        res = self.move(name='py_box', pose=pose_at(2.5, 3.0))
        self.assertTrue(res.success, res.message)
        scan = self.scan_after(rospy.get_rostime())
        self.assertAlmostEqual(scan.ranges[2], WALL, delta=1e-5)

        res = self.delete(name='py_box')
        self.assertTrue(res.success, res.message)
        self.assertNotIn('py_box', self.list().names)
        after = self.scan_after(rospy.get_rostime())
        self.assertEqual(list(after.ranges), list(before.ranges))

        # A refused request: the same name twice is fine once the first is gone; a missing file is
        # refused with its name.
        res = self.spawn(name='py_missing', file='/nonexistent/box.urdf')
        self.assertFalse(res.success)
        self.assertIn('/nonexistent/box.urdf', res.message)


if __name__ == '__main__':
    rospy.init_node('edit_client')
    rostest.rosrun('laser_raycast', 'node_edit_python', EditClient)
