"""Detection: the detector interface, the baseline detectors, fitting and saving them, and
the scoring of detectors against the ground truth.

"Monitor" names one thing in this project: the ROS 2 node that runs a detector live
(``brake-sim monitor``; its adapter :mod:`brake_sim_ros.ros.monitor`, its composition root
:mod:`brake_sim_ros.app.monitor`). This package knows nothing of ROS."""
