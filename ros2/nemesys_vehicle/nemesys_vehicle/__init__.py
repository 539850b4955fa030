"""NemeSys onboard node: the reference ROS 2 package (see README.md)."""
