"""Domain errors. Each subclasses the built-in it refines, so callers may catch either."""


class BrakeSimError(Exception):
    """Base of every error this package raises on purpose."""


class ParameterError(BrakeSimError, ValueError):
    """A physical parameter, defect or actuation value outside the model's validity."""


class StepSizeError(BrakeSimError, ValueError):
    """A fixed step larger than the stability or accuracy limit of the current model."""


class ScenarioError(BrakeSimError, ValueError):
    """A scenario file that cannot be loaded: unknown key, wrong type, bad value."""


class SimulationError(BrakeSimError, RuntimeError):
    """The integration failed (non-finite state, solver failure)."""


class FidelityError(BrakeSimError, ValueError):
    """Needs that no model level can serve, or a forced level that cannot deliver them."""
