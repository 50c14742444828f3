"""Rerun logging of the simulator stream: sink, drawing, blueprint, targets, MCAP viewing."""
