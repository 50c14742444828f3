"""Brake health monitoring: the detector interface, baseline detectors and the scoring of
detectors against the ground truth (issue "Monitoring")."""
