"""The physics core knows nothing of ROS, files formats or plots."""

import subprocess
import sys


def test_core_imports_no_adapter_libraries():
    code = (
        "import sys\n"
        "import brake_sim_ros.model.kernel, brake_sim_ros.solvers.fixed_step,"
        " brake_sim_ros.solvers.reference, brake_sim_ros.analysis.impacts,"
        " brake_sim_ros.scenarios, brake_sim_ros.sensing.sensors, brake_sim_ros.sensing.structure\n"
        "bad = [m for m in sys.modules if m.split('.')[0] in"
        " ('rclpy', 'mcap', 'mcap_ros2', 'rerun', 'matplotlib', 'brake_sim_msgs')]\n"
        "print(bad)\n"
        "sys.exit(1 if bad else 0)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
