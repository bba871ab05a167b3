"""ROS 2 glue of matrix-tracker: conversions between core types and messages, settings as parameters."""
