"""The robot's sensors: a planar laser and odometry (what the robot believes)."""
