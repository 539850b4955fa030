"""ament_python package of the NemeSys reference vehicle node (``colcon build``)."""

from glob import glob

from setuptools import setup

PACKAGE = "nemesys_vehicle"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml", "README.md"]),
        (f"share/{PACKAGE}/launch", glob("launch/*.launch.py")),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
    ],
    # ROS convention: dependencies are in package.xml (rosdep: python3-serial); codec, planner,
    # onboard and vehicle_contract come from the nemesys-console checkout's vehicle/
    # distribution, installed alongside (README.md)
    install_requires=["setuptools"],
    # Humble's Python (3.10) and later: what CI tests (README.md, "Python versions")
    python_requires=">=3.10",
    zip_safe=True,
    maintainer="NemeSys Console maintainers",
    maintainer_email="nemesys@example.org",
    description="Reference ROS 2 node for a NemeSys AUV (the NemeSys Console vehicle contract)",
    license="MIT",
    entry_points={"console_scripts": ["vehicle_node = nemesys_vehicle.node:main"]},
)
