"""ROS ``ParameterDescriptor`` of each parameter spec of :mod:`brake_sim_ros.stream.parameters`."""

from __future__ import annotations

from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    ParameterType,
)

from brake_sim_ros.stream.parameters import ParamSpec

_TYPES = {
    bool: ParameterType.PARAMETER_BOOL,
    int: ParameterType.PARAMETER_INTEGER,
    float: ParameterType.PARAMETER_DOUBLE,
    str: ParameterType.PARAMETER_STRING,
}


def descriptor(spec: ParamSpec, *, read_only: bool = False) -> ParameterDescriptor:
    """``rcl_interfaces/ParameterDescriptor`` for ``spec`` (type from its default's type)."""
    desc = ParameterDescriptor(
        name=spec.name,
        type=_TYPES[type(spec.default)],
        description=spec.description,
        additional_constraints=spec.constraints,
        read_only=read_only,
    )
    if spec.range is not None and isinstance(spec.default, float):
        desc.floating_point_range = [
            FloatingPointRange(
                from_value=float(spec.range[0]), to_value=float(spec.range[1]), step=0.0
            )
        ]
    elif spec.range is not None and type(spec.default) is int:
        desc.integer_range = [
            IntegerRange(from_value=int(spec.range[0]), to_value=int(spec.range[1]), step=1)
        ]
    return desc
