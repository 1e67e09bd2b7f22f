"""Thin ROS 2 node wrappers around hand_codesign.core."""
