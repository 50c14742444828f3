"""ROS 2 adapter: the simulator as an rclpy node, and a recording replayed on ROS 2.

The adapter translates, it holds no physics and no file format: the node steps the
stepper :func:`brake_sim_ros.stream.build.stepper_for` builds and publishes the stream of
:mod:`brake_sim_ros.stream`; it imports nothing from ``recording`` or ``viz`` (the
composition roots in :mod:`brake_sim_ros.app` attach those as sinks).

Modules:
    node: :class:`~brake_sim_ros.ros.node.BrakeSimNode`.
    replay: a node that publishes a checked recording with its original timing.
    qos: rclpy profiles of the topic table's QoS.
    messages: the message class of each type of the topic table.
    descriptors: ROS parameter descriptors of the node's parameter specs.
    budget: what a chunk costs on this machine (stepping, publishing), measured at start.
    pacing: real time, real-time factor, as fast as possible, paused (pure logic).
    commands: actuation-command checks and the command timeout behaviours (pure logic).
    diagnostics: run counters, the /diagnostics status and the end-of-run summary.
    harness: start a node process and talk to it (tests, benchmark).

Importing this package does not import rclpy; ``pacing`` and ``commands`` never do.
"""
