"""``python -m brake_sim_ros.cli``: the same as ``brake-sim``."""

import sys

from brake_sim_ros.cli import main

sys.exit(main())
