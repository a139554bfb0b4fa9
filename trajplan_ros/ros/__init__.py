"""The ROS 2 side: the planner node, its settings, its work queue and message conversion."""
