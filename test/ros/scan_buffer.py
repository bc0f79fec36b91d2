"""The scans of a topic as the editing tests wait for them (edit_client.py, edit_rosservice.py)."""
import threading

import rospy
from sensor_msgs.msg import LaserScan


class ScanBuffer:
    """Keeps the last `kept` LaserScans of topic; after(stamp) is the first stamped after stamp."""

    def __init__(self, topic='scan', kept=100):
        self.lock = threading.Lock()
        self.kept = kept
        self.scans = []
        self.sub = rospy.Subscriber(topic, LaserScan, self.on_scan, queue_size=kept)

    def on_scan(self, scan):
        with self.lock:
            self.scans.append(scan)
            del self.scans[:-self.kept]

    def after(self, stamp, timeout=20.0):
        """The first scan stamped after stamp, or None after timeout seconds (ROS time)."""
        deadline = rospy.get_rostime() + rospy.Duration(timeout)
        while not rospy.is_shutdown() and rospy.get_rostime() < deadline:
            with self.lock:
                for scan in self.scans:
                    if scan.header.stamp > stamp:
                        return scan
            rospy.sleep(0.005)
        return None
