from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["cell_nodes", "cell_nodes.manual", "cell_nodes.alarms", "cell_nodes.modules", "cell_nodes.parameters", "cell_nodes.process", "cell_nodes.routines"], package_dir={"": "src"}))
