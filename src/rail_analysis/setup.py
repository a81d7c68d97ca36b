# The rail_analysis Python package (src/rail_analysis), installed by catkin_python_setup().
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["rail_analysis"], package_dir={"": "src"}))
