"""Simulated laser scanners and lidars, from Python.

Load URDF models into a Scene, describe the beams with a Pattern, and cast them from many sensor
poses at once with a Caster; the results are numpy arrays. The scene, the casts and the REP 117
ranges are those of the node and of cast_scan (docs/python.md in the package).

    import numpy as np
    import laser_raycast as lr

    scene = lr.Scene.from_urdf("package://laser_raycast/worlds/demo_room.urdf")
    pattern = lr.Pattern.preset("UTM-30LX")
    poses = np.tile(np.eye(4), (100, 1, 1))
    poses[:, 0, 3] = np.linspace(-1.0, 1.0, 100)   # x of each sensor pose
    poses[:, 2, 3] = 0.3
    scans = lr.Caster().cast(scene, poses, pattern)
    scans.ranges.shape   # (100, 1081)
"""

from laser_raycast._laser_raycast import (  # noqa: F401 (the package's interface)
    Caster,
    Measurement,
    Pattern,
    Scans,
    Scene,
    SceneLoadError,
)

__all__ = ["Caster", "Measurement", "Pattern", "Scans", "Scene", "SceneLoadError"]
