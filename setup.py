from glob import glob

from setuptools import find_packages, setup

package_name = 'trajplan_ros'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/urdf', glob('resource/*.urdf')),
    ],
    python_requires='>=3.10',
    install_requires=['setuptools', 'numpy'],
    extras_require={
        # The ROS 2 Jazzy runtime from PyPI, for machines without an apt/rosdep installation.
        'ros': ['ros-jazzy-rclpy', 'ros-jazzy-common-interfaces', 'ros-jazzy-rmw-fastrtps-cpp'],
        'test': ['pytest', 'colcon-common-extensions'],
        'bench': ['scipy', 'pyswarms', 'tqdm'],
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
        ],
    },
)
