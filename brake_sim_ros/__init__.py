"""brake-sim-ros: real-time drum-brake vibro-acoustic simulator for ROS 2."""

__version__ = "0.1.0"
