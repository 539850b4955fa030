"""A dive as the robotics tools read it: MCAP and rosbag2 exports of the mission log, in ROS 2
message types (the typed NemeSys messages of ``ros2/nemesys_msgs``)."""
