"""What ships under examples/ stays what its comments say it is."""

from __future__ import annotations

from pathlib import Path

from brake_sim_ros.campaigns.loader import load_campaign
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.scenarios.toml_text import dumps

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_demo_live_is_the_demo_campaigns_brake_at_its_sample_rate():
    """A detector fitted on the demo refuses another rate: the live example must be the
    demo's base scenario on the demo's brake (the service brake) at the demo's rate, and
    nothing else."""
    live = load_scenario(EXAMPLES / "demo_live.toml")
    demo = load_campaign("demo")
    assert live.sample_rate_hz == demo.outputs.sample_rate_hz == 5120.0
    assert live.setup.params.brake == demo.brake == "service"
    base = parse_scenario(dumps(demo.base_data), "the demo's base")
    base = base.with_solver(sample_rate_hz=demo.outputs.sample_rate_hz)
    assert (live.setup, live.solver) == (base.setup, base.solver)
    assert (live.duration_s, live.seed, live.needs) == (base.duration_s, base.seed, base.needs)
