"""ROS 2 node around physics_core: stepping, commands, outputs, recording and replay."""
