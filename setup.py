# The Python package laser_raycast (python/laser_raycast), for catkin_python_setup(): never run it
# directly; catkin installs the package and builds its extension module (CMakeLists.txt).
from setuptools import setup

from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["laser_raycast"], package_dir={"": "python"}))
