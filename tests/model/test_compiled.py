"""How the compiled functions are compiled (model/compiled.py): without numba's reference
counting but where a function allocates.

A counted array costs two atomic operations at every call that passes it (three quarters
of the stepping's time before it was turned off), and a function compiled inside another
inherits the caller's setting unless its own sets it: so every compiled function of the
model and the sensors sets it, and the ones that count are exactly those that allocate.
"""

from __future__ import annotations

import importlib
import pkgutil

from numba.core.registry import CPUDispatcher

import brake_sim_ros.model
import brake_sim_ros.sensing
from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING

# the functions that allocate arrays (a kernel's shell that allocates the loop's scratch,
# or a helper over whole arrays), each called once a block, not inside the stepping
ALLOCATING = {
    "brake_sim_ros.model.advance.fixed_step_advance",
    "brake_sim_ros.model.growth.working_copy",
    "brake_sim_ros.model.growth_law.severity_series",
    "brake_sim_ros.model.kernel.evaluate_rows",
    "brake_sim_ros.model.kernel.rhs",
    "brake_sim_ros.model.lining.stored_energy_rows",
    "brake_sim_ros.model.quasi_static.advance",
    "brake_sim_ros.model.service.stored_energy_rows",
    "brake_sim_ros.model.tyre.stored_energy_rows",
    "brake_sim_ros.sensing.lti.lti_advance",
    "brake_sim_ros.sensing.paths.analog_advance",
}


def _compiled_functions() -> dict[str, CPUDispatcher]:
    found = {}
    for package in (brake_sim_ros.model, brake_sim_ros.sensing):
        for info in pkgutil.iter_modules(package.__path__):
            module = importlib.import_module(f"{package.__name__}.{info.name}")
            for name, obj in vars(module).items():
                if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == module.__name__:
                    found[f"{module.__name__}.{name}"] = obj
    return found


def test_only_the_allocating_functions_count_references():
    found = _compiled_functions()
    assert len(found) > 100  # the walk finds the model's and the sensors' kernels
    counting = {name for name, f in found.items() if f.targetoptions.get("_nrt") is not False}
    assert counting == ALLOCATING
    for name, f in found.items():
        options = JIT_ALLOCATING if name in ALLOCATING else JIT
        assert f.targetoptions["_nrt"] is options["_nrt"], name
        assert f.targetoptions["error_model"] == options["error_model"], name
