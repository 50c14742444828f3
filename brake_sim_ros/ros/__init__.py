"""ROS 2 adapter: the simulator as an rclpy node (``python -m brake_sim_ros.ros.node``).

The adapter translates, it holds no physics: the node steps
:class:`brake_sim_ros.solvers.fixed_step.FixedStepStepper` and publishes what it returns.

Modules:
    node: :class:`~brake_sim_ros.ros.node.BrakeSimNode` and ``main``.
    parameters: ROS parameter declarations generated from the core dataclasses.
    conversion: SampleBlock -> messages (no rclpy).
    qos: the QoS profiles of every topic, and why.
    pacing: real time, real-time factor, as fast as possible, paused (pure logic).
    commands: actuation-command checks and the command timeout behaviours (pure logic).
    diagnostics: run counters, the /diagnostics status and the end-of-run summary.
    harness: start a node process and talk to it (tests, benchmark).
    benchmark: CPU use, highest real-time factor, command latency.

Importing this package does not import rclpy; ``pacing`` and ``commands`` never do.
"""
